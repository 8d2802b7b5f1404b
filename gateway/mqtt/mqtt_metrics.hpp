// The MQTT publisher's and its queue's metrics, registered once
// (metrics/registry.hpp) and read from the publisher at scrape time.
// Thread safety: as the registry's (one io_context thread).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "metrics/metrics.hpp"
#include "mqtt/publisher.hpp"
#include "metrics/registry.hpp"

namespace gateway::mqtt {

// The /metrics view of the publisher, its disk queue and its memory tier,
// and how many requests it handed on were dropped for their reply address
// (MqttRequests::Counters::replies_refused; 0 when requests are not served).
metrics::MqttMetrics to_metrics(const MqttPublisher& publisher, std::uint64_t requests_refused = 0);

// The publisher as its owner holds it, read at every render(): the owner
// may build it later (at start); while `publisher` is empty every series
// reads 0. `requests_refused` (may be empty: 0) reads the request front
// end's count at render time. The slot and what the function reads MUST
// outlive the registry's render() calls. brokers: the configured URIs,
// normalized (Client::uris()), for canopen_gateway_mqtt_broker_connected.
void register_metrics(metrics::Registry& r, const std::unique_ptr<MqttPublisher>& publisher,
                      std::function<std::uint64_t()> requests_refused, const std::vector<std::string>& brokers = {});

}  // namespace gateway::mqtt
