#include "mqtt/mqtt_metrics.hpp"

namespace gateway::mqtt {

metrics::MqttMetrics to_metrics(const MqttPublisher& publisher, std::uint64_t requests_refused) {
  const auto c = publisher.counters();
  const auto& q = publisher.queue_counters();
  const auto& t = publisher.tier_counters();
  metrics::MqttMetrics m;
  m.connected = c.connected;
  m.published = c.published;
  m.acked = c.acked;
  m.dropped = c.dropped;
  m.queue_depth = c.queue_depth;
  m.queue_bytes = c.queue_bytes;
  m.reconnects = c.reconnects;
  m.requests_refused = requests_refused;
  m.stalls = c.stalls;
  m.broker = c.broker;
  m.storage_failing = c.storage_failing;
  m.memory_depth = t.memory_depth;
  m.spilled = t.spilled + t.to_disk;
  m.storage_bytes = q.storage_bytes;
  m.storage_syncs = q.syncs;
  m.storage_errors = q.write_errors;
  m.corrupt_records = q.corrupt_records;
  m.corrupt_bytes = q.corrupt_bytes + q.truncated_bytes;
  m.dropped_by_reason = {{"queue_full", q.dropped_qos0 + q.dropped_qos1 + q.dropped_span},
                         {"too_big", q.dropped_too_big},
                         {"storage_full", q.dropped_full + t.dropped_spill},
                         {"memory_full", t.dropped_memory},
                         {"backpressure", t.dropped_backpressure},
                         {"rejected", c.rejected}};
  return m;
}

void register_metrics(metrics::Registry& r, const std::unique_ptr<MqttPublisher>& publisher,
                      std::function<std::uint64_t()> requests_refused, const std::vector<std::string>& brokers) {
  metrics::register_mqtt(
      r,
      [&publisher, refused = std::move(requests_refused)] {
        return publisher ? to_metrics(*publisher, refused ? refused() : 0) : metrics::MqttMetrics{};
      },
      brokers);
}

}  // namespace gateway::mqtt
