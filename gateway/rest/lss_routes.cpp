// LSS (contract "LSS master (CiA 305), REST (role admin)"): fastscan,
// configure, assign-all and the devices the last scan found, through the core.
#include "rest/routes.hpp"

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>

#include "rest/rest_parse.hpp"
#include "rest/route_checks.hpp"

namespace gateway::rest {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

json::object identity_json(const core::LssAddress& a) {
  json::object o;
  o["vendorId"] = a.vendor_id;
  o["productCode"] = a.product_code;
  o["revisionNumber"] = a.revision;
  o["serialNumber"] = a.serial;
  return o;
}

json::object assignment_json(const core::LssAssignment& a) {
  json::object o;
  o["identity"] = identity_json(a.address);
  o["nodeId"] = a.node_id;
  if (a.bitrate) o["bitrate"] = *a.bitrate;
  o["stored"] = a.stored;
  return o;
}

// The body decoded once into the core's command (one that does not decode
// is answered 400 by the core after the role check, as for the other
// routes); `Success` encoded by `ok`.
template <typename Success, typename Parse, typename Ok>
void lss_post(const Context& ctx, const Request& req, Responder respond, Parse parse, Ok ok) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  auto cmd = parse(req.body, error);
  core::Command command =
      cmd ? core::Command{std::move(*cmd)} : core::Command{undecodable(core::Operation::lss, 0, error, false)};
  ctx.core.execute(core_request(req, *net, std::move(command)), json_result<Success>(std::move(respond), ok));
}

}  // namespace

void lss_fastscan(const Context& ctx, const Request& req, Responder respond) {
  lss_post<core::LssFound>(ctx, req, std::move(respond), rest::parse_lss_fastscan, [](const core::LssFound& f) {
    json::object out;
    out["network"] = f.network;
    out["identity"] = identity_json(f.address);
    return out;
  });
}

// The one assignment: {"network", "identity", "nodeId", "bitrate"?, "stored"}.
void lss_configure(const Context& ctx, const Request& req, Responder respond) {
  lss_post<core::LssAssigned>(ctx, req, std::move(respond), rest::parse_lss_configure,
                              [](const core::LssAssigned& a) {
                                json::object out;
                                out["network"] = a.network;
                                if (!a.assignments.empty())
                                  for (auto& [k, v] : assignment_json(a.assignments.front())) out[k] = v;
                                return out;
                              });
}

void lss_assign_all(const Context& ctx, const Request& req, Responder respond) {
  lss_post<core::LssAssigned>(ctx, req, std::move(respond), rest::parse_lss_assign_all,
                              [](const core::LssAssigned& a) {
                                json::array list;
                                for (const auto& as : a.assignments) list.push_back(assignment_json(as));
                                json::object out;
                                out["network"] = a.network;
                                out["assignments"] = std::move(list);
                                return out;
                              });
}

void lss_devices(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  ctx.core.execute(core_request(req, *net, core::LssDevices{}),
                         json_result<core::LssDeviceList>(std::move(respond), [](const core::LssDeviceList& l) {
                           json::array list;
                           for (const auto& d : l.devices) {
                             json::object o;
                             o["identity"] = identity_json(d.address);
                             o["nodeId"] = d.node_id ? json::value(*d.node_id) : json::value(nullptr);
                             list.push_back(std::move(o));
                           }
                           json::object out;
                           out["network"] = l.network;
                           out["devices"] = std::move(list);
                           return out;
                         }));
}

}  // namespace gateway::rest
