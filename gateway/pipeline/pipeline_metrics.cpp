#include "pipeline/pipeline_metrics.hpp"

#include <map>
#include <string>
#include <utility>

#include "metrics/metrics.hpp"

namespace gateway {

void register_metrics(metrics::Registry& r, const EventPipeline& pipeline) {
  metrics::register_events_by_kind(r, [&pipeline] {
    std::map<std::string, std::uint64_t> by_kind;
    for (int k = 0; k <= static_cast<int>(kLastEventKind); ++k) {
      const auto kind = static_cast<EventKind>(k);
      by_kind[std::string(to_string(kind))] = pipeline.published(kind);
    }
    return by_kind;
  });
}

void register_network_metrics(metrics::Registry& r, const StateCache& cache, std::uint32_t number,
                              std::function<const canopen::can::Channel*()> channel) {
  metrics::register_network(r, [&cache, number, channel = std::move(channel)] {
    metrics::NetworkMetrics n;
    n.network = number;
    if (const NetworkInfo* info = cache.network(number)) {
      n.interface = info->simulated ? std::string("demo") : info->interface;
      n.events = info->events;
    }
    if (const canopen::can::Channel* ch = channel()) {
      n.bus_state = std::string(canopen::can::to_string(ch->state()));
      const auto c = ch->stats();
      n.rx_frames = c.rx_frames;
      n.tx_frames = c.tx_frames;
      n.rx_dropped = c.rx_dropped;
      n.tx_dropped = c.tx_dropped;
      n.error_frames = c.error_frames;
      n.reopens = c.reopens;
    }
    return n;
  });
}

}  // namespace gateway
