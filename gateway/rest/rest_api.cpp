// The route table of the REST API (rest_api.hpp); the handlers are in the
// files of their resource (routes.hpp).
#include "rest/rest_api.hpp"

#include "rest/route_checks.hpp"
#include "rest/routes.hpp"

namespace gateway {

using http::Request;
using http::Responder;

void register_rest_routes(http::HttpServer& server, core::RequestCore& core, const status::View& status) {
  const rest::Context ctx{core, status};
  auto route = [&](const char* method, std::string_view pattern, auto fn) {
    server.add_route(method, pattern, [ctx, fn](const Request& req, Responder respond) { fn(ctx, req, std::move(respond)); });
  };
  // Routes whose answer exists as JSON only (no message in proto/).
  auto json_route = [&](const char* method, std::string_view pattern, auto fn) {
    route(method, pattern, [fn](const rest::Context& a2, const Request& req, Responder respond) {
      if (accepts_only_protobuf(req))
        return respond(json_only_refusal());
      fn(a2, req, std::move(respond));
    });
  };
  const std::string node = "/api/v1/networks/{net}/nodes/{node}";
  json_route("GET", "/api/v1/gateway", rest::get_gateway);
  json_route("GET", "/api/v1/networks/{net}", rest::get_network);
  json_route("GET", "/api/v1/networks/{net}/nodes", rest::get_nodes);
  json_route("GET", node, rest::get_node);
  route("GET", node + "/sdo/{index}/{sub}",
        [](const rest::Context& a2, const Request& req, Responder r) { rest::sdo(a2, false, req, std::move(r)); });
  route("PUT", node + "/sdo/{index}/{sub}",
        [](const rest::Context& a2, const Request& req, Responder r) { rest::sdo(a2, true, req, std::move(r)); });
  route("POST", node + "/nmt", rest::nmt);
  json_route("GET", node + "/od", rest::get_od);
  json_route("GET", node + "/emcy", rest::get_emcy);
  json_route("PUT", node + "/rpdo/{n}", rest::rpdo);
  json_route("GET", node + "/pdo", rest::get_pdo);
  json_route("POST", node + "/pdo/read", rest::read_pdo);
  json_route("POST", "/api/v1/networks/{net}/sync", rest::sync);
  json_route("POST", "/api/v1/networks/{net}/lss/fastscan", rest::lss_fastscan);
  json_route("POST", "/api/v1/networks/{net}/lss/configure", rest::lss_configure);
  json_route("POST", "/api/v1/networks/{net}/lss/assign-all", rest::lss_assign_all);
  json_route("GET", "/api/v1/networks/{net}/lss/devices", rest::lss_devices);
  // Run-time node configuration (issue 17 item 1).
  json_route("GET", node + "/config", rest::get_node_config);
  json_route("PUT", node + "/config", rest::put_node_config);
  json_route("DELETE", node + "/config", rest::delete_node_config);
  rest::register_maintenance_routes(server, ctx);  // PUT .../eds and remote maintenance (issue 17)
}

}  // namespace gateway
