// The value history's metrics (metrics/registry.hpp), read at scrape time:
//   canopen_gateway_history_bytes                   gauge: bytes the history holds
//   canopen_gateway_history_max_bytes               gauge: history.max-bytes
//   canopen_gateway_history_objects                 gauge: objects recorded
//   canopen_gateway_history_refused_objects_total   counter: objects refused for want of room
// Thread safety: as the registry's (one io_context thread).
#pragma once

#include "history/value_history.hpp"
#include "metrics/registry.hpp"

namespace gateway::history {

// `h` MUST outlive the registry's render() calls.
void register_metrics(metrics::Registry& r, const ValueHistory& h);

}  // namespace gateway::history
