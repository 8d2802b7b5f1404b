// The request core's metrics (SDO transfers, NMT commands, refusals, the
// SDO latency histogram), registered once by the core's owner
// (metrics/registry.hpp) and read from its Counters at scrape time. Here,
// not in core/: the core counts (core::Counters), the composition root
// shows the counts in the Prometheus format, so the core links no metrics.
// Thread safety: as the registry's (one io_context thread).
#pragma once

#include "core/request_core.hpp"
#include "metrics/registry.hpp"

namespace gateway {

// Registers the families with metrics::register_requests(), the refusals
// (401/403, the two 429 reasons) and the histogram included. `counters`
// (RequestCore::counters()) MUST outlive the registry's render() calls.
void register_core_metrics(metrics::Registry& r, const core::Counters& counters);

}  // namespace gateway
