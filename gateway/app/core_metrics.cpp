#include "app/core_metrics.hpp"

#include <array>
#include <vector>

#include "metrics/metrics.hpp"

namespace gateway {

using core::Counters;

void register_core_metrics(metrics::Registry& r, const Counters& counters) {
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
  // LSS (contract "LSS master"): operations by how they ended, node-IDs given.
  static constexpr std::string_view lss = "canopen_gateway_lss_operations_total";
  static constexpr std::string_view lss_help =
      "LSS operations (one per request) by result: ok, timeout (no answer), refused (a slave's error code), "
      "none-found (fastscan: no unconfigured device), busy (409: another LSS operation ran), failed.";
  r.family(lss, lss_help, metrics::MetricType::Counter);
  auto lss_result = [&](const char* result, std::uint64_t Counters::*f) {
    r.counter_fn(lss, lss_help, {{"result", result}}, [c, f] { return metrics::Value(c->*f); });
  };
  lss_result("ok", &Counters::lss_ok);
  lss_result("timeout", &Counters::lss_timeouts);
  lss_result("refused", &Counters::lss_refused);
  lss_result("none-found", &Counters::lss_none_found);
  lss_result("busy", &Counters::lss_busy);
  lss_result("failed", &Counters::lss_failed);
  r.counter_fn("canopen_gateway_lss_node_ids_assigned_total", "Node-IDs given to devices by LSS.", {},
               [c] { return metrics::Value(c->lss_assigned); });
  // Remote maintenance (contract "Remote configuration and maintenance").
  static constexpr std::string_view maint = "canopen_gateway_maintenance_operations_total";
  static constexpr std::string_view maint_help =
      "Remote maintenance operations (one per request) by operation (dcf-read, dcf-apply, store, restore, "
      "program-download) and result: ok, failed (the device or the transfer), busy (409: another ran for the node).";
  r.family(maint, maint_help, metrics::MetricType::Counter);
  static constexpr std::array<const char*, Counters::kMaintenanceKinds> kinds = {"dcf-read", "dcf-apply", "store",
                                                                                 "restore", "program-download"};
  static constexpr std::array<const char*, Counters::kMaintenanceResults> results = {"ok", "failed", "busy"};
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    for (std::size_t res = 0; res < results.size(); ++res) {
      r.counter_fn(maint, maint_help, {{"operation", kinds[k]}, {"result", results[res]}},
                   [c, k, res] { return metrics::Value(c->maintenance[k][res]); });
    }
  }
}

}  // namespace gateway
