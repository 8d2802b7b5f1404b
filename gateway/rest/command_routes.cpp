// SDO upload and download (JSON or protobuf), NMT, RPDO and SYNC: the path
// and body decoded into one core::Request, the result encoded.
#include "rest/routes.hpp"

#include <boost/json/object.hpp>
#include <boost/json/parse.hpp>
#include <boost/json/serialize.hpp>

#include "canopen/json_value.hpp"
#include "canopen_gateway.pb.h"
#include "google/protobuf/util/json_util.h"
#include "messages/request_codec.hpp"
#include "rest/rest_parse.hpp"
#include "rest/route_checks.hpp"

namespace gateway::rest {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

bool accepts_protobuf(const Request& r) { return header_contains(r.header("accept"), kProtobuf); }
bool sends_protobuf(const Request& r) { return header_contains(r.header("content-type"), kProtobuf); }

// The command of an SDO request: path (index, sub, ?type=) and, for a
// write, the body; the correlation id a write body carries goes to `opts`.
core::Command sdo_command(bool write, const Request& req, std::uint8_t node, ReplyOptions& opts) {
  const auto op = write ? core::Operation::sdo_write : core::Operation::sdo_read;
  const auto index = parse_index_text(req.param("index"));
  if (!index)
    return undecodable(op, node, "object index must be hex (1017, 0x1017 or 1017h), not '" +
                                     std::string(req.param("index")) + "'", true);
  const auto sub = parse_sub_index_text(req.param("sub"));
  if (!sub)
    return undecodable(op, node, "sub-index must be 0..255 (decimal or 0x hex), not '" +
                                     std::string(req.param("sub")) + "'", true);
  std::optional<canopen::DataType> type;
  if (auto t = req.query_param("type")) {
    type = canopen::parse_type_name(*t);
    if (!type) return undecodable(op, node, "unknown type '" + std::string(*t) + "'", true);
  }
  if (!write) return core::SdoRead{node, *index, *sub, type};

  canopen::Result<SdoWriteParams> params = canopen::Error{};
  if (sends_protobuf(req)) {
    canopen::gateway::v1::SdoWriteRequest m;
    if (!m.ParseFromString(req.body)) return undecodable(op, node, "the body is not a protobuf SdoWriteRequest", false);
    m.set_index(*index);
    m.set_sub_index(*sub);
    if (type) m.set_type(std::string(req.query_param("type").value_or("")));
    params = parse_sdo_write(m);
  } else {
    boost::system::error_code ec;
    auto body = json::parse(req.body, ec);
    if (ec || !body.is_object())
      return undecodable(op, node, "the body must be a JSON object {\"value\": ..., \"type\": ...}", false);
    auto& o = body.as_object();
    for (const char* k : {"index", "subIndex", "sub_index"}) o.erase(k);
    o["index"] = *index;
    o["subIndex"] = *sub;
    if (type) o["type"] = std::string(req.query_param("type").value_or(""));
    if (opts.protobuf) {
      // A JSON body with a protobuf reply reads as the protobuf message would.
      canopen::gateway::v1::SdoWriteRequest m;
      if (!google::protobuf::util::JsonStringToMessage(json::serialize(o), &m).ok())
        return undecodable(op, node, "the body is not an SDO write request {\"value\": ..., \"type\": ...}", false);
      params = parse_sdo_write(m);
    } else {
      params = parse_sdo_write(o);
    }
  }
  if (!params) return undecodable(op, node, params.error().detail, false);
  opts.correlation_id = params->correlation_id;
  return core::SdoWrite{node, *params->index, *params->sub, params->type, canopen::literal_from_json(params->value)};
}

// Executes a decoded request and answers with its result (SDO and NMT:
// JSON or protobuf as `opts` say).
void execute(const Context& ctx, core::Request request, ReplyOptions opts, Responder respond) {
  ctx.core.execute(std::move(request), [respond, opts](core::Result result) {
    respond(from_reply(encode_result(result, opts)));
  });
}

}  // namespace

void sdo(const Context& ctx, bool write, const Request& req, Responder respond) {
  ReplyOptions opts;
  opts.protobuf = accepts_protobuf(req) || sends_protobuf(req);
  const auto net = path_network(req, respond, opts.protobuf);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  auto command = node ? sdo_command(write, req, *node, opts)
                      : core::Command{undecodable(write ? core::Operation::sdo_write : core::Operation::sdo_read, 0,
                                                  error, true)};
  execute(ctx, core_request(req, *net, std::move(command)), std::move(opts), std::move(respond));
}

void nmt(const Context& ctx, const Request& req, Responder respond) {
  ReplyOptions opts;
  opts.protobuf = sends_protobuf(req);
  const auto net = path_network(req, respond, opts.protobuf);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, true, error);
  core::Command command = undecodable(core::Operation::nmt, 0, error, true);
  if (node) {
    auto params = parse_nmt(req.body, opts.protobuf);
    if (params) {
      opts.correlation_id = params->correlation_id;
      command = core::Nmt{*node, params->command};
    } else {
      command = undecodable(core::Operation::nmt, *node, params.error().detail, false);
    }
  }
  execute(ctx, core_request(req, *net, std::move(command)), std::move(opts), std::move(respond));
}

void rpdo(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  const auto number = parse_decimal(req.param("n"));
  core::Command command = undecodable(core::Operation::rpdo_write, 0, error, true);
  if (node && (!number || *number == 0 || *number > 512))
    command = undecodable(core::Operation::rpdo_write, *node,
                          "RPDO number must be 1..512, not '" + std::string(req.param("n")) + "'", true);
  else if (node)
    command = rest::decode_rpdo_body(*node, static_cast<std::uint16_t>(*number), req.body);
  ctx.core.execute(core_request(req, *net, std::move(command)),
                         json_result<core::RpdoSent>(std::move(respond), [](const core::RpdoSent& s) {
                           json::object out;
                           out["network"] = s.network;
                           out["node"] = s.node;
                           out["rpdo"] = s.number;
                           out["cobId"] = s.cob_id;
                           out["transmissionType"] = s.transmission_type;
                           out["raw"] = hex_text(s.raw);
                           return out;
                         }));
}
void sync(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  core::Command command = core::Sync{};
  if (req.body.find_first_not_of(" \t\r\n") != std::string::npos) {
    boost::system::error_code ec;
    auto body = json::parse(req.body, ec);
    if (ec || !body.is_object()) {
      command = undecodable(core::Operation::sync, 0, "the body must be a JSON object {\"counter\": n}", false);
    } else if (const auto* c = body.as_object().if_contains("counter"); c != nullptr && !c->is_null()) {
      if (!c->is_int64() || c->as_int64() < 1 || c->as_int64() > 240)
        command = undecodable(core::Operation::sync, 0, "\"counter\" must be 1..240", false);
      else
        command = core::Sync{static_cast<std::uint8_t>(c->as_int64())};
    }
  }
  ctx.core.execute(core_request(req, *net, std::move(command)),
                         json_result<core::SyncSent>(std::move(respond), [](const core::SyncSent& s) {
                           json::object out;
                           out["network"] = s.network;
                           out["counter"] = s.counter ? json::value(*s.counter) : json::value(nullptr);
                           return out;
                         }));
}

}  // namespace gateway::rest
