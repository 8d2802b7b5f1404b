// sparkplug: (SparkplugConfig): the edge node's ids and its own MQTT
// session; merge() fills in what it inherits from mqtt:.
#include <fstream>

#include "config/config_yaml.hpp"

namespace gateway::config_yaml {

namespace {

// Sparkplug ids are topic levels (spec ch4: no '+', '/', '#'); like the
// gateway id, no spaces or control characters either.
void sparkplug_id(const At& v, std::string& out) {
  out = v.str();
  if (!valid_topic_level(out))
    v.fail("'" + out + "' cannot be a Sparkplug id (1..64 characters, no '/', '+', '#', spaces)");
}

}  // namespace

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
    parse_mqtt_uris(*v, m);  // checked with mqtt.uri's rules by main (process.cpp)
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
  if (auto v = a.get("mqtt-version")) parse_mqtt_version(*v, m);
  if (auto v = a.get("keepalive-s")) m.keepalive = std::chrono::seconds(v->integer(1, 65535));
}

}  // namespace gateway::config_yaml
