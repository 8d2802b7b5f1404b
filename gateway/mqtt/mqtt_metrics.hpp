// The MQTT publisher's and its queue's metrics, registered once
// (metrics/registry.hpp) and read from the publisher at scrape time.
// Thread safety: as the registry's (one io_context thread).
#pragma once

#include <memory>

#include "metrics/metrics.hpp"
#include "mqtt/mqtt_requests.hpp"
#include "mqtt/publisher.hpp"
#include "metrics/registry.hpp"

namespace gateway::mqtt {

// The /metrics view of the publisher, its disk queue and its memory tier,
// and of the requests it hands on (`requests`: nullptr when not served).
metrics::MqttMetrics to_metrics(const MqttPublisher& publisher, const MqttRequests* requests = nullptr);

// The publisher and the requests' handler as their owner holds them, read
// at every render(): the owner may build them later (at start); while
// `publisher` is empty every series reads 0, and an empty `requests` counts
// no refused requests. Both slots MUST outlive the registry's render() calls.
void register_metrics(metrics::Registry& r, const std::unique_ptr<MqttPublisher>& publisher,
                      const std::unique_ptr<MqttRequests>& requests);

}  // namespace gateway::mqtt
