// Everything the HTTP server answers besides its own WebSocket path and the
// dashboard files: the REST routes, /metrics and the OpenAPI document.
#include <chrono>
#include <string>
#include <utility>

#include "http_metrics.hpp"
#include "metrics.hpp"
#include "rest_api.hpp"
#include "history_routes.hpp"
#include "trace_routes.hpp"

namespace gateway {

void register_metrics_route(http::HttpServer& server, App& app) {
  // The server's families and the uptime come last, as /metrics has always
  // had them (after the App's own, app.hpp).
  http::register_metrics(app.metrics(), server);
  metrics::register_uptime(app.metrics(), [started = app.started_at()] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  });
  server.add_route("GET", "/metrics", [a = &app](const http::Request&, http::Responder respond) {
    http::Response r;
    r.status = 200;
    r.content_type = std::string(metrics::kContentType);
    r.body = a->metrics().render();
    respond(std::move(r));
  });
}

void register_openapi_route(http::HttpServer& server) {
  server.add_route("GET", "/api/v1/openapi.json", [](const http::Request&, http::Responder respond) {
    respond(http::Response::json(std::string(openapi_document())));
  });
}

void register_api_routes(http::HttpServer& server, App& app) {
  register_rest_routes(server, app);
  register_trace_routes(server, app);
  register_history_routes(server, app);
  register_metrics_route(server, app);
  register_openapi_route(server);
}

}  // namespace gateway
