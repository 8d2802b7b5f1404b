// merge(): the command line over the file, the defaults that depend on
// both (ids, state directories, the demo) and the checks of the result as
// a whole.
#include <arpa/inet.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "ascii/ascii_listen.hpp"
#include "canopen/eds/eds.hpp"
#include "config/config.hpp"

namespace gateway {

namespace {

namespace fs = std::filesystem;

// An IPv4 or IPv6 literal (an IPv6 one may carry a %scope), what the HTTP
// server can listen on.
bool ip_literal(const std::string& s) {
  unsigned char buf[16];
  if (::inet_pton(AF_INET, s.c_str(), buf) == 1) return true;
  return ::inet_pton(AF_INET6, s.substr(0, s.find('%')).c_str(), buf) == 1;
}

// The first line of the machine id (systemd's /etc/machine-id, else
// D-Bus's copy); "" when neither can be read.
std::string machine_id_text() {
  for (const char* path : {"/etc/machine-id", "/var/lib/dbus/machine-id"}) {
    std::ifstream in(path);
    std::string line;
    if (in && std::getline(in, line) && !line.empty()) return line;
  }
  return {};
}

// FNV-1a: a serial from the gateway id where the machine has no id.
std::uint32_t fnv1a(const std::string& s) {
  std::uint32_t h = 2166136261u;
  for (const char ch : s) h = (h ^ static_cast<unsigned char>(ch)) * 16777619u;
  return h;
}

}  // namespace

std::optional<std::uint32_t> serial_from_machine_id(const std::string& text) {
  if (text.size() < 8) return std::nullopt;
  std::uint32_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + 8, v, 16);
  if (ec != std::errc{} || end != text.data() + 8) return std::nullopt;  // 8 hex digits, no sign
  return v;
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
    c.mqtt.standby_uris.clear();
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
    const bool same_broker = sp.mqtt.server_uri.empty() || (c.mqtt.enabled && sp.mqtt.uris() == c.mqtt.uris());
    if (sp.mqtt.server_uri.empty()) {
      if (!c.mqtt.enabled)
        throw ConfigError(sp.origin + ": no broker for the Sparkplug edge node: set sparkplug.uri, or turn MQTT on "
                                      "(mqtt.uri or --mqtt; Sparkplug then uses the same broker)");
      sp.mqtt.server_uri = c.mqtt.server_uri;
      sp.mqtt.standby_uris = c.mqtt.standby_uris;
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
    // As REST without tokens: every local process is admin (cocomm's reset
    // and lss_* commands work out of the box); with tokens, or reachable
    // from elsewhere, operator unless ascii.role says otherwise.
    if (!c.ascii.role) c.ascii.role = c.http.tokens.empty() && a->local() ? Role::Admin : Role::Operator;
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
  if (!c.identity.serial) c.identity.serial = serial_from_machine_id(machine_id_text()).value_or(fnv1a(c.gateway_id));
  for (auto& n : c.networks) n.identity = c.identity;
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
