// networks: and their nodes: (NetworkConfig, NodeConfig), and one nodes:
// entry on its own for the run-time configuration (parse_node_config(),
// node_config_json()).
#include <cstdio>
#include <filesystem>
#include <set>

#include <boost/json/serialize.hpp>
#include <yaml-cpp/yaml.h>

#include "config/config_yaml.hpp"
#include "messages/request_codec.hpp"  // parse_index_text

namespace gateway {

namespace config_yaml {

namespace fs = std::filesystem;

// One `nodes:` entry: the file parser's and parse_node_config()'s (the
// run-time configuration over REST), so both give the same reasons.
void parse_node(const At& a, NodeConfig& n, const std::string& dir) {
  a.expect_map({"id", "name", "eds", "dcf", "heartbeat-consumer-ms", "guarding", "boot", "sparkplug-metrics"});
  auto id = a.get("id");
  if (!id) a.fail("missing key 'id' (the node-ID, 1..127)");
  n.id = static_cast<std::uint8_t>(id->integer(1, 127));
  if (auto v = a.get("name")) n.name = v->str();
  auto eds = a.get("eds");
  auto dcf = a.get("dcf");
  if (eds && dcf) dcf->fail("give either eds or dcf, not both");
  if (eds || dcf) {
    const At& f = eds ? *eds : *dcf;
    n.eds = resolve(dir, f.str());
    std::error_code ec;
    if (!fs::is_regular_file(n.eds, ec)) f.fail("file '" + n.eds + "' not found");
  }
  if (auto v = a.get("heartbeat-consumer-ms")) {
    const auto s = v->str();
    if (s == "auto") {
      n.heartbeat_consumer.reset();
    } else if (!s.empty() && s[0] >= '0' && s[0] <= '9') {
      n.heartbeat_consumer = ms(*v);
    } else {
      v->fail("'" + s + "' is not auto, 0 (not watched) or a consumer time in ms (1..65535)");
    }
  }
  if (auto g = a.get("guarding")) {
    g->expect_map({"guard-time-ms", "life-time-factor"});
    if (auto v = g->get("guard-time-ms")) n.guarding.guard_time = ms(*v);
    if (auto v = g->get("life-time-factor")) n.guarding.life_time_factor = static_cast<std::uint8_t>(v->integer(0, 255));
    if ((n.guarding.guard_time.count() == 0) != (n.guarding.life_time_factor == 0))
      g->fail("guard-time-ms and life-time-factor must both be set (or both 0)");
  }
  if (auto b = a.get("boot")) {
    b->expect_map({"check-identity", "configure", "start", "read-pdo-config"});
    BootConfig bc;
    if (auto v = b->get("check-identity")) bc.check_identity = v->boolean();
    if (auto v = b->get("configure")) bc.configure = v->boolean();
    if (auto v = b->get("start")) bc.start = v->boolean();
    if (auto v = b->get("read-pdo-config")) bc.read_pdo_config = v->boolean();
    if (bc.configure && n.eds.empty()) b->fail("configure: true needs an eds or dcf file for the node");
    // The mapped objects' types and names come from the EDS/DCF.
    if (bc.read_pdo_config.value_or(false) && n.eds.empty())
      b->fail("read-pdo-config: true needs an eds or dcf file for the node");
    n.boot = bc;
  }
  if (auto m = a.get("sparkplug-metrics")) {
    for (const auto& item : m->items()) {
      // "2300h", 2300h, "6060h:0", 0x2300: the index in hex as everywhere
      // in the API (parse_index_text), an optional ":sub" (decimal or 0x).
      const auto text = item.str();
      const auto colon = text.find(':');
      const auto index = parse_index_text(std::string_view(text).substr(0, colon));
      std::optional<std::uint8_t> sub;
      if (colon != std::string::npos) sub = parse_sub_index_text(std::string_view(text).substr(colon + 1));
      if (!index || (colon != std::string::npos && !sub))
        item.fail("'" + text + "' is not an object (e.g. 2300h, 6060h:0)");
      SparkplugObject o{*index, sub};
      if (std::find(n.sparkplug_metrics.begin(), n.sparkplug_metrics.end(), o) != n.sparkplug_metrics.end())
        item.fail("'" + text + "' is listed twice");
      n.sparkplug_metrics.push_back(o);
    }
  }
}

namespace {

// lss: {assign: [{identity: {vendor-id, product-code, revision, serial},
// node-id: N, store: true}]} (contract "LSS master"; CiA 305: the LSS
// address is the four 1018h values).
void parse_lss(const At& a, NetworkConfig& net) {
  a.expect_map({"assign"});
  std::set<int> ids;
  std::set<canopen::lss::Identity> addresses;
  for (const auto& item : a.get("assign") ? a.get("assign")->items() : std::vector<At>{}) {
    item.expect_map({"identity", "node-id", "store"});
    auto identity = item.get("identity");
    if (!identity) item.fail("missing key 'identity' ({vendor-id, product-code, revision, serial})");
    identity->expect_map({"vendor-id", "product-code", "revision", "serial"});
    LssAssignConfig e;
    auto word = [&](const char* key) -> std::uint32_t {
      auto v = identity->get(key);
      if (!v) identity->fail(std::string("missing key '") + key + "' (all four LSS address parts are needed)");
      return static_cast<std::uint32_t>(v->integer(0, 0xFFFFFFFF));
    };
    e.identity.vendor_id = word("vendor-id");
    e.identity.product_code = word("product-code");
    e.identity.revision = word("revision");
    e.identity.serial = word("serial");
    auto id = item.get("node-id");
    if (!id) item.fail("missing key 'node-id' (1..127)");
    e.node_id = static_cast<std::uint8_t>(id->integer(1, 127));
    if (e.node_id == net.node_id) id->fail("node " + std::to_string(e.node_id) + " is the gateway's own node-ID");
    if (!ids.insert(e.node_id).second) id->fail("node-ID " + std::to_string(e.node_id) + " is assigned twice");
    if (!addresses.insert(e.identity).second)
      identity->fail("this LSS address is listed twice");
    if (auto v = item.get("store")) e.store = v->boolean();
    net.lss_assign.push_back(e);
  }
}

}  // namespace

void parse_network(const At& a, NetworkConfig& net, std::uint8_t default_node_id, const std::string& dir) {
  a.expect_map(
      {"interface", "simulated", "simulation", "bitrate", "node-id", "heartbeat-ms", "sync", "time", "boot", "nodes",
       "lss", "capture"});
  auto iface = a.get("interface");
  if (auto sim = a.get("simulated")) net.simulated = sim->boolean();
  if (net.simulated) {
    // The demo's devices on an in-process bus: for trying dashboards and
    // pipelines without hardware.
    if (iface) iface->fail("a simulated network has no interface");
    if (auto n = a.get("nodes")) n->fail("a simulated network has the built-in devices (nodes 5, 10, 11)");
    if (auto s = a.get("simulation")) {
      s->expect_map({"tpdo-period-ms", "heartbeat-ms", "emcy-period-ms"});
      if (auto v = s->get("tpdo-period-ms")) net.simulation.tpdo_period = ms(*v);
      if (auto v = s->get("heartbeat-ms")) net.simulation.heartbeat = ms(*v);
      if (auto v = s->get("emcy-period-ms")) net.simulation.emcy_period = ms(*v, 3'600'000);
    }
  } else {
    if (auto s = a.get("simulation")) s->fail("only for a network with simulated: true");
    if (!iface) a.fail("missing key 'interface' (a SocketCAN interface such as can0)");
    net.interface = iface->str();
    if (net.interface.empty() || net.interface.size() > 15 || net.interface.find_first_of("/: \t") != std::string::npos)
      iface->fail("'" + net.interface + "' is not an interface name");
  }
  if (auto v = a.get("bitrate")) net.bitrate = static_cast<std::uint32_t>(v->integer(1000, 8'000'000));
  net.node_id = default_node_id;
  if (auto v = a.get("node-id")) net.node_id = static_cast<std::uint8_t>(v->integer(1, 127));
  if (auto v = a.get("heartbeat-ms")) net.heartbeat_producer = ms(*v);
  if (auto s = a.get("sync")) {
    s->expect_map({"period-us", "counter-overflow", "window-us"});
    if (auto v = s->get("period-us")) net.sync.period = std::chrono::microseconds(v->integer(0, 0xFFFFFFFF));
    if (auto v = s->get("counter-overflow")) {
      net.sync.counter_overflow = static_cast<std::uint8_t>(v->integer(0, 240));
      if (net.sync.counter_overflow == 1) v->fail("1 is reserved (CiA 301 7.5.2.22: 0 or 2..240)");
    }
    if (auto v = s->get("window-us")) net.sync.window = std::chrono::microseconds(v->integer(0, 0xFFFFFFFF));
  }
  if (auto t = a.get("time")) {
    t->expect_map({"produce", "period-ms"});
    if (auto v = t->get("produce")) net.time.produce = v->boolean();
    if (auto v = t->get("period-ms")) net.time.period = std::chrono::milliseconds(v->integer(10, 86'400'000));
  }
  if (auto b = a.get("boot")) {
    b->expect_map({"read-pdo-config", "at-start"});  // the rest of boot: is per node
    if (auto v = b->get("read-pdo-config")) net.read_pdo_config = v->boolean();
    if (auto v = b->get("at-start")) {
      const std::string mode = v->str();
      if (mode == "as-found") net.boot_at_start = NetworkConfig::BootAtStart::AsFound;
      else if (mode == "reset-communication") net.boot_at_start = NetworkConfig::BootAtStart::ResetCommunication;
      else v->fail("'" + mode + "' is not as-found or reset-communication");
    }
  }
  std::set<int> seen;
  for (const auto& item : a.get("nodes") ? a.get("nodes")->items() : std::vector<At>{}) {
    NodeConfig n;
    parse_node(item, n, dir);
    if (!seen.insert(n.id).second) item.fail("node " + std::to_string(n.id) + " is listed twice");
    if (n.id == net.node_id) item.fail("node " + std::to_string(n.id) + " is the gateway's own node-ID");
    net.nodes.push_back(std::move(n));
  }
  if (auto l = a.get("lss")) parse_lss(*l, net);
  if (auto c = a.get("capture")) {
    c->expect_map({"ring-seconds", "max-bytes"});
    if (auto v = c->get("ring-seconds")) net.capture.ring_seconds = static_cast<std::uint32_t>(v->integer(0, 3600));
    // at least a few hundred frames; at most 1 GiB per network
    if (auto v = c->get("max-bytes")) net.capture.max_bytes = v->integer(65536, std::uint64_t{1} << 30);
  }
}

}  // namespace config_yaml

using namespace config_yaml;

NodeConfig parse_node_config(std::string_view text, const std::string& source, const std::string& dir, bool lines) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + (lines ? ":" + std::to_string(e.mark.line + 1) : std::string()) +
                      ": not valid YAML or JSON: " + e.msg);
  }
  At a(root, "", source, lines);
  if (!a.is_map()) a.fail("expected a mapping of keys (one nodes: entry)");
  NodeConfig n;
  parse_node(a, n, dir);
  return n;
}

NodeConfig node_config_from_json(const boost::json::value& settings, const NetworkConfig& net,
                                 const std::string& source, const std::string& dir, bool lines) {
  boost::json::value v = settings;
  bool built_in = false;
  if (auto* o = v.if_object(); o != nullptr && net.simulated) {
    if (const auto* e = o->if_contains("eds"); e != nullptr && e->is_string() && e->as_string() == kBuiltInEds) {
      built_in = true;
      o->erase("eds");
    }
  }
  NodeConfig n = parse_node_config(boost::json::serialize(v), source, dir, lines);
  if (built_in) n.eds = std::string(kBuiltInEds);
  return n;
}

NodeConfig node_config_from_request(boost::json::value body, std::uint8_t node, const NetworkConfig& net,
                                    const std::string& config_file) {
  if (auto* o = body.if_object(); o != nullptr && !o->contains("id")) (*o)["id"] = node;
  const std::string dir = config_file.empty() ? std::string() : fs::path(config_file).parent_path().string();
  return node_config_from_json(body, net, "request body", dir, false);
}

boost::json::object node_config_json(const NodeConfig& n) {
  boost::json::object o;
  o["id"] = n.id;
  if (!n.name.empty()) o["name"] = n.name;
  if (!n.eds.empty()) o["eds"] = n.eds;
  if (n.heartbeat_consumer) o["heartbeat-consumer-ms"] = n.heartbeat_consumer->count();
  else o["heartbeat-consumer-ms"] = "auto";
  if (n.guarding.guard_time.count() > 0)
    o["guarding"] = {{"guard-time-ms", n.guarding.guard_time.count()}, {"life-time-factor", n.guarding.life_time_factor}};
  if (n.boot) {
    boost::json::object b{{"check-identity", n.boot->check_identity}, {"configure", n.boot->configure},
                          {"start", n.boot->start}};
    if (n.boot->read_pdo_config) b["read-pdo-config"] = *n.boot->read_pdo_config;
    o["boot"] = std::move(b);
  }
  if (!n.sparkplug_metrics.empty()) {
    boost::json::array m;
    for (const auto& obj : n.sparkplug_metrics) {
      char buf[16];
      std::string t(buf, static_cast<std::size_t>(std::snprintf(buf, sizeof buf, "%04Xh", obj.index)));
      if (obj.sub) t += ":" + std::to_string(*obj.sub);
      m.emplace_back(t);
    }
    o["sparkplug-metrics"] = std::move(m);
  }
  return o;
}

}  // namespace gateway
