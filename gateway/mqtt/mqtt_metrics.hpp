// The MQTT publisher's and its queue's metrics, registered once
// (metrics/registry.hpp) and read from the publisher at scrape time. This
// replaces the App's relay of the same counters (App::MqttCounters).
// Thread safety: as the registry's (one io_context thread).
#pragma once

#include "metrics.hpp"
#include "mqtt/mqtt_requests.hpp"
#include "mqtt/publisher.hpp"
#include "registry.hpp"

namespace gateway::mqtt {

// The /metrics view of the publisher, its disk queue and its memory tier,
// and of the requests it hands on (`requests`: nullptr when not served).
metrics::MqttMetrics to_metrics(const MqttPublisher& publisher, const MqttRequests* requests = nullptr);

// `publisher` and `requests` (may be nullptr) MUST outlive the registry's
// render() calls.
void register_metrics(metrics::Registry& r, const MqttPublisher& publisher, const MqttRequests* requests = nullptr);

}  // namespace gateway::mqtt
