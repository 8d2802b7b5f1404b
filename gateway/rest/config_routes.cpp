// Run-time node configuration (contract "Remote configuration and
// maintenance"): GET (viewer) / PUT / DELETE .../config and PUT .../eds
// (admin), through the request core (core/node_config.cpp; the App applies
// and keeps them).
#include "rest/routes.hpp"

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>
#include <boost/json/parse.hpp>

#include "config/config.hpp"
#include "edstool/eds_report.hpp"
#include "rest/route_checks.hpp"

namespace gateway::rest {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

json::object node_config_json(const core::NodeConfigView& v) {
  json::object out;
  out["network"] = v.network;
  out["node"] = v.node;
  out["source"] = v.source;
  if (!v.file.empty()) out["file"] = v.file;
  if (v.settings) out["settings"] = node_config_json(*v.settings);
  else out["settings"] = nullptr;
  return out;
}

// The node of the path as the command, or the 400 of a bad node-ID.
template <typename Make>
core::Command config_command(const Request& req, core::Operation op, Make make) {
  std::string error;
  const auto node = path_node(req, false, error);
  if (!node) return undecodable(op, 0, error, true);
  return make(*node);
}

void config_request(const Context& ctx, const Request& req, Responder respond, core::Command command) {
  const auto net = path_network(req, respond);
  if (!net) return;
  auto r = core_request(req, *net, std::move(command));
  r.check_bus = false;  // settings, not the bus
  ctx.core.execute(std::move(r), json_result<core::NodeConfigView>(std::move(respond), node_config_json));
}

// The body by the configuration file's rules; what does not decode
// travels in `invalid` (the core answers it after the caller and the node).
core::NodeConfigWrite decode_node_settings(const status::View& status, const Request& req, std::uint8_t node,
                                           const json::value& body) {
  core::NodeConfigWrite w;
  w.node = node;
  std::string error;
  const auto net = path_network(req, error);
  // An unknown network is the core's 404, before it looks at the settings.
  if (!net || *net == 0 || *net > status.networks().size()) return w;
  try {
    w.settings = node_config_from_request(body, node, status.networks()[*net - 1], status.config_file());
  } catch (const ConfigError& e) {
    w.invalid = e.what();
  }
  return w;
}

// The uploaded file's name: ?name=, else Content-Disposition's filename
// (for messages; the kept copy has the gateway's own name).
std::string upload_name(const Request& req) {
  if (auto n = req.query_param("name"); n && !n->empty()) return std::string(*n);
  const auto cd = req.header("content-disposition");
  if (!cd) return {};
  const auto at = cd->find("filename=");
  if (at == std::string_view::npos) return {};
  auto v = cd->substr(at + 9);
  v = v.substr(0, v.find(';'));
  if (v.size() >= 2 && v.front() == '"' && v.back() == '"') v = v.substr(1, v.size() - 2);
  // Only the last path element: a name for messages, never a path.
  if (const auto slash = v.find_last_of("/\\"); slash != std::string_view::npos) v = v.substr(slash + 1);
  return std::string(v);
}

}  // namespace

void get_node_config(const Context& ctx, const Request& req, Responder respond) {
  config_request(ctx, req, std::move(respond), config_command(req, core::Operation::config_read, [](std::uint8_t n) {
                   return core::Command{core::NodeConfigRead{n}};
                 }));
}

void put_node_config(const Context& ctx, const Request& req, Responder respond) {
  config_request(ctx, req, std::move(respond), config_command(req, core::Operation::config_write, [&](std::uint8_t n) {
                   boost::system::error_code ec;
                   auto body = json::parse(req.body, ec);
                   if (ec || !body.is_object())
                     return core::Command{undecodable(core::Operation::config_write, n,
                                                      "the body must be a JSON object: the keys of one nodes: entry "
                                                      "of the configuration file (name, eds, heartbeat-consumer-ms, "
                                                      "guarding, boot, sparkplug-metrics)",
                                                      false)};
                   return core::Command{decode_node_settings(ctx.status, req, n, body)};
                 }));
}

void delete_node_config(const Context& ctx, const Request& req, Responder respond) {
  config_request(ctx, req, std::move(respond), config_command(req, core::Operation::config_write, [](std::uint8_t n) {
                   core::NodeConfigWrite revert;
                   revert.node = n;
                   revert.revert = true;
                   return core::Command{std::move(revert)};
                 }));
}

void put_node_eds(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  auto command = config_command(req, core::Operation::config_write, [&](std::uint8_t n) {
    return core::Command{core::NodeEdsWrite{n, req.body, upload_name(req)}};
  });
  auto r = core_request(req, *net, std::move(command));
  r.check_bus = false;
  ctx.core.execute(std::move(r),
                         json_result<core::NodeConfigView>(std::move(respond), [](const core::NodeConfigView& v) {
                           auto out = node_config_json(v);
                           json::array warnings;
                           for (const auto& w : v.warnings) warnings.emplace_back(edstool::warning_line(v.eds_name, w));
                           out["warnings"] = std::move(warnings);
                           return out;
                         }));
}

}  // namespace gateway::rest
