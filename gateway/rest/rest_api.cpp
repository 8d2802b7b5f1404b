#include "rest_api.hpp"

#include <boost/json/object.hpp>
#include <boost/json/array.hpp>
#include <boost/json/parse.hpp>
#include <boost/json/serialize.hpp>
#include <charconv>
#include <cstdio>

#include "canopen/eds/eds.hpp"
#include "canopen/json_value.hpp"
#include "canopen/pdo/config_reader.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/pdo/remote_config.hpp"
#include "canopen/sdo/abort.hpp"
#include "auth.hpp"
#include "core/format.hpp"
#include "core/request_core.hpp"
#include "canopen_gateway.pb.h"
#include "eds_report.hpp"
#include "google/protobuf/util/json_util.h"
#include "json_text.hpp"
#include "request_codec.hpp"
#include "rest_parse.hpp"
#include "route_checks.hpp"
#include "sparkplug/edge_client.hpp"
#include "trace/network_trace.hpp"
#include "trace_routes.hpp"

namespace gateway {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

bool accepts_protobuf(const Request& r) { return header_contains(r.header("accept"), kProtobuf); }
bool sends_protobuf(const Request& r) { return header_contains(r.header("content-type"), kProtobuf); }


Response json_response(const json::value& v, int status = 200) { return Response::json(json::serialize(v), status); }

using rest::parse_decimal;

std::string hex_text(std::span<const std::uint8_t> bytes) { return core::hex_bytes(bytes); }



std::string state_name(const NodeInfo& n) {
  if (n.lost) return "lost";
  if (!n.state) return "unknown";
  return std::string(canopen::to_string(*n.state));
}

json::object emcy_json(const CachedEmcy& e) {
  json::object j;
  j["seq"] = e.seq;
  j["timestamp"] = timestamp_text(e.timestamp);
  j["errorCode"] = e.emcy.error_code;
  j["errorRegister"] = e.emcy.error_register;
  j["manufacturerData"] = hex_text(e.emcy.manufacturer);
  j["description"] = e.emcy.description;
  return j;
}

json::object node_summary(const App& app, std::uint32_t net, const NodeInfo& n, WallTime now) {
  json::object o;
  o["node"] = n.id;
  o["name"] = n.name;
  o["configured"] = n.configured;
  o["state"] = state_name(n);
  if (n.last_heartbeat) {
    o["lastHeartbeatAgeMs"] =
        std::chrono::duration_cast<std::chrono::milliseconds>(now - *n.last_heartbeat).count();
  } else {
    o["lastHeartbeatAgeMs"] = nullptr;
  }
  if (n.last_seen) o["lastSeen"] = timestamp_text(*n.last_seen);
  o["bootCount"] = n.boot_count;
  if (n.identity) {
    json::object id;
    id["deviceType"] = n.identity->device_type;
    id["vendorId"] = n.identity->vendor_id;
    id["productCode"] = n.identity->product_code;
    id["revision"] = n.identity->revision;
    id["serial"] = n.identity->serial;
    o["identity"] = std::move(id);
  } else {
    o["identity"] = nullptr;
  }
  o["emcyCount"] = n.emcy_count;
  o["emcyErrorCount"] = n.emcy_error_count;
  o["lastEmcy"] = n.last_emcy ? json::value(emcy_json(*n.last_emcy)) : json::value(nullptr);
  o["eds"] = app.description(net, n.id) != nullptr;
  return o;
}

// The Sparkplug B edge node's session (GET /api/v1/gateway).
json::object sparkplug_json(const sparkplug::EdgeClient& sp) {
  const auto& edge = sp.edge();
  const auto& cfg = sp.config();
  const auto counters = sp.counters();
  json::object o;
  o["groupId"] = cfg.session.group_id;
  o["edgeNodeId"] = cfg.session.edge_node_id;
  o["state"] = sparkplug::state_name(edge.state());
  o["connected"] = sp.connected();
  o["bdSeq"] = edge.bd_seq() ? json::value(*edge.bd_seq()) : json::value(nullptr);
  const auto rebirth = edge.last_rebirth();
  o["lastRebirth"] = rebirth ? json::value(timestamp_text(WallTime(std::chrono::milliseconds(*rebirth))))
                             : json::value(nullptr);
  if (!cfg.session.primary_host_id.empty())
    o["primaryHost"] = json::object{{"id", cfg.session.primary_host_id}, {"online", edge.host_online()}};
  o["messagesPublished"] = counters.published;
  o["commandsReceived"] = counters.commands;
  return o;
}

// ---- routes ------------------------------------------------------------------

void get_gateway(App& app, const Request&, Responder respond) {
  json::object o;
  o["version"] = std::string(App::version());
  o["gatewayId"] = app.config().gateway_id;
  o["uptimeSeconds"] =
      std::chrono::duration_cast<std::chrono::seconds>(std::chrono::steady_clock::now() - app.started_at()).count();
  const auto& nets = app.config().networks;
  o["nodeId"] = nets.empty() ? 127 : nets.front().node_id;
  json::array list;
  for (std::size_t i = 0; i < nets.size(); ++i) {
    const auto number = static_cast<std::uint32_t>(i + 1);
    json::object n;
    n["network"] = number;
    n["interface"] = nets[i].simulated ? std::string("demo") : nets[i].interface;
    n["simulated"] = nets[i].simulated;
    n["nodeId"] = nets[i].node_id;
    if (auto s = app.bus_state(number)) n["bus"] = std::string(canopen::can::to_string(*s));
    // Where each configured node's settings come from (run-time configuration).
    json::array nodes;
    for (const auto& origin : app.node_origins(number)) {
      json::object entry{{"node", origin.node}, {"source", origin.source}};
      if (!origin.file.empty()) entry["file"] = origin.file;
      nodes.push_back(std::move(entry));
    }
    n["nodes"] = std::move(nodes);
    list.push_back(std::move(n));
  }
  o["networks"] = std::move(list);
  json::object c;
  c["sdoRequests"] = app.counters().sdo_requests;
  c["sdoAborts"] = app.counters().sdo_aborts;
  c["sdoTimeouts"] = app.counters().sdo_timeouts;
  c["nmtCommands"] = app.counters().nmt_commands;
  o["counters"] = std::move(c);
  if (const auto* sp = app.sparkplug()) o["sparkplug"] = sparkplug_json(*sp);
  respond(json_response(o));
}

void get_network(App& app, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  if (auto err = check_net(app, req, net)) return respond(std::move(*err));
  const auto& cfg = app.config().networks[net - 1];
  json::object o;
  o["network"] = net;
  o["interface"] = cfg.simulated ? std::string("demo") : cfg.interface;
  o["simulated"] = cfg.simulated;
  o["nodeId"] = cfg.node_id;
  if (auto s = app.own_state(net)) o["nodeState"] = std::string(canopen::to_string(*s));
  if (cfg.bitrate != 0) o["bitrate"] = cfg.bitrate;
  if (auto s = app.bus_state(net)) o["bus"] = std::string(canopen::can::to_string(*s));
  if (auto tap = app.frame_tap(net)) {  // issue 18: bus load and the capture ring (trace_routes.hpp)
    o["busLoad"] = bus_load_json(*tap);
    o["capture"] = capture_json(*tap);
  }
  const auto* info = app.cache().network(net);
  json::object counters;
  if (info != nullptr) {
    counters["events"] = info->events;
    counters["lastSeq"] = info->last_seq;
    counters["syncCount"] = info->sync_count;
    if (info->last_sync_counter) counters["lastSyncCounter"] = *info->last_sync_counter;
    counters["nodes"] = info->nodes.size();
    if (info->last_bus_event) {
      json::object b;
      b["state"] = std::string(canopen::can::to_string(info->last_bus_event->state));
      b["previous"] = std::string(canopen::can::to_string(info->last_bus_event->previous));
      b["cause"] = std::string(canopen::can::to_string(info->last_bus_event->cause));
      b["txErrorCounter"] = info->last_bus_event->tx_error_counter;
      b["rxErrorCounter"] = info->last_bus_event->rx_error_counter;
      b["dropped"] = info->last_bus_event->dropped;
      o["lastBusEvent"] = std::move(b);
    }
  }
  o["counters"] = std::move(counters);
  // The own node's parameters as they are now (an SDO write or an NMT reset
  // of the gateway's node may have changed them since the configuration).
  const auto* own = app.own_dictionary(net);
  auto param = [own](std::uint16_t index, std::uint64_t fallback) {
    return own != nullptr ? own->get_unsigned(index, 0).value_or(fallback) : fallback;
  };
  constexpr std::uint64_t kProduce = 0x40000000;  // bit 30 of 1005h / 1012h
  json::object sync;
  sync["producer"] = (param(0x1005, 0) & kProduce) != 0 && param(0x1006, 0) != 0;
  sync["periodUs"] = param(0x1006, 0);
  sync["windowUs"] = param(0x1007, 0);
  sync["counterOverflow"] = param(0x1019, 0);
  o["sync"] = std::move(sync);
  json::object time;
  time["producer"] = (param(0x1012, 0) & kProduce) != 0;
  time["periodMs"] = cfg.time.period.count();
  o["time"] = std::move(time);
  o["heartbeatMs"] = param(0x1017, 0);
  respond(json_response(o));
}

void get_nodes(App& app, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  if (auto err = check_net(app, req, net)) return respond(std::move(*err));
  json::array list;
  const auto now = WallTime::clock::now();
  if (const auto* info = app.cache().network(net)) {
    for (const auto& [id, n] : info->nodes) list.push_back(node_summary(app, net, n, now));
  }
  json::object o;
  o["network"] = net;
  o["nodes"] = std::move(list);
  respond(json_response(o));
}

void get_node(App& app, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(app, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  const auto* n = app.cache().node(net, node);
  if (n == nullptr) {
    return respond(problem_response(404, "node " + std::to_string(node) + " is neither configured nor heard on network " +
                                             std::to_string(net)));
  }
  auto o = node_summary(app, net, *n, WallTime::clock::now());
  o["network"] = net;
  json::array values;
  for (const auto& [key, v] : n->values) {
    json::object e;
    e["index"] = key.first;
    e["subIndex"] = key.second;
    e["name"] = v.name;
    e["type"] = std::string(canopen::cia309_name(v.value.type));
    e["value"] = canopen::value_to_json(v.value);
    e["timestamp"] = timestamp_text(v.timestamp);
    e["tpdo"] = v.tpdo;
    values.push_back(std::move(e));
  }
  o["values"] = std::move(values);
  json::array tpdos;
  for (const auto& [number, raw] : n->tpdo_raw) {
    json::object t;
    t["tpdo"] = number;
    t["raw"] = hex_text(raw);
    tpdos.push_back(std::move(t));
  }
  o["tpdos"] = std::move(tpdos);
  respond(json_response(o));
}

void get_od(App& app, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(app, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  json::object o;
  o["network"] = net;
  o["node"] = node;
  if (node == app.config().networks[net - 1].node_id) {
    // The gateway's own node has no EDS: its built-in dictionary is what
    // SDO requests to its node-ID read and write.
    const auto* own = app.own_dictionary(net);
    if (own == nullptr) return respond(problem_response(404, "network " + std::to_string(net) + " has no own node"));
    const auto name = own->get(0x1008, 0);
    o["vendorName"] = "";
    o["productName"] = name && std::holds_alternative<std::string>(name->data) ? std::get<std::string>(name->data)
                                                                                 : std::string("canopen-gateway");
    o["dcf"] = false;
    o["gateway"] = true;
    o["objects"] = gateway::edstool::objects_json(*own);
    return respond(json_response(o));
  }
  const auto* desc = app.description(net, node);
  if (desc == nullptr)
    return respond(problem_response(404, "node " + std::to_string(node) + " on network " + std::to_string(net) +
                                             " has no EDS/DCF configured"));
  for (auto& [key, value] : gateway::edstool::dictionary_json(*desc)) o[key] = std::move(value);
  o["gateway"] = false;
  respond(json_response(o));
}

void get_emcy(App& app, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(app, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  json::array list;
  std::uint64_t count = 0;
  std::uint64_t errors = 0;
  if (const auto* n = app.cache().node(net, node)) {
    count = n->emcy_count;
    errors = n->emcy_error_count;
    for (const auto& e : n->emcys) list.push_back(emcy_json(e));
  }
  json::object o;
  o["network"] = net;
  o["node"] = node;
  o["emcyCount"] = count;
  o["emcyErrorCount"] = errors;
  o["emcy"] = std::move(list);
  respond(json_response(o));
}

// ---- requests for the request core -------------------------------------------
// The path and body decode into one core::Request; the core answers it
// (ranges, roles, limits, audit) and the result is encoded here.

// The caller as the HTTP authorizer established it. Without an authorizer
// the server is open, and the request is too.
core::Caller rest_caller(const Request& req) {
  core::Caller c;
  c.transport = core::Transport::rest;
  c.authenticated = true;
  c.who = req.who;
  c.key = req.caller.empty() ? auth::address_caller(auth::peer_address(req.peer)) : req.caller;
  c.role = req.authorized ? static_cast<Role>(req.role) : Role::Admin;
  return c;
}

// The network of the path: its number (the core checks that it exists), or
// the 400 for one that is not a number.
std::optional<std::uint32_t> path_network(const Request& req, Responder& respond, bool protobuf = false) {
  std::string error;
  auto n = gateway::path_network(req, error);  // route_checks.hpp, not this overload
  if (!n) respond(problem_response(400, error, protobuf));
  return n;
}

core::Request core_request(const Request& req, std::uint32_t net, core::Command command) {
  core::Request r;
  r.caller = rest_caller(req);
  r.network = net;
  r.command = std::move(command);
  r.check_bus = true;  // REST answers 503 while the bus is off or down
  return r;
}

core::Undecodable undecodable(core::Operation op, std::uint8_t node, std::string detail, bool in_address) {
  return core::Undecodable{op, node, std::move(detail), in_address};
}

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
void execute(App& app, core::Request request, ReplyOptions opts, Responder respond) {
  app.requests().execute(std::move(request), [respond, opts](core::Result result) {
    respond(from_reply(encode_result(result, opts)));
  });
}

void sdo(App& app, bool write, const Request& req, Responder respond) {
  ReplyOptions opts;
  opts.protobuf = accepts_protobuf(req) || sends_protobuf(req);
  const auto net = path_network(req, respond, opts.protobuf);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  auto command = node ? sdo_command(write, req, *node, opts)
                      : core::Command{undecodable(write ? core::Operation::sdo_write : core::Operation::sdo_read, 0,
                                                  error, true)};
  execute(app, core_request(req, *net, std::move(command)), std::move(opts), std::move(respond));
}

void nmt(App& app, const Request& req, Responder respond) {
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
  execute(app, core_request(req, *net, std::move(command)), std::move(opts), std::move(respond));
}

// The result of a JSON-only command: `ok` writes the success.
template <typename Success, typename Ok>
core::RequestCore::Done json_result(Responder respond, Ok ok) {
  return [respond, ok](core::Result result) {
    if (const auto* s = std::get_if<Success>(&result)) return respond(json_response(ok(*s)));
    if (const auto* p = std::get_if<core::Problem>(&result)) return respond(from_reply(encode_problem(*p)));
    respond(problem_response(500, "unexpected result"));
  };
}

void rpdo(App& app, const Request& req, Responder respond) {
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
  app.requests().execute(core_request(req, *net, std::move(command)),
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

// ---- PDO configuration in effect (issue 11) ----------------------------------

const char* direction_text(canopen::pdo::Direction d) {
  return d == canopen::pdo::Direction::Transmit ? "tpdo" : "rpdo";
}

json::object pdo_json(const canopen::pdo::RemotePdo& p, const canopen::Result<canopen::pdo::PdoConfig>& cfg) {
  using canopen::pdo::Direction;
  const auto& c = p.parameters.comm;
  json::object o;
  o["direction"] = direction_text(p.key.direction);
  o["number"] = p.key.number;
  o["commIndex"] = canopen::pdo::comm_index(p.key.direction, p.key.number);
  o["mappingIndex"] = canopen::pdo::mapping_index(p.key.direction, p.key.number);
  o["cobId"] = c.cob_id.can_id();
  o["cobIdRaw"] = c.cob_id.raw;
  o["enabled"] = c.cob_id.valid();
  o["rtrAllowed"] = c.cob_id.rtr_allowed();
  o["extended"] = c.cob_id.extended();
  o["transmissionType"] = c.transmission_type;
  o["inhibitTime"] = c.inhibit_time;
  o["eventTimer"] = c.event_timer;
  o["syncStart"] = c.sync_start;
  const unsigned count = p.parameters.count;
  o["kind"] = count == 0xFE ? "sam-mpdo" : count == 0xFF ? "dam-mpdo" : "normal";
  json::array mapping;
  if (cfg) {
    for (const auto& e : cfg->entries) {
      json::object m;
      m["index"] = e.index;
      m["subIndex"] = e.sub;
      m["bits"] = e.bits;
      m["name"] = e.name;
      m["type"] = std::string(canopen::cia309_name(e.type));
      m["dummy"] = e.dummy;
      mapping.push_back(std::move(m));
    }
    o["length"] = cfg->byte_length();
  } else {
    // Not resolvable: the raw entries as the device has them, and why.
    for (unsigned i = 1; i <= count && i <= canopen::pdo::kMaxMappedEntries; ++i) {
      const auto it = p.parameters.entries.find(static_cast<std::uint8_t>(i));
      if (it == p.parameters.entries.end()) break;
      const auto e = canopen::pdo::MappingEntry::from_raw(it->second);
      json::object m;
      m["index"] = e.index;
      m["subIndex"] = e.sub;
      m["bits"] = e.bits;
      mapping.push_back(std::move(m));
    }
    o["error"] = cfg.error().detail;
  }
  o["mapping"] = std::move(mapping);
  o["source"] = std::string(canopen::pdo::to_string(p.source));
  if (!p.read_error.empty()) o["readError"] = p.read_error;
  return o;
}

json::array pdos_json(const canopen::pdo::RemotePdoTable& table, std::uint8_t node) {
  json::array list;
  for (const auto* p : table.pdos(node)) list.push_back(pdo_json(*p, table.resolve(node, p->key)));
  return list;
}

// The node's PDO table, or the 404 when it has none (no EDS/DCF).
const canopen::pdo::RemotePdoTable* node_pdo_table(const App& app, std::uint32_t net, std::uint8_t node,
                                                   std::optional<Response>& err) {
  const auto* table = app.pdo_config(net);
  if (table == nullptr || !table->has_node(node))
    err = problem_response(404, "node " + std::to_string(node) + " on network " + std::to_string(net) +
                                    " has no EDS/DCF, so its PDOs are not decoded");
  return err ? nullptr : table;
}

void get_pdo(App& app, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(app, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  std::optional<Response> err;
  const auto* table = node_pdo_table(app, net, node, err);
  if (table == nullptr) return respond(std::move(*err));
  json::object o;
  o["network"] = net;
  o["node"] = node;
  o["pdos"] = pdos_json(*table, node);
  respond(json_response(o));
}

void read_pdo(App& app, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::pdo_config_read, 0, error, true);
  if (node) command = core::PdoConfigRead{*node};
  App* a = &app;
  app.requests().execute(
      core_request(req, *net, std::move(command)),
      json_result<core::PdoConfigReport>(std::move(respond), [a](const core::PdoConfigReport& report) {
        json::array read;
        for (const auto& p : report.report.pdos) {
          json::object o;
          o["direction"] = direction_text(p.key.direction);
          o["number"] = p.key.number;
          o["ok"] = p.parameters.has_value();
          if (!p.parameters) {
            o["error"] = p.detail;
            if (&p.error.category() == &canopen::sdo_abort_category()) {
              o["abortCode"] = detail::abort_code_text(static_cast<std::uint32_t>(p.error.value()));
            }
          }
          read.push_back(std::move(o));
        }
        json::object out;
        out["network"] = report.network;
        out["node"] = report.node;
        out["summary"] = report.report.summary();
        out["read"] = std::move(read);
        out["pdos"] = pdos_json(*a->pdo_config(report.network), report.node);
        return out;
      }));
}

void sync(App& app, const Request& req, Responder respond) {
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
  app.requests().execute(core_request(req, *net, std::move(command)),
                         json_result<core::SyncSent>(std::move(respond), [](const core::SyncSent& s) {
                           json::object out;
                           out["network"] = s.network;
                           out["counter"] = s.counter ? json::value(*s.counter) : json::value(nullptr);
                           return out;
                         }));
}

// ---- LSS (contract "LSS master (CiA 305), REST (role admin)") --------------------

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
void lss_post(App& app, const Request& req, Responder respond, Parse parse, Ok ok) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  auto cmd = parse(req.body, error);
  core::Command command =
      cmd ? core::Command{std::move(*cmd)} : core::Command{undecodable(core::Operation::lss, 0, error, false)};
  app.requests().execute(core_request(req, *net, std::move(command)), json_result<Success>(std::move(respond), ok));
}

void lss_fastscan(App& app, const Request& req, Responder respond) {
  lss_post<core::LssFound>(app, req, std::move(respond), rest::parse_lss_fastscan, [](const core::LssFound& f) {
    json::object out;
    out["network"] = f.network;
    out["identity"] = identity_json(f.address);
    return out;
  });
}

// The one assignment: {"network", "identity", "nodeId", "bitrate"?, "stored"}.
void lss_configure(App& app, const Request& req, Responder respond) {
  lss_post<core::LssAssigned>(app, req, std::move(respond), rest::parse_lss_configure,
                              [](const core::LssAssigned& a) {
                                json::object out;
                                out["network"] = a.network;
                                if (!a.assignments.empty())
                                  for (auto& [k, v] : assignment_json(a.assignments.front())) out[k] = v;
                                return out;
                              });
}

void lss_assign_all(App& app, const Request& req, Responder respond) {
  lss_post<core::LssAssigned>(app, req, std::move(respond), rest::parse_lss_assign_all,
                              [](const core::LssAssigned& a) {
                                json::array list;
                                for (const auto& as : a.assignments) list.push_back(assignment_json(as));
                                json::object out;
                                out["network"] = a.network;
                                out["assignments"] = std::move(list);
                                return out;
                              });
}

void lss_devices(App& app, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  app.requests().execute(core_request(req, *net, core::LssDevices{}),
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

// ---- Run-time node configuration (contract "Remote configuration and maintenance") ----
// GET (viewer) / PUT / DELETE .../config and PUT .../eds (admin), through the
// request core (core/node_config.cpp; the App applies and keeps them).

json::object node_config_json(const core::NodeConfigView& v) {
  json::object out;
  out["network"] = v.network;
  out["node"] = v.node;
  out["source"] = v.source;
  if (!v.file.empty()) out["file"] = v.file;
  out["settings"] = v.settings;
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

void config_request(App& app, const Request& req, Responder respond, core::Command command) {
  const auto net = path_network(req, respond);
  if (!net) return;
  auto r = core_request(req, *net, std::move(command));
  r.check_bus = false;  // settings, not the bus
  app.requests().execute(std::move(r), json_result<core::NodeConfigView>(std::move(respond), node_config_json));
}

void get_node_config(App& app, const Request& req, Responder respond) {
  config_request(app, req, std::move(respond), config_command(req, core::Operation::config_read, [](std::uint8_t n) {
                   return core::Command{core::NodeConfigRead{n}};
                 }));
}

void put_node_config(App& app, const Request& req, Responder respond) {
  config_request(app, req, std::move(respond), config_command(req, core::Operation::config_write, [&](std::uint8_t n) {
                   boost::system::error_code ec;
                   auto body = json::parse(req.body, ec);
                   if (ec || !body.is_object())
                     return core::Command{undecodable(core::Operation::config_write, n,
                                                      "the body must be a JSON object: the keys of one nodes: entry "
                                                      "of the configuration file (name, eds, heartbeat-consumer-ms, "
                                                      "guarding, boot, sparkplug-metrics)",
                                                      false)};
                   return core::Command{core::NodeConfigWrite{n, std::move(body), false}};
                 }));
}

void delete_node_config(App& app, const Request& req, Responder respond) {
  config_request(app, req, std::move(respond), config_command(req, core::Operation::config_write, [](std::uint8_t n) {
                   return core::Command{core::NodeConfigWrite{n, {}, true}};
                 }));
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

void put_node_eds(App& app, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  auto command = config_command(req, core::Operation::config_write, [&](std::uint8_t n) {
    return core::Command{core::NodeEdsWrite{n, req.body, upload_name(req)}};
  });
  auto r = core_request(req, *net, std::move(command));
  r.check_bus = false;
  app.requests().execute(std::move(r),
                         json_result<core::NodeConfigView>(std::move(respond), [](const core::NodeConfigView& v) {
                           auto out = node_config_json(v);
                           json::array warnings;
                           for (const auto& w : v.warnings) warnings.emplace_back(w);
                           out["warnings"] = std::move(warnings);
                           return out;
                         }));
}

// ---- Remote maintenance (contract "Remote configuration and maintenance") ----
// DCF read-back and apply, store/restore, program download: decoded here,
// decided by the core (maintenance.cpp), run by the network's services.

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
void get_dcf(App& app, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::dcf_read, 0, error, true);
  if (node) command = core::DcfRead{*node};
  const bool as_json = header_contains(req.header("accept"), "application/json");
  app.requests().execute(core_request(req, *net, std::move(command)), [respond, as_json](core::Result result) {
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

void post_dcf(App& app, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::dcf_write, 0, error, true);
  if (node) command = dcf_apply_command(req, *node);
  app.requests().execute(core_request(req, *net, std::move(command)),
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
void store_route(App& app, bool restore, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::store, 0, error, true);
  if (node) command = core::NodeStore{*node, restore};
  app.requests().execute(core_request(req, *net, std::move(command)),
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
void put_program(App& app, const Request& req, Responder respond) {
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
  app.requests().execute(core_request(req, *net, std::move(command)),
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

// The routes above with what they need of the server: EDS, DCF and program
// bodies as application/octet-stream, the program route's own body limit,
// and no handler timeout (every step has its SDO timeout, and a download
// takes as long as the image needs on the bus).
void register_maintenance_routes(http::HttpServer& server, App& app) {
  App* a = &app;
  const std::string node = "/api/v1/networks/{net}/nodes/{node}";
  http::RouteOptions upload;
  upload.body_types = {"application/octet-stream"};
  upload.handler_timeout = std::chrono::milliseconds(0);
  http::RouteOptions long_running;
  long_running.handler_timeout = std::chrono::milliseconds(0);
  http::RouteOptions program = upload;
  program.max_body_bytes = app.config().http.max_program_bytes;
  auto add = [&](const char* method, const std::string& pattern, auto fn, const http::RouteOptions& options) {
    server.add_route(
        method, pattern, [a, fn](const Request& req, Responder respond) { fn(*a, req, std::move(respond)); }, options);
  };
  // An EDS/DCF file as application/octet-stream (issue 17 item 1).
  add("PUT", node + "/eds", put_node_eds, upload);
  add("GET", node + "/dcf", get_dcf, long_running);
  add("POST", node + "/dcf", post_dcf, upload);
  add("POST", node + "/store", [](App& a2, const Request& req, Responder r) { store_route(a2, false, req, std::move(r)); },
      long_running);
  add("POST", node + "/restore",
      [](App& a2, const Request& req, Responder r) { store_route(a2, true, req, std::move(r)); }, long_running);
  add("PUT", node + "/program/{n}", put_program, program);
}

}  // namespace

void register_rest_routes(http::HttpServer& server, App& app) {
  App* a = &app;
  auto route = [&](const char* method, std::string_view pattern, auto fn) {
    server.add_route(method, pattern, [a, fn](const Request& req, Responder respond) { fn(*a, req, std::move(respond)); });
  };
  // Routes whose answer exists as JSON only (no message in proto/).
  auto json_route = [&](const char* method, std::string_view pattern, auto fn) {
    route(method, pattern, [fn](App& a2, const Request& req, Responder respond) {
      if (accepts_only_protobuf(req))
        return respond(json_only_refusal());
      fn(a2, req, std::move(respond));
    });
  };
  const std::string node = "/api/v1/networks/{net}/nodes/{node}";
  json_route("GET", "/api/v1/gateway", get_gateway);
  json_route("GET", "/api/v1/networks/{net}", get_network);
  json_route("GET", "/api/v1/networks/{net}/nodes", get_nodes);
  json_route("GET", node, get_node);
  route("GET", node + "/sdo/{index}/{sub}",
        [](App& a2, const Request& req, Responder r) { sdo(a2, false, req, std::move(r)); });
  route("PUT", node + "/sdo/{index}/{sub}",
        [](App& a2, const Request& req, Responder r) { sdo(a2, true, req, std::move(r)); });
  route("POST", node + "/nmt", nmt);
  json_route("GET", node + "/od", get_od);
  json_route("GET", node + "/emcy", get_emcy);
  json_route("PUT", node + "/rpdo/{n}", rpdo);
  json_route("GET", node + "/pdo", get_pdo);
  json_route("POST", node + "/pdo/read", read_pdo);
  json_route("POST", "/api/v1/networks/{net}/sync", sync);
  json_route("POST", "/api/v1/networks/{net}/lss/fastscan", lss_fastscan);
  json_route("POST", "/api/v1/networks/{net}/lss/configure", lss_configure);
  json_route("POST", "/api/v1/networks/{net}/lss/assign-all", lss_assign_all);
  json_route("GET", "/api/v1/networks/{net}/lss/devices", lss_devices);
  // Run-time node configuration (issue 17 item 1).
  json_route("GET", node + "/config", get_node_config);
  json_route("PUT", node + "/config", put_node_config);
  json_route("DELETE", node + "/config", delete_node_config);
  register_maintenance_routes(server, app);  // PUT .../eds and remote maintenance (issue 17)
}

}  // namespace gateway
