#include "history/history_metrics.hpp"

namespace gateway::history {

void register_metrics(metrics::Registry& r, const ValueHistory& h) {
  r.gauge_fn("canopen_gateway_history_bytes", "Bytes the PDO value history holds (history.max-bytes caps it).", {},
             [&h] { return metrics::Value(h.bytes()); });
  r.gauge_fn("canopen_gateway_history_max_bytes", "The PDO value history's cap in bytes (history.max-bytes; 0 = off).",
             {}, [&h] { return metrics::Value(h.max_bytes()); });
  r.gauge_fn("canopen_gateway_history_objects", "Objects (node, index, sub) the PDO value history records.", {},
             [&h] { return metrics::Value(std::uint64_t{h.objects()}); });
  r.counter_fn("canopen_gateway_history_refused_objects_total",
               "Objects the PDO value history did not record because history.max-bytes was reached.", {},
               [&h] { return metrics::Value(h.refused_total()); });
}

}  // namespace gateway::history
