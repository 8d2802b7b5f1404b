// The HTTP server's metrics (WebSocket hub, responses by status, connection
// handling), registered once by their owner (metrics/registry.hpp) and read
// from HttpServer::stats() at scrape time.
// Thread safety: as the registry's (one io_context thread).
#pragma once

#include "http/http_server.hpp"
#include "metrics/metrics.hpp"
#include "metrics/registry.hpp"

namespace gateway::http {

// The /metrics view of the server's stats.
metrics::HttpServerMetrics to_metrics(const HttpStats& s);

// `server` MUST outlive the registry's render() calls.
void register_metrics(metrics::Registry& r, const HttpServer& server);

}  // namespace gateway::http
