// The pipeline's and the state cache's metrics, registered once by their
// owner (metrics/registry.hpp); the values are read at scrape time.
// Thread safety: as the registry's (one io_context thread).
#pragma once

#include <cstdint>
#include <functional>

#include "canopen/can/channel.hpp"
#include "pipeline/pipeline.hpp"
#include "metrics/registry.hpp"
#include "pipeline/state_cache.hpp"

namespace gateway {

// canopen_gateway_events_published_total{kind} for every event kind.
// `pipeline` MUST outlive the registry's render() calls.
void register_metrics(metrics::Registry& r, const EventPipeline& pipeline);

// The per-network families of network `number` (already added to `cache`):
// its channel's frame counters and bus state, the cache's event count;
// interface label "demo" for a simulated network, as /metrics has it. Call
// metrics::register_network_families() first (once). `cache` and the
// channel `channel()` returns (nullptr: counters 0, no current bus state)
// MUST outlive the registry's render() calls.
void register_network_metrics(metrics::Registry& r, const StateCache& cache, std::uint32_t number,
                              std::function<const canopen::can::Channel*()> channel);

}  // namespace gateway
