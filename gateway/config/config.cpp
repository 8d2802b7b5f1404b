// parse_config() and load_config(): the top level of the file and the
// gateway's own keys (gateway:, history:); each component's section is
// parsed in its own file (config_yaml.hpp lists them), merge() with the
// command line is merge.cpp, check_state_dirs() state_dirs.cpp.
#include "config/config.hpp"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "config/config_yaml.hpp"

namespace gateway {

namespace fs = std::filesystem;

namespace config_yaml {

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

std::chrono::milliseconds ms(const At& a, std::uint64_t max) {
  return std::chrono::milliseconds(a.integer(0, max));
}

Role parse_role(const At& a, bool allow_none) {
  const auto s = a.str();
  auto r = role_from_string(s);
  if (!r || (*r == Role::None && !allow_none))
    a.fail("'" + s + "' is not viewer, operator or admin" + (allow_none ? " or none" : ""));
  return *r;
}

}  // namespace config_yaml

using namespace config_yaml;

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
    g->expect_map({"id", "node-id", "log-level", "state-dir", "device-type", "vendor-id", "serial-number"});
    if (auto v = g->get("device-type")) c.identity.device_type = static_cast<std::uint32_t>(v->integer(0, 0xFFFFFFFF));
    if (auto v = g->get("vendor-id")) c.identity.vendor_id = static_cast<std::uint32_t>(v->integer(0, 0xFFFFFFFF));
    if (auto v = g->get("serial-number")) c.identity.serial = static_cast<std::uint32_t>(v->integer(0, 0xFFFFFFFF));
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
    parse_mqtt_kinds(*m, c.mqtt, file);
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

}  // namespace gateway
