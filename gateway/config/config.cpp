#include "config.hpp"

#include "ascii/ascii_listen.hpp"
#include "canopen/eds/eds.hpp"
#include "mqtt/topic_filter.hpp"
#include "request_codec.hpp"      // parse_index_text

#include <arpa/inet.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "request_checks.hpp"

namespace gateway {

namespace {

namespace fs = std::filesystem;

// A YAML node with the key path that led to it, so every error can say
// where it is. Unknown keys are errors: a typo must not be a silent default.
class At {
 public:
  // lines: whether messages name the line (not for a request body, whose
  // lines are the serialised JSON's, not what the user wrote).
  At(const YAML::Node& n, std::string path, const std::string& file, bool lines = true)
      : n_(n), path_(std::move(path)), file_(file), lines_(lines) {}

  [[noreturn]] void fail(const std::string& reason) const { throw ConfigError(where() + ": " + reason); }

  // "file:line: key.path", as errors start.
  std::string where() const {
    std::string w = file_.empty() ? std::string("<config>") : file_;
    const auto mark = n_.Mark();
    if (lines_ && mark.line >= 0) w += ":" + std::to_string(mark.line + 1);
    return w + ": " + (path_.empty() ? std::string("(top level)") : path_);
  }

  bool is_map() const { return n_.IsMap(); }
  bool is_seq() const { return n_.IsSequence(); }
  bool is_null() const { return !n_ || n_.IsNull(); }
  const YAML::Node& node() const { return n_; }
  const std::string& path() const { return path_; }

  void expect_map(std::initializer_list<const char*> allowed) const {
    if (is_null()) return;
    if (!n_.IsMap()) fail("expected a mapping of keys");
    for (const auto& kv : n_) {
      const auto key = kv.first.as<std::string>();
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
        At(kv.first, join(key), file_, lines_).fail("unknown key (known here: " + list + ")");
      }
    }
  }

  std::optional<At> get(const char* key) const {
    if (is_null() || !n_.IsMap()) return std::nullopt;
    auto child = n_[key];
    if (!child) return std::nullopt;
    return At(child, join(key), file_, lines_);
  }

  std::vector<At> items() const {
    std::vector<At> out;
    if (is_null()) return out;
    if (!n_.IsSequence()) fail("expected a list");
    std::size_t i = 0;
    for (const auto& item : n_) out.emplace_back(item, path_ + "[" + std::to_string(i++) + "]", file_, lines_);
    return out;
  }

  std::string str() const {
    if (!n_.IsScalar()) fail("expected a single value");
    return n_.Scalar();
  }

  bool boolean() const {
    const auto s = str();
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
    fail("'" + s + "' is not true or false");
  }

  // Decimal or 0x hex integer within [lo, hi].
  std::uint64_t integer(std::uint64_t lo, std::uint64_t hi) const {
    const auto s = str();
    std::uint64_t v = 0;
    const char* b = s.data();
    const char* e = s.data() + s.size();
    int base = 10;
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      b += 2;
      base = 16;
    }
    auto [p, ec] = std::from_chars(b, e, v, base);
    if (ec != std::errc() || p != e || b == e) fail("'" + s + "' is not a whole number");
    if (v < lo || v > hi) fail(s + " is out of range " + std::to_string(lo) + ".." + std::to_string(hi));
    return v;
  }

 private:
  std::string join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  YAML::Node n_;
  std::string path_;
  const std::string& file_;
  bool lines_ = true;
};

std::string resolve(const std::string& base_dir, const std::string& name) {
  if (name.empty() || base_dir.empty() || fs::path(name).is_absolute()) return name;
  return (fs::path(base_dir) / name).lexically_normal().string();
}

bool valid_topic_level(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  return std::none_of(s.begin(), s.end(), [](char ch) {
    const auto c = static_cast<unsigned char>(ch);
    return c <= 0x20 || c == 0x7F || c == '/' || c == '+' || c == '#';
  });
}

// An IPv4 or IPv6 literal (an IPv6 one may carry a %scope), what the HTTP
// server can listen on.
bool ip_literal(const std::string& s) {
  unsigned char buf[16];
  if (::inet_pton(AF_INET, s.c_str(), buf) == 1) return true;
  return ::inet_pton(AF_INET6, s.substr(0, s.find('%')).c_str(), buf) == 1;
}

std::chrono::milliseconds ms(const At& a, std::uint64_t max = 65535) {
  return std::chrono::milliseconds(a.integer(0, max));
}

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
    b->expect_map({"read-pdo-config"});  // the rest of boot: is per node
    if (auto v = b->get("read-pdo-config")) net.read_pdo_config = v->boolean();
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

Role parse_role(const At& a, bool allow_none = false) {
  const auto s = a.str();
  auto r = role_from_string(s);
  if (!r || (*r == Role::None && !allow_none))
    a.fail("'" + s + "' is not viewer, operator or admin" + (allow_none ? " or none" : ""));
  return *r;
}

// tls: {ca, cert, key} of an MQTT connection (mqtt, sparkplug).
void parse_tls_files(const At& t, mqtt::MqttConfig& m, const std::string& dir) {
  t.expect_map({"ca", "cert", "key"});
  auto file = [&](const char* key, std::string& out) {
    if (auto v = t.get(key)) {
      out = resolve(dir, v->str());
      std::error_code ec;
      if (!fs::is_regular_file(out, ec)) v->fail("file '" + out + "' not found");
    }
  };
  file("ca", m.ca_file);
  file("cert", m.cert_file);
  file("key", m.key_file);
  if (m.cert_file.empty() != m.key_file.empty()) t.fail("cert and key go together");
}

void parse_mqtt(const At& a, MqttConfig& m, const std::string& dir) {
  a.expect_map({"uri", "client-id", "username", "password", "password-file", "tls", "format", "qos", "heartbeat",
                "heartbeat-min-interval-ms", "queue", "requests-role", "reply-topics"});
  auto uri = a.get("uri");
  if (!uri) a.fail("missing key 'uri' (e.g. tcp://localhost:1883)");
  m.server_uri = uri->str();
  m.uri_origin = uri->where();
  m.enabled = true;
  if (auto v = a.get("client-id")) m.client_id = v->str();
  if (auto v = a.get("username")) m.username = v->str();
  if (auto v = a.get("password")) m.password = v->str();
  if (auto v = a.get("password-file")) {
    std::ifstream in(resolve(dir, v->str()));
    if (!in) v->fail("cannot read '" + resolve(dir, v->str()) + "'");
    std::getline(in, m.password);
  }
  if (auto t = a.get("tls")) parse_tls_files(*t, m, dir);
  if (auto v = a.get("format")) {
    const auto f = v->str();
    if (f == "json") m.format = PayloadFormat::Json;
    else if (f == "protobuf") m.format = PayloadFormat::Protobuf;
    else v->fail("'" + f + "' is not json or protobuf");
  }
  if (auto q = a.get("qos")) {
    if (!q->is_map()) q->fail("expected kind: level pairs, e.g. tpdo: 0");  // read in parse_config
  }
  if (auto v = a.get("heartbeat")) m.heartbeat = v->boolean();
  if (auto v = a.get("requests-role")) m.requests_role = parse_role(*v, true);
  if (auto r = a.get("reply-topics")) {
    for (const auto& item : r->items()) {
      const auto filter = item.str();
      if (auto why = mqtt::topic_filter_problem(filter); !why.empty())
        item.fail("'" + filter + "' is not an MQTT topic filter: " + std::string(why));
      m.reply_topics.push_back(filter);
    }
    // An empty list would refuse every reply; leaving the key out is the default rule.
    if (m.reply_topics.empty()) r->fail("no topic filter (leave the key out for the default rule)");
  }
  if (auto v = a.get("heartbeat-min-interval-ms")) m.heartbeat_min_interval = ms(*v, 3'600'000);
  if (auto q = a.get("queue")) {
    q->expect_map({"dir", "max-bytes", "max-messages", "memory-max-bytes", "memory-max-messages", "storage"});
    if (auto v = q->get("dir")) m.queue.dir = resolve(dir, v->str());
    if (auto v = q->get("max-bytes")) m.queue.max_bytes = v->integer(1 << 16, 1ULL << 40);
    if (auto v = q->get("max-messages")) m.queue.max_messages = v->integer(16, 1ULL << 32);
    if (auto v = q->get("memory-max-bytes")) m.memory_max_bytes = v->integer(1 << 16, 1ULL << 36);
    if (auto v = q->get("memory-max-messages")) m.memory_max_messages = v->integer(16, 1ULL << 32);
    if (auto s = q->get("storage"); s && !s->is_map())
      s->fail("expected kind: mode pairs, e.g. tpdo: outage");  // read in parse_config
  }
}

// Sparkplug ids are topic levels (spec ch4: no '+', '/', '#'); like the
// gateway id, no spaces or control characters either.
void sparkplug_id(const At& v, std::string& out) {
  out = v.str();
  if (!valid_topic_level(out))
    v.fail("'" + out + "' cannot be a Sparkplug id (1..64 characters, no '/', '+', '#', spaces)");
}

void parse_sparkplug(const At& a, SparkplugConfig& sp, const std::string& dir) {
  a.expect_map({"group-id", "edge-node-id", "primary-host-id", "aliases", "commands-role", "uri", "client-id",
                "username", "password", "password-file", "tls", "mqtt-version", "keepalive-s"});
  auto group = a.get("group-id");
  if (!group) a.fail("missing key 'group-id' (the Sparkplug group, e.g. plant1)");
  sparkplug_id(*group, sp.group_id);
  sp.enabled = true;
  sp.origin = group->where();
  if (auto v = a.get("edge-node-id")) sparkplug_id(*v, sp.edge_node_id);
  if (auto v = a.get("primary-host-id")) sparkplug_id(*v, sp.primary_host_id);
  if (auto v = a.get("aliases")) sp.aliases = v->boolean();
  if (auto v = a.get("commands-role")) sp.commands_role = parse_role(*v, true);
  auto& m = sp.mqtt;
  if (auto v = a.get("uri")) {
    m.server_uri = v->str();  // checked with mqtt.uri's rules by main (check_mqtt_uris)
    sp.uri_origin = v->where();
  }
  if (auto v = a.get("client-id")) m.client_id = v->str();
  if (auto v = a.get("username")) m.username = v->str();
  if (auto v = a.get("password")) m.password = v->str();
  if (auto v = a.get("password-file")) {
    if (a.get("password")) v->fail("give either password or password-file, not both");
    std::ifstream in(resolve(dir, v->str()));
    if (!in) v->fail("cannot read '" + resolve(dir, v->str()) + "'");
    std::getline(in, m.password);
  }
  if (auto t = a.get("tls")) parse_tls_files(*t, m, dir);
  if (auto v = a.get("mqtt-version")) {
    const auto s = v->str();
    if (s == "5") m.mqtt_version = 5;
    else if (s == "3.1.1") m.mqtt_version = 4;
    else v->fail("'" + s + "' is not 5 (falls back to 3.1.1 when the broker refuses it) or 3.1.1");
  }
  if (auto v = a.get("keepalive-s")) m.keepalive = std::chrono::seconds(v->integer(1, 65535));
}


void parse_ascii(const At& a, AsciiConfig& ac) {
  a.expect_map({"listen", "allow-remote", "role", "idle-timeout-s", "max-clients"});
  ac.enabled = true;
  ac.listen_origin = a.where() + " (ascii.listen not set, default " + ac.listen + ")";
  if (auto v = a.get("listen")) {
    ac.listen = v->str();
    if (!ascii::parse_listen_address(ac.listen))
      v->fail("'" + ac.listen + "' is not ADDR:PORT (an IP address) or unix:/path");
    ac.listen_origin = v->where() + " " + ac.listen;
  }
  if (auto v = a.get("allow-remote")) ac.allow_remote = v->boolean();
  if (auto v = a.get("role")) ac.role = parse_role(*v);
  if (auto v = a.get("idle-timeout-s")) ac.idle_timeout = std::chrono::seconds(v->integer(0, 86400));
  if (auto v = a.get("max-clients")) ac.max_clients = v->integer(1, 1024);
}

void parse_http(const At& a, HttpConfig& h, const std::string& dir) {
  a.expect_map({"listen", "tls", "host-names", "allowed-origins", "tokens", "auth", "plain-http", "rate-limit",
                "web-root", "max-connections", "max-connections-per-address", "max-program-bytes"});
  if (auto v = a.get("listen")) {
    if (!split_host_port(v->str(), h.address, h.port)) v->fail("'" + v->str() + "' is not ADDR:PORT");
    h.listen_origin = v->where() + " " + v->str();
  }
  if (auto t = a.get("tls")) {
    t->expect_map({"cert", "key"});
    auto cert = t->get("cert");
    auto key = t->get("key");
    if (!cert || !key) t->fail("needs both cert and key");
    h.tls_origin = t->where();
    h.cert_file = resolve(dir, cert->str());
    h.key_file = resolve(dir, key->str());
    std::error_code ec;
    if (!fs::is_regular_file(h.cert_file, ec)) cert->fail("file '" + h.cert_file.string() + "' not found");
    if (!fs::is_regular_file(h.key_file, ec)) key->fail("file '" + h.key_file.string() + "' not found");
  }
  if (auto n = a.get("host-names")) {
    for (const auto& item : n->items()) {
      const auto name = item.str();
      if (auto hp = http::parse_host(name); !hp || hp->port)
        item.fail("'" + name + "' is not a host name or IP address (without a port)");
      h.host_names.push_back(name);
    }
  }
  if (auto o = a.get("allowed-origins")) {
    for (const auto& item : o->items()) {
      const auto origin = item.str();
      if (origin != "*" && !http::parse_origin(origin))
        item.fail("'" + origin + "' is not an origin like https://host:port (or *)");
      h.allowed_origins.push_back(origin);
    }
  }
  if (auto v = a.get("max-connections")) h.max_connections = v->integer(1, 100'000);
  if (auto v = a.get("max-connections-per-address")) h.max_connections_per_address = v->integer(0, 100'000);
  if (auto v = a.get("max-program-bytes"))
    h.max_program_bytes = static_cast<std::size_t>(v->integer(1024, 1024ULL * 1024 * 1024));
  if (auto v = a.get("auth")) h.auth = v->boolean();
  if (auto v = a.get("plain-http")) h.plain_http = v->boolean();
  if (auto r = a.get("rate-limit")) {
    r->expect_map({"requests-per-second", "burst"});
    if (auto v = r->get("requests-per-second")) h.rate_limit = static_cast<double>(v->integer(0, 1'000'000));
    if (auto v = r->get("burst")) h.rate_burst = static_cast<double>(v->integer(1, 1'000'000));
    h.rate_burst = std::max(h.rate_burst, h.rate_limit);
  }
  if (auto v = a.get("web-root")) h.static_dir = resolve(dir, v->str());
  if (auto t = a.get("tokens")) {
    std::set<std::string> names;
    for (const auto& item : t->items()) {
      item.expect_map({"name", "role", "sha256"});
      TokenConfig tc;
      auto name = item.get("name");
      auto role = item.get("role");
      auto hash = item.get("sha256");
      if (!name || !role || !hash) item.fail("a token needs name, role and sha256");
      tc.name = name->str();
      if (!names.insert(tc.name).second) name->fail("token name '" + tc.name + "' is used twice");
      tc.role = parse_role(*role);
      tc.sha256 = hash->str();
      std::transform(tc.sha256.begin(), tc.sha256.end(), tc.sha256.begin(),
                     [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); });
      if (tc.sha256.size() != 64 || tc.sha256.find_first_not_of("0123456789abcdef") != std::string::npos)
        hash->fail("not a hex SHA-256 (64 hex digits; store the hash, never the token)");
      h.tokens.push_back(std::move(tc));
    }
  }
}

}  // namespace

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

std::string default_gateway_id() {
  char host[256] = {};
  std::string id;
  if (::gethostname(host, sizeof host - 1) == 0) id = host;
  for (auto& c : id) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u == 0x7F || c == '/' || c == '+' || c == '#') c = '_';
  }
  // "(none)" is what a kernel without a host name reports.
  return id.empty() || id == "(none)" || id == "localhost" ? std::string("gateway") : id;
}

Config parse_config(const std::string& yaml_text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError((file.empty() ? std::string("<config>") : file) + ":" + std::to_string(e.mark.line + 1) +
                      ": not valid YAML: " + e.msg);
  }
  Config c;
  c.source = file;
  const std::string dir = file.empty() ? std::string() : fs::path(file).parent_path().string();
  At top(root, "", file);
  if (top.is_null()) return c;
  top.expect_map({"gateway", "networks", "mqtt", "http", "sparkplug", "ascii", "history"});
  std::uint8_t default_node_id = 127;
  if (auto g = top.get("gateway")) {
    g->expect_map({"id", "node-id", "log-level", "state-dir"});
    if (auto v = g->get("id")) {
      c.gateway_id = v->str();
      if (!valid_topic_level(c.gateway_id)) v->fail("'" + c.gateway_id + "' cannot be an MQTT topic level");
    }
    if (auto v = g->get("node-id")) default_node_id = static_cast<std::uint8_t>(v->integer(1, 127));
    c.node_id = default_node_id;
    if (auto v = g->get("log-level")) {
      auto l = parse_log_level(v->str());
      if (!l) v->fail("'" + v->str() + "' is not one of trace, debug, info, warn, error");
      c.log_level = *l;
    }
    if (auto v = g->get("state-dir")) {
      c.state_dir = resolve(dir, v->str());
      c.state_dir_origin = v->where();
    }
  }
  if (auto h = top.get("history")) {
    h->expect_map({"max-bytes"});
    if (auto v = h->get("max-bytes")) {
      // One object takes about 38 KiB (value_history.hpp): below 1 MiB the
      // history would hold too few objects to be of use; 0 turns it off.
      c.history.max_bytes = v->integer(0, std::uint64_t{16} << 30);
      if (c.history.max_bytes != 0 && c.history.max_bytes < (std::uint64_t{1} << 20))
        v->fail("must be 0 (no history) or 1048576 (1 MiB) .. 17179869184 (16 GiB), not " +
                std::to_string(c.history.max_bytes));
    }
  }
  if (auto n = top.get("networks")) {
    std::set<std::string> ifaces;
    for (const auto& item : n->items()) {
      NetworkConfig net;
      parse_network(item, net, default_node_id, dir);
      if (!net.simulated && !ifaces.insert(net.interface).second)
        item.fail("interface " + net.interface + " is configured twice");
      c.networks.push_back(std::move(net));
    }
  }
  if (auto m = top.get("mqtt")) {
    parse_mqtt(*m, c.mqtt, dir);
    if (auto q = m->get("queue"); q && q->get("dir")) c.queue_dir_origin = q->get("dir")->where();
    // Per-kind maps need the file name for errors, so they are read here.
    // `default` first sets every kind, whatever its place in the map.
    auto per_kind = [&](const At& map, const auto& set) {
      for (const auto& kv : map.node()) {
        const auto key = kv.first.as<std::string>();
        if (key != "default") continue;
        for (int k = 0; k <= static_cast<int>(kLastEventKind); ++k)
          set(static_cast<EventKind>(k), At(kv.second, map.path() + "." + key, file));
      }
      for (const auto& kv : map.node()) {
        const auto key = kv.first.as<std::string>();
        if (key == "default") continue;
        EventKind kind{};
        if (!event_kind_from_string(key, kind))
          At(kv.first, map.path() + "." + key, file)
              .fail("unknown event kind (status, bus, state, heartbeat, emcy, tpdo, pdo, sync, time, boot, default)");
        set(kind, At(kv.second, map.path() + "." + key, file));
      }
    };
    if (auto q = m->get("qos"))
      per_kind(*q, [&](EventKind k, const At& v) { c.mqtt.qos[k] = static_cast<std::uint8_t>(v.integer(0, 2)); });
    if (auto s = m->get("queue") ? m->get("queue")->get("storage") : std::nullopt) {
      per_kind(*s, [&](EventKind k, const At& v) {
        const auto mode = v.str();
        if (mode == "disk") c.mqtt.storage[k] = StorageMode::Disk;
        else if (mode == "outage") c.mqtt.storage[k] = StorageMode::Outage;
        else if (mode == "memory") c.mqtt.storage[k] = StorageMode::Memory;
        else v.fail("'" + mode + "' is not disk, outage or memory");
      });
    }
  }
  if (auto h = top.get("http")) parse_http(*h, c.http, dir);
  if (auto sp = top.get("sparkplug")) parse_sparkplug(*sp, c.sparkplug, dir);
  if (auto as = top.get("ascii")) parse_ascii(*as, c.ascii);
  return c;
}

Config load_config(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file + ": cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_config(text.str(), file);
}

Config merge(Config c, const CliOptions& cli) {
  if (cli.log_level) c.log_level = *cli.log_level;
  if (cli.gateway_id) c.gateway_id = *cli.gateway_id;
  if (c.gateway_id.empty()) c.gateway_id = default_gateway_id();
  if (cli.node_id) {
    c.node_id = static_cast<std::uint8_t>(*cli.node_id);
    for (auto& n : c.networks) n.node_id = c.node_id;
  }
  // A network the flags add (--can, --demo) gets gateway.node-id, as a file network does.
  const std::uint8_t own = c.node_id;
  // --can replaces the file's list of networks; settings of a file network
  // with the same interface are kept.
  if (!cli.can_interfaces.empty()) {
    std::vector<NetworkConfig> nets;
    for (const auto& iface : cli.can_interfaces) {
      auto it = std::find_if(c.networks.begin(), c.networks.end(),
                             [&](const NetworkConfig& n) { return n.interface == iface; });
      NetworkConfig n = it != c.networks.end() ? *it : NetworkConfig{};
      n.interface = iface;
      if (it == c.networks.end()) n.node_id = own;
      nets.push_back(std::move(n));
    }
    c.networks = std::move(nets);
  }
  if (cli.demo) {
    c.demo = true;
    NetworkConfig sim;
    sim.simulated = true;
    sim.interface = "";
    sim.node_id = own;
    // The gateway produces SYNC there, so the drive's synchronous TPDOs
    // (position, velocity) flow too.
    sim.sync.period = std::chrono::milliseconds(100);
    // The in-process bus has no bit rate of its own; counting its frames as
    // on a 250 kbit/s bus (CiA 301's most common rate) gives the demo a bus
    // load to show in REST, /metrics and the dashboard.
    sim.bitrate = 250000;
    c.networks.push_back(std::move(sim));
  }
  // --eds NODE=FILE describes NODE on every network.
  for (const auto& e : cli.eds) {
    std::error_code ec;
    if (!fs::is_regular_file(e.file, ec)) throw ConfigError("--eds " + std::to_string(e.node) + "=" + e.file + ": file not found");
    bool taken = false;  // by a real network, whose App reads it at start
    for (auto& net : c.networks) {
      if (net.simulated) continue;
      taken = true;
      auto it = std::find_if(net.nodes.begin(), net.nodes.end(), [&](const NodeConfig& n) { return n.id == e.node; });
      if (it == net.nodes.end()) {
        NodeConfig n;
        n.id = static_cast<std::uint8_t>(e.node);
        net.nodes.push_back(n);
        it = net.nodes.end() - 1;
      }
      it->eds = e.file;
    }
    // A file no network takes (--demo alone) is read here, with the same
    // rules, so it is checked all the same.
    if (!taken) {
      try {
        (void)canopen::eds::load_device_description(e.file, static_cast<std::uint8_t>(e.node));
      } catch (const canopen::eds::EdsError& err) {
        throw ConfigError("--eds " + std::to_string(e.node) + "=" + e.file + ": " + err.what());
      }
    }
  }
  if (cli.mqtt_uri) {
    c.mqtt.enabled = true;
    c.mqtt.server_uri = *cli.mqtt_uri;
    c.mqtt.uri_origin = "--mqtt " + *cli.mqtt_uri;
  }
  if (cli.mqtt_format) c.mqtt.format = *cli.mqtt_format == "protobuf" ? PayloadFormat::Protobuf : PayloadFormat::Json;
  if (c.mqtt.client_id.empty()) c.mqtt.client_id = "canopen-gateway-" + c.gateway_id;
  if (cli.sparkplug_group) {
    c.sparkplug.enabled = true;
    c.sparkplug.group_id = *cli.sparkplug_group;
    c.sparkplug.origin = "--sparkplug " + *cli.sparkplug_group;
  }
  if (c.sparkplug.enabled) {
    auto& sp = c.sparkplug;
    if (sp.edge_node_id.empty()) sp.edge_node_id = c.gateway_id;
    if (sp.mqtt.client_id.empty()) sp.mqtt.client_id = "canopen-gateway-" + c.gateway_id + "-spb";
    // The same broker as the native topics unless sparkplug.uri says
    // otherwise; only then its credentials and TLS files too (mqtt's
    // password is not sent to another broker).
    const bool same_broker = sp.mqtt.server_uri.empty() || (c.mqtt.enabled && sp.mqtt.server_uri == c.mqtt.server_uri);
    if (sp.mqtt.server_uri.empty()) {
      if (!c.mqtt.enabled)
        throw ConfigError(sp.origin + ": no broker for the Sparkplug edge node: set sparkplug.uri, or turn MQTT on "
                                      "(mqtt.uri or --mqtt; Sparkplug then uses the same broker)");
      sp.mqtt.server_uri = c.mqtt.server_uri;
      sp.uri_origin = c.mqtt.uri_origin + " (sparkplug.uri not set)";
    }
    if (same_broker) {
      if (sp.mqtt.username.empty() && sp.mqtt.password.empty()) {
        sp.mqtt.username = c.mqtt.username;
        sp.mqtt.password = c.mqtt.password;
      }
      if (sp.mqtt.ca_file.empty() && sp.mqtt.cert_file.empty()) {
        sp.mqtt.ca_file = c.mqtt.ca_file;
        sp.mqtt.cert_file = c.mqtt.cert_file;
        sp.mqtt.key_file = c.mqtt.key_file;
        sp.mqtt.key_password = c.mqtt.key_password;
      }
    }
    sp.mqtt.verify_server = c.mqtt.verify_server;
    sp.mqtt.connect_timeout = c.mqtt.connect_timeout;
    sp.mqtt.reconnect_min = c.mqtt.reconnect_min;
    sp.mqtt.reconnect_max = c.mqtt.reconnect_max;
    if (sp.mqtt.client_id == c.mqtt.client_id && same_broker)
      throw ConfigError(sp.origin + ": sparkplug.client-id '" + sp.mqtt.client_id +
                        "' is mqtt's as well: the broker would drop one session for the other");
  }
  if (cli.http) {
    split_host_port(*cli.http, c.http.address, c.http.port);
    c.http.listen_origin = "--http " + *cli.http;
  }
  if (c.http.listen_origin.empty()) c.http.listen_origin = "http.listen not set, default 127.0.0.1:8080";
  if (cli.ascii) {
    c.ascii.enabled = true;
    c.ascii.listen = *cli.ascii;
    c.ascii.listen_origin = "--ascii " + *cli.ascii;
  }
  if (c.ascii.enabled) {
    const auto a = ascii::parse_listen_address(c.ascii.listen);
    if (!a)
      throw ConfigError(c.ascii.listen_origin + ": '" + c.ascii.listen +
                        "' is not ADDR:PORT (an IP address) or unix:/path");
    // Anyone who reaches the socket acts with ascii.role: off this machine
    // only when the file says so.
    if (!a->local() && !c.ascii.allow_remote)
      throw ConfigError(c.ascii.listen_origin +
                        ": not a loopback address or unix socket, and the ASCII interface has no authentication of "
                        "its own; set ascii.allow-remote: true to accept that (and limit who reaches the port)");
  }
  // The server binds an address, it does not resolve names; "localhost" is
  // the one name everybody means the same by.
  if (c.http.address == "localhost") c.http.address = "127.0.0.1";
  if (!ip_literal(c.http.address))
    throw ConfigError(c.http.listen_origin + ": '" + c.http.address +
                      "' is not an IP address (listen on an address of this machine, 127.0.0.1, or 0.0.0.0 for all)");
  // --demo is for looking at on this machine: no login only where nobody
  // else can reach it and no tokens say otherwise (api-contract).
  if (c.demo && c.http.tokens.empty() && c.http.loopback()) c.http.auth = false;
  const char* systemd_state = std::getenv("STATE_DIRECTORY");  // StateDirectory= (may list several, ':')
  if (c.state_dir.empty() && systemd_state != nullptr && *systemd_state != '\0') {
    const std::string dirs = systemd_state;
    c.state_dir = dirs.substr(0, dirs.find(':'));
    c.state_dir_origin = "gateway.state-dir from $STATE_DIRECTORY (systemd StateDirectory=)";
  }
  if (c.state_dir.empty()) {
    // A service runs as root; a user's run keeps its state in the user's home.
    const char* home = std::getenv("HOME");
    const bool system = ::geteuid() == 0 || home == nullptr;
    c.state_dir = system ? std::string("/var/lib/canopen-gateway")
                         : (fs::path(home) / ".local/state/canopen-gateway").string();
    c.state_dir_origin = std::string("gateway.state-dir not set, default for ") + (system ? "root" : "a user ($HOME)");
  }
  if (c.mqtt.queue.dir.empty()) {
    c.mqtt.queue.dir = fs::path(c.state_dir) / "mqtt-queue";
    c.queue_dir_origin = "mqtt.queue.dir not set, default <state-dir>/mqtt-queue (" + c.state_dir_origin + ")";
  }

  const std::string where = c.source.empty() ? std::string("command line") : c.source;
  if (c.networks.empty())
    throw ConfigError(where + ": networks: no network configured (use --can IFACE, networks: in the file, or --demo)");
  for (const auto& net : c.networks) {
    for (const auto& n : net.nodes) {
      if (n.id != net.node_id) continue;
      // Blame the flag that brought the two together, else the file.
      const auto eds = std::find_if(cli.eds.begin(), cli.eds.end(), [&](const EdsOption& e) { return e.node == n.id; });
      const std::string blame = eds != cli.eds.end() ? "--eds " + std::to_string(eds->node) + "=" + eds->file
                                : cli.node_id       ? "--node-id " + std::to_string(*cli.node_id)
                                                    : where;
      throw ConfigError(blame + ": node " + std::to_string(n.id) + " is the gateway's own node-ID on " +
                        (net.simulated ? std::string("the demo network") : net.interface));
    }
  }
  // Tokenless MQTT requests are refused unless mqtt.requests-role says
  // otherwise (the broker's users are not the gateway's). The demo without
  // tokens lets them read, as its tour does; writes need the key set.
  if (!c.mqtt.requests_role) c.mqtt.requests_role = c.demo && c.http.tokens.empty() ? Role::Viewer : Role::None;
  // These blame the listen address (flag or file:line): it is what made
  // tokens and TLS necessary.
  if (c.http.auth && !c.http.loopback()) {
    const std::string tokens_in = c.source.empty() ? std::string() : " in " + c.source;
    if (c.http.tokens.empty())
      throw ConfigError(c.http.listen_origin + ": not a loopback address, and no http.tokens are configured" + tokens_in +
                        (c.demo ? " (--demo turns authentication off on loopback only)" : "") +
                        ": nobody could use the API; add tokens (see gateway.example.yaml), listen on 127.0.0.1, "
                        "or set http.auth: false (not advised)");
    if (c.http.cert_file.empty() && !c.http.plain_http)
      throw ConfigError(c.http.listen_origin +
                        ": not a loopback address, and bearer tokens would cross the network in clear text; "
                        "configure http.tls (cert, key)" + tokens_in + ", or set http.plain-http: true to accept that");
  }
  return c;
}

}  // namespace gateway
