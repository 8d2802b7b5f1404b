#include "core/core_metrics.hpp"

#include <vector>

#include "metrics.hpp"

namespace gateway::core {

void register_metrics(metrics::Registry& r, const Counters& counters) {
  const Counters* c = &counters;
  metrics::register_requests(
      r,
      [c] {
        return metrics::RequestMetrics{c->sdo_requests,  c->sdo_aborts,        c->sdo_timeouts,
                                       c->nmt_commands,  c->auth_failures,     c->sdo_share_refused,
                                       c->requests_rate_limited};
      },
      std::vector<double>(Counters::kSdoLatencyBounds.begin(), Counters::kSdoLatencyBounds.end()), [c] {
        return metrics::HistogramValues{
            std::vector<std::uint64_t>(c->sdo_latency_counts.begin(), c->sdo_latency_counts.end()), c->sdo_latency_sum};
      });
}

}  // namespace gateway::core
