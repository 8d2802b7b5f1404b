// Remote maintenance (contract "Remote configuration and maintenance"):
// DCF read-back and apply, store/restore, program download: decoded here,
// decided by the core (maintenance.cpp), run by the network's services.
#include "rest/routes.hpp"

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>
#include <boost/json/parse.hpp>
#include <chrono>

#include "canopen/sdo/abort.hpp"
#include "core/format.hpp"
#include "rest/rest_parse.hpp"
#include "rest/route_checks.hpp"

namespace gateway::rest {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

// The object's result as the API writes it: index, subIndex, ok, and for a
// failure abortCode ("0x06010001", SDO aborts only) and error (its text).
json::object object_outcome_json(const core::ObjectOutcome& o) {
  json::object j;
  j["index"] = o.index;
  j["subIndex"] = o.sub;
  j["ok"] = !o.error;
  if (o.error) {
    if (&o.error.category() == &canopen::sdo_abort_category())
      j["abortCode"] = core::abort_code_text(static_cast<std::uint32_t>(o.error.value()));
    j["error"] = o.detail.empty() ? o.error.message() : o.error.message() + ": " + o.detail;
  }
  return j;
}

// "0x2000:1=0x06010001, 0x2001:0=0x06020000": the aborted objects of a DCF
// read-back for the X-Canopen-Failed-Objects header (abort code "local" for
// a failure that is not an SDO abort).
std::string failed_objects_header(const std::vector<core::ObjectOutcome>& failed) {
  std::string out;
  for (const auto& f : failed) {
    if (!out.empty()) out += ", ";
    out += "0x" + core::hex_number(f.index, 4) + ":" + std::to_string(f.sub) + "=";
    out += &f.error.category() == &canopen::sdo_abort_category()
               ? core::abort_code_text(static_cast<std::uint32_t>(f.error.value()))
               : std::string("local");
  }
  return out;
}

// ?name=true|false|1|0 (absent: false); nullopt and `error` for another value.
std::optional<bool> query_flag(const Request& req, std::string_view name, std::string& error) {
  const auto v = req.query_param(name);
  if (!v || *v == "false" || *v == "0") return false;
  if (*v == "true" || *v == "1" || v->empty()) return true;
  error = "?" + std::string(name) + "= must be true or false, not '" + std::string(*v) + "'";
  return std::nullopt;
}

// GET .../dcf: the DCF as text/plain (a file named node<N>.dcf) with the
// counts in headers; `Accept: application/json` gives it inside JSON with
// the failed objects in full.
void get_dcf(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::dcf_read, 0, error, true);
  if (node) command = core::DcfRead{*node};
  const bool as_json = header_contains(req.header("accept"), "application/json");
  ctx.core.execute(core_request(req, *net, std::move(command)), [respond, as_json](core::Result result) {
    if (const auto* p = std::get_if<core::Problem>(&result)) return respond(from_reply(encode_problem(*p)));
    const auto* d = std::get_if<core::DcfDocument>(&result);
    if (d == nullptr) return respond(problem_response(500, "unexpected result"));
    if (as_json) {
      json::object out;
      out["network"] = d->network;
      out["node"] = d->node;
      out["objects"] = d->objects;
      json::array failed;
      for (const auto& f : d->failed) failed.push_back(object_outcome_json(f));
      out["failed"] = std::move(failed);
      out["dcf"] = d->text;
      return respond(json_response(out));
    }
    Response r;
    r.content_type = "text/plain; charset=utf-8";
    r.body = d->text;
    r.headers.emplace_back("Content-Disposition", "attachment; filename=\"node" + std::to_string(d->node) + ".dcf\"");
    r.headers.emplace_back("X-Canopen-Objects-Read", std::to_string(d->objects));
    r.headers.emplace_back("X-Canopen-Objects-Failed", std::to_string(d->failed.size()));
    if (!d->failed.empty()) r.headers.emplace_back("X-Canopen-Failed-Objects", failed_objects_header(d->failed));
    respond(std::move(r));
  });
}

// POST .../dcf: the DCF as the body (application/octet-stream), ?store= and
// ?reset=; or application/json {"dcf": "<text>", "store": bool, "reset": bool}.
core::Command dcf_apply_command(const Request& req, std::uint8_t node) {
  const auto op = core::Operation::dcf_write;
  std::string error;
  const auto store = query_flag(req, "store", error);
  const auto reset = query_flag(req, "reset", error);
  if (!store || !reset) return undecodable(op, node, error, false);
  core::DcfApply cmd{node, req.body, *store, *reset};
  const auto type = req.header("content-type");
  if (type && type->find("application/json") != std::string_view::npos) {
    boost::system::error_code ec;
    auto body = json::parse(req.body, ec);
    const json::object* o = !ec && body.is_object() ? &body.as_object() : nullptr;
    const json::value* text = o != nullptr ? o->if_contains("dcf") : nullptr;
    if (text == nullptr || !text->is_string())
      return undecodable(op, node, "the JSON body must be {\"dcf\": \"<DCF text>\", \"store\": bool, \"reset\": bool}",
                         false);
    cmd.text = std::string(text->as_string());
    for (auto [key, flag] : {std::pair{"store", &cmd.store}, std::pair{"reset", &cmd.reset}}) {
      if (const auto* v = o->if_contains(key)) {
        if (!v->is_bool()) return undecodable(op, node, "\"" + std::string(key) + "\" must be true or false", false);
        *flag = *flag || v->as_bool();
      }
    }
  }
  if (cmd.text.find_first_not_of(" \t\r\n") == std::string::npos)
    return undecodable(op, node, "the body must be a DCF (CiA 306)", false);
  return cmd;
}

void post_dcf(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::dcf_write, 0, error, true);
  if (node) command = dcf_apply_command(req, *node);
  ctx.core.execute(core_request(req, *net, std::move(command)),
                         json_result<core::DcfApplied>(std::move(respond), [](const core::DcfApplied& a) {
                           json::array objects;
                           std::size_t failed = 0;
                           for (const auto& o : a.objects) {
                             failed += o.error ? 1 : 0;
                             objects.push_back(object_outcome_json(o));
                           }
                           json::object out;
                           out["network"] = a.network;
                           out["node"] = a.node;
                           out["written"] = a.objects.size() - failed;
                           out["failed"] = failed;
                           out["objects"] = std::move(objects);
                           out["stored"] = a.stored;
                           if (a.store_error) out["storeError"] = object_outcome_json(*a.store_error);
                           out["reset"] = a.reset;
                           return out;
                         }));
}

// POST .../store and .../restore (no body).
void store_route(const Context& ctx, bool restore, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::store, 0, error, true);
  if (node) command = core::NodeStore{*node, restore};
  ctx.core.execute(core_request(req, *net, std::move(command)),
                         json_result<core::NodeStored>(std::move(respond), [](const core::NodeStored& s) {
                           json::object out;
                           out["network"] = s.network;
                           out["node"] = s.node;
                           out["operation"] = s.restore ? "restore" : "store";
                           out["reset"] = s.restore;  // restore: NMT reset node sent after "load"
                           return out;
                         }));
}

// PUT .../program/{n}: the image as the body (application/octet-stream);
// answers once the program runs (or the step that failed).
void put_program(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  const auto number = parse_decimal(req.param("n"));
  core::Command command = undecodable(core::Operation::program, 0, error, true);
  if (node && !header_contains(req.header("content-type"), "application/octet-stream")) {
    command = undecodable(core::Operation::program, *node,
                          "the program image must be the body as application/octet-stream", false);
  } else if (node && (!number || *number == 0 || *number > 254)) {
    command = undecodable(core::Operation::program, *node,
                          "program number must be 1..254 (1F50h sub-index), not '" + std::string(req.param("n")) + "'",
                          true);
  } else if (node) {
    command = core::ProgramDownload{*node, static_cast<std::uint8_t>(*number),
                                    canopen::Bytes(req.body.begin(), req.body.end())};
  }
  ctx.core.execute(core_request(req, *net, std::move(command)),
                         json_result<core::ProgramDownloaded>(std::move(respond), [](const core::ProgramDownloaded& d) {
                           json::object out;
                           out["network"] = d.network;
                           out["node"] = d.node;
                           out["program"] = d.program;
                           out["bytes"] = d.bytes;
                           out["started"] = true;
                           out["identification"] =
                               d.identification ? json::value(*d.identification) : json::value(nullptr);
                           if (d.identification) out["identificationHex"] = "0x" + core::hex_number(*d.identification, 8);
                           return out;
                         }));
}

}  // namespace

// The routes above with what they need of the server: EDS, DCF and program
// bodies as application/octet-stream, the program route's own body limit,
// and no handler timeout (every step has its SDO timeout, and a download
// takes as long as the image needs on the bus).
void register_maintenance_routes(http::HttpServer& server, const Context& ctx) {
  const std::string node = "/api/v1/networks/{net}/nodes/{node}";
  http::RouteOptions upload;
  upload.body_types = {"application/octet-stream"};
  upload.handler_timeout = std::chrono::milliseconds(0);
  http::RouteOptions long_running;
  long_running.handler_timeout = std::chrono::milliseconds(0);
  http::RouteOptions program = upload;
  program.max_body_bytes = ctx.status.max_program_bytes();
  auto add = [&](const char* method, const std::string& pattern, auto fn, const http::RouteOptions& options) {
    server.add_route(
        method, pattern, [ctx, fn](const Request& req, Responder respond) { fn(ctx, req, std::move(respond)); }, options);
  };
  // An EDS/DCF file as application/octet-stream (issue 17 item 1).
  add("PUT", node + "/eds", put_node_eds, upload);
  add("GET", node + "/dcf", get_dcf, long_running);
  add("POST", node + "/dcf", post_dcf, upload);
  add("POST", node + "/store", [](const Context& a2, const Request& req, Responder r) { store_route(a2, false, req, std::move(r)); },
      long_running);
  add("POST", node + "/restore",
      [](const Context& a2, const Request& req, Responder r) { store_route(a2, true, req, std::move(r)); }, long_running);
  add("PUT", node + "/program/{n}", put_program, program);
}

}  // namespace gateway::rest
