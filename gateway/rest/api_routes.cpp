// Everything the HTTP server answers besides its own WebSocket path and the
// dashboard files: the REST routes, /metrics and the OpenAPI document.
#include <string>
#include <utility>

#include "metrics/metrics.hpp"
#include "rest/rest_api.hpp"
#include "rest/history_routes.hpp"
#include "rest/trace_routes.hpp"

namespace gateway {

void register_metrics_route(http::HttpServer& server, const status::View& status) {
  server.add_route("GET", "/metrics", [s = &status](const http::Request&, http::Responder respond) {
    http::Response r;
    r.status = 200;
    r.content_type = std::string(metrics::kContentType);
    r.body = s->metrics_text();
    respond(std::move(r));
  });
}

void register_openapi_route(http::HttpServer& server) {
  server.add_route("GET", "/api/v1/openapi.json", [](const http::Request&, http::Responder respond) {
    respond(http::Response::json(std::string(openapi_document())));
  });
}

void register_api_routes(http::HttpServer& server, core::RequestCore& core, const status::View& status,
                         boost::asio::io_context& io) {
  register_rest_routes(server, core, status);
  register_trace_routes(server, status, io);
  register_history_routes(server, status);
  register_metrics_route(server, status);
  register_openapi_route(server);
}

}  // namespace gateway
