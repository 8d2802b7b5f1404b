#include "cli.hpp"

#include <charconv>

namespace gateway {

namespace {

int parse_int(const std::string& flag, const std::string& v) {
  int out = 0;
  auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), out);
  if (ec != std::errc() || p != v.data() + v.size()) throw UsageError(flag + ": '" + v + "' is not a number");
  return out;
}

// MQTT topic level: no wildcards, no '/', printable.
bool valid_topic_level(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c <= 0x20 || c == 0x7F || c == '/' || c == '+' || c == '#') return false;
  }
  return true;
}

}  // namespace

bool split_host_port(const std::string& text, std::string& host, unsigned short& port) {
  std::string h;
  std::string p;
  if (!text.empty() && text.front() == '[') {
    const auto close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') return false;
    h = text.substr(1, close - 1);
    p = text.substr(close + 2);
  } else {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos || text.find(':') != colon) return false;
    h = text.substr(0, colon);
    p = text.substr(colon + 1);
  }
  if (h.empty() || p.empty()) return false;
  unsigned value = 0;
  auto [end, ec] = std::from_chars(p.data(), p.data() + p.size(), value);
  if (ec != std::errc() || end != p.data() + p.size() || value > 65535) return false;
  host = h;
  port = static_cast<unsigned short>(value);
  return true;
}

std::string usage_text() {
  return "usage: canopen-gateway [--config FILE] [--can IFACE]... [--node-id N]\n"
         "                       [--eds NODE=FILE]... [--mqtt URI]\n"
         "                       [--mqtt-format json|protobuf] [--http ADDR:PORT]\n"
         "                       [--gateway-id ID] [--sparkplug GROUP_ID]\n"
         "                       [--ascii ADDR:PORT|unix:PATH] [--demo]\n"
         "                       [--log-level trace|debug|info|warn|error]\n"
         "       canopen-gateway --help | --version\n";
}

std::string help_text() {
  return usage_text() + R"(
Bridges CANopen networks (SocketCAN) to MQTT, a REST API, a WebSocket event
stream and a web dashboard. Flags win over the configuration file: a flag not
given leaves the file's value, else the default shown. At least one network
is needed: --can, networks: in the --config file, or --demo.

  --config FILE      YAML configuration file; gateway.example.yaml (installed
                     in share/canopen-gateway/, deploy/ in the source) shows
                     every key. Default: none, flags and defaults only.
  --can IFACE        SocketCAN interface (can0, vcan0, ...), one network each,
                     numbered from 1 in the order given; repeatable. Replaces
                     the file's networks (one with the same interface keeps
                     its settings). Default: the file's networks.
  --node-id N        the gateway's own CANopen node-ID on every network,
                     1..127. Default: the file's node-id, else 127.
  --eds NODE=FILE    EDS or DCF file describing node NODE (1..127) on every
                     CAN network; repeatable. Default: the file's nodes; a
                     node without one has its values shown raw (hex).
  --mqtt URI         turn MQTT on and publish to this broker:
                     tcp://HOST[:PORT] (port 1883) or ssl://HOST[:PORT] (8883);
                     mqtt:// and mqtts:// mean the same.
                     Default: mqtt.uri in the file, else MQTT off.
  --mqtt-format F    MQTT payloads: json (proto3 JSON mapping) or protobuf.
                     Default: mqtt.format in the file, else json.
  --http ADDR:PORT   where the REST API, WebSocket events, /metrics and the
                     dashboard listen: an IP address ([::1]:8080 for IPv6,
                     0.0.0.0 for every address) and a port (0: any free one).
                     Off loopback the file needs http.tokens and http.tls
                     (see gateway.example.yaml). Default: http.listen in the
                     file, else 127.0.0.1:8080.
  --gateway-id ID    MQTT topic level, canopen/ID/...; no '/', '+', '#' or
                     spaces. Default: gateway.id in the file, else the host
                     name.
  --sparkplug G      also run a Sparkplug B 3.0 edge node in group G (no '/',
                     '+', '#' or spaces) on its own MQTT session: edge node id
                     sparkplug.edge-node-id, else the gateway id; the broker
                     sparkplug.uri, else mqtt's (--mqtt). Default:
                     sparkplug.group-id in the file, else off.
  --ascii ADDR       also serve the CiA 309-3 ASCII interface (cocomm, nc):
                     ADDR:PORT (an IP address; port 0: any free one) or
                     unix:PATH (mode 0660). Off loopback the file needs
                     ascii.allow-remote: true. Clients act with ascii.role
                     (default admin without http tokens, else operator).
                     Default: ascii.listen in the file,
                     else off.
  --demo             add a simulated network with a CiA 402 drive (node 5)
                     and two CiA 401 I/O modules (nodes 10, 11): no CAN
                     hardware or broker needed. On a loopback listener
                     without tokens it asks for no login. Default: off.
  --log-level L      trace, debug, info, warn or error (to stderr).
                     Default: gateway.log-level in the file, else info.
  -h, --help         print this text and exit.
  --version          print the version and exit.

A value may also follow an equals sign: --http=0.0.0.0:8443.
At start-up the gateway logs the URLs of the dashboard, the REST API, the
event stream, /metrics and the MQTT broker and topics.

Exit status: 0 after SIGINT or SIGTERM and a clean stop; 2 for a bad command
line or configuration, or an address it cannot listen on (one line on stderr
naming the flag or FILE:LINE); 3 when a CAN interface cannot be opened; 1 for
anything else.
)";
}

CliOptions parse_cli(const std::vector<std::string>& args) {
  CliOptions o;
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string flag = args[i];
    std::string value;
    bool has_inline_value = false;
    if (auto eq = flag.find('='); flag.rfind("--", 0) == 0 && eq != std::string::npos) {
      value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
      has_inline_value = true;
    }
    auto take_value = [&]() -> std::string {
      if (has_inline_value) return value;
      if (i + 1 >= args.size() || args[i + 1].rfind("--", 0) == 0) throw UsageError(flag + ": missing value");
      return args[++i];
    };
    auto no_value = [&] {
      if (has_inline_value) throw UsageError(flag + " takes no value");
    };
    if (flag == "-h" || flag == "--help") {
      no_value();
      o.help = true;
    } else if (flag == "--version") {
      no_value();
      o.version = true;
    } else if (flag == "--can") {
      std::string iface = take_value();
      // Linux interface names: 1..15 bytes, no '/', ':' or white space, not "." or "..".
      const bool bad = iface.empty() || iface.size() > 15 || iface == "." || iface == ".." ||
                       iface.find_first_of("/: \t\n") != std::string::npos;
      if (bad) throw UsageError("--can: '" + iface + "' is not an interface name");
      o.can_interfaces.push_back(iface);
    } else if (flag == "--node-id") {
      const std::string v = take_value();
      const int n = parse_int(flag, v);
      if (n < 1 || n > 127) throw UsageError("--node-id: " + v + " is out of range 1..127");
      o.node_id = n;
    } else if (flag == "--eds") {
      const std::string v = take_value();
      const auto eq = v.find('=');
      if (eq == std::string::npos) throw UsageError("--eds: '" + v + "' is not NODE=FILE");
      const std::string node_text = v.substr(0, eq);
      int n = 0;
      auto [p, ec] = std::from_chars(node_text.data(), node_text.data() + node_text.size(), n);
      if (ec != std::errc() || p != node_text.data() + node_text.size())
        throw UsageError("--eds: node '" + node_text + "' is not a number");
      if (n < 1 || n > 127) throw UsageError("--eds: node " + node_text + " is out of range 1..127");
      if (eq + 1 == v.size()) throw UsageError("--eds: no file given for node " + node_text);
      for (const auto& e : o.eds) {
        if (e.node == n) throw UsageError("--eds: node " + node_text + " given twice");
      }
      o.eds.push_back({n, v.substr(eq + 1)});
    } else if (flag == "--log-level") {
      const std::string v = take_value();
      auto l = parse_log_level(v);
      if (!l) throw UsageError("--log-level: '" + v + "' is not one of trace, debug, info, warn, error");
      o.log_level = *l;
    } else if (flag == "--config") {
      const std::string v = take_value();
      if (v.empty()) throw UsageError("--config: empty file name");
      o.config_file = v;
    } else if (flag == "--mqtt") {
      const std::string v = take_value();
      // The schemes the publisher speaks (mqtt/publisher.hpp); the rest of
      // the URI is checked with the configuration (main.cpp).
      const bool known = v.rfind("tcp://", 0) == 0 || v.rfind("mqtt://", 0) == 0 || v.rfind("ssl://", 0) == 0 ||
                         v.rfind("mqtts://", 0) == 0;
      if (!known)
        throw UsageError("--mqtt: '" + v + "' is not a broker URI (tcp://HOST[:PORT], ssl://HOST[:PORT], mqtt://, mqtts://)");
      o.mqtt_uri = v;
    } else if (flag == "--mqtt-format") {
      const std::string v = take_value();
      if (v != "json" && v != "protobuf") throw UsageError("--mqtt-format: '" + v + "' is not json or protobuf");
      o.mqtt_format = v;
    } else if (flag == "--http") {
      const std::string v = take_value();
      std::string host;
      unsigned short port = 0;
      if (!split_host_port(v, host, port)) throw UsageError("--http: '" + v + "' is not ADDR:PORT");
      o.http = v;
    } else if (flag == "--gateway-id") {
      const std::string v = take_value();
      if (!valid_topic_level(v))
        throw UsageError("--gateway-id: '" + v + "' cannot be an MQTT topic level (no '/', '+', '#', spaces)");
      o.gateway_id = v;
    } else if (flag == "--sparkplug") {
      const std::string v = take_value();
      if (!valid_topic_level(v))
        throw UsageError("--sparkplug: '" + v + "' cannot be a Sparkplug group id (no '/', '+', '#', spaces)");
      o.sparkplug_group = v;
    } else if (flag == "--ascii") {
      const std::string v = take_value();
      std::string host;
      unsigned short port = 0;
      const bool unix_path = v.rfind("unix:", 0) == 0 && v.size() > 5;
      if (!unix_path && !split_host_port(v, host, port))
        throw UsageError("--ascii: '" + v + "' is not ADDR:PORT or unix:PATH");
      o.ascii = v;
    } else if (flag == "--demo") {
      no_value();
      o.demo = true;
    } else {
      throw UsageError("unknown option '" + args[i] + "' (canopen-gateway --help lists them)");
    }
  }
  if (!o.help && !o.version && o.can_interfaces.empty() && !o.config_file && !o.demo)
    throw UsageError("no CAN interface given (use --can IFACE, --config FILE or --demo)");
  return o;
}

}  // namespace gateway
