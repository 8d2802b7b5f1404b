// The listings (GET /api/v1/gateway, /networks/{net}, .../nodes, .../nodes/{node},
// .../od, .../emcy), answered from the status view; JSON only.
#include "rest/routes.hpp"

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>
#include <chrono>

#include "canopen/eds/eds.hpp"
#include "canopen/json_value.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "edstool/eds_report.hpp"
#include "rest/route_checks.hpp"
#include "trace/network_trace.hpp"
#include "rest/trace_routes.hpp"

namespace gateway::rest {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

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

json::object node_summary(const Context& ctx, std::uint32_t net, const NodeInfo& n, WallTime now) {
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
  o["eds"] = ctx.status.description(net, n.id) != nullptr;
  return o;
}

// "5", "3.1.1", or null when not connected.
json::value version_name(int v) {
  if (v == 5) return json::value("5");
  if (v == 4) return json::value("3.1.1");
  return json::value(nullptr);
}

// The native MQTT connection (GET /api/v1/gateway).
json::object mqtt_json(const status::MqttStatus& m) {
  json::object o;
  o["connected"] = m.connected;
  o["broker"] = m.broker.empty() ? json::value(nullptr) : json::value(m.broker);
  o["mqttVersion"] = version_name(m.mqtt_version);
  json::array brokers;
  for (const auto& b : m.brokers) brokers.emplace_back(b);
  o["brokers"] = std::move(brokers);
  o["reconnects"] = m.reconnects;
  return o;
}

// The Sparkplug B edge node's session (GET /api/v1/gateway).
json::object sparkplug_json(const status::SparkplugStatus& sp) {
  json::object o;
  o["groupId"] = sp.group_id;
  o["edgeNodeId"] = sp.edge_node_id;
  o["state"] = sp.state;
  o["connected"] = sp.connected;
  o["broker"] = sp.broker.empty() ? json::value(nullptr) : json::value(sp.broker);
  o["mqttVersion"] = version_name(sp.mqtt_version);
  o["bdSeq"] = sp.bd_seq ? json::value(*sp.bd_seq) : json::value(nullptr);
  const auto rebirth = sp.last_rebirth_ms;
  o["lastRebirth"] = rebirth ? json::value(timestamp_text(WallTime(std::chrono::milliseconds(*rebirth))))
                             : json::value(nullptr);
  if (!sp.primary_host_id.empty())
    o["primaryHost"] = json::object{{"id", sp.primary_host_id}, {"online", sp.primary_host_online}};
  o["messagesPublished"] = sp.messages_published;
  o["commandsReceived"] = sp.commands_received;
  return o;
}

}  // namespace

void get_gateway(const Context& ctx, const Request&, Responder respond) {
  json::object o;
  o["version"] = std::string(ctx.status.version());
  o["gatewayId"] = ctx.status.gateway_id();
  o["uptimeSeconds"] =
      std::chrono::duration_cast<std::chrono::seconds>(std::chrono::steady_clock::now() - ctx.status.started_at()).count();
  const auto& nets = ctx.status.networks();
  o["nodeId"] = nets.empty() ? 127 : nets.front().node_id;
  json::array list;
  for (std::size_t i = 0; i < nets.size(); ++i) {
    const auto number = static_cast<std::uint32_t>(i + 1);
    json::object n;
    n["network"] = number;
    n["interface"] = nets[i].simulated ? std::string("demo") : nets[i].interface;
    n["simulated"] = nets[i].simulated;
    n["nodeId"] = nets[i].node_id;
    if (auto s = ctx.status.bus_state(number)) n["bus"] = std::string(canopen::can::to_string(*s));
    // Where each configured node's settings come from (run-time configuration).
    json::array nodes;
    for (const auto& origin : ctx.status.node_origins(number)) {
      json::object entry{{"node", origin.node}, {"source", origin.source}};
      if (!origin.file.empty()) entry["file"] = origin.file;
      nodes.push_back(std::move(entry));
    }
    n["nodes"] = std::move(nodes);
    list.push_back(std::move(n));
  }
  o["networks"] = std::move(list);
  json::object c;
  c["sdoRequests"] = ctx.status.counters().sdo_requests;
  c["sdoAborts"] = ctx.status.counters().sdo_aborts;
  c["sdoTimeouts"] = ctx.status.counters().sdo_timeouts;
  c["nmtCommands"] = ctx.status.counters().nmt_commands;
  o["counters"] = std::move(c);
  if (const auto m = ctx.status.mqtt()) o["mqtt"] = mqtt_json(*m);
  if (const auto sp = ctx.status.sparkplug()) o["sparkplug"] = sparkplug_json(*sp);
  respond(json_response(o));
}

void get_network(const Context& ctx, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  if (auto err = check_net(ctx.status, req, net)) return respond(std::move(*err));
  const auto& cfg = ctx.status.networks()[net - 1];
  json::object o;
  o["network"] = net;
  o["interface"] = cfg.simulated ? std::string("demo") : cfg.interface;
  o["simulated"] = cfg.simulated;
  o["nodeId"] = cfg.node_id;
  if (auto s = ctx.status.own_state(net)) o["nodeState"] = std::string(canopen::to_string(*s));
  if (cfg.bitrate != 0) o["bitrate"] = cfg.bitrate;
  if (auto s = ctx.status.bus_state(net)) o["bus"] = std::string(canopen::can::to_string(*s));
  if (auto tap = ctx.status.frame_tap(net)) {  // issue 18: bus load and the capture ring (trace_routes.hpp)
    o["busLoad"] = bus_load_json(*tap);
    o["capture"] = capture_json(*tap);
  }
  const auto* info = ctx.status.cache().network(net);
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
  const auto* own = ctx.status.own_dictionary(net);
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

void get_nodes(const Context& ctx, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  if (auto err = check_net(ctx.status, req, net)) return respond(std::move(*err));
  json::array list;
  const auto now = WallTime::clock::now();
  if (const auto* info = ctx.status.cache().network(net)) {
    for (const auto& [id, n] : info->nodes) list.push_back(node_summary(ctx, net, n, now));
  }
  json::object o;
  o["network"] = net;
  o["nodes"] = std::move(list);
  respond(json_response(o));
}

void get_node(const Context& ctx, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(ctx.status, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  const auto* n = ctx.status.cache().node(net, node);
  if (n == nullptr) {
    return respond(problem_response(404, "node " + std::to_string(node) + " is neither configured nor heard on network " +
                                             std::to_string(net)));
  }
  auto o = node_summary(ctx, net, *n, WallTime::clock::now());
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

void get_od(const Context& ctx, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(ctx.status, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  json::object o;
  o["network"] = net;
  o["node"] = node;
  if (node == ctx.status.networks()[net - 1].node_id) {
    // The gateway's own node has no EDS: its built-in dictionary is what
    // SDO requests to its node-ID read and write.
    const auto* own = ctx.status.own_dictionary(net);
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
  const auto* desc = ctx.status.description(net, node);
  if (desc == nullptr)
    return respond(problem_response(404, "node " + std::to_string(node) + " on network " + std::to_string(net) +
                                             " has no EDS/DCF configured"));
  for (auto& [key, value] : gateway::edstool::dictionary_json(*desc)) o[key] = std::move(value);
  o["gateway"] = false;
  respond(json_response(o));
}

void get_emcy(const Context& ctx, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(ctx.status, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  json::array list;
  std::uint64_t count = 0;
  std::uint64_t errors = 0;
  if (const auto* n = ctx.status.cache().node(net, node)) {
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

}  // namespace gateway::rest
