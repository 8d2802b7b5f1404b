// mqtt: (gateway::MqttConfig) and the TLS files of an MQTT connection
// (also sparkplug.tls).
#include <algorithm>
#include <filesystem>
#include <fstream>

#include "config/config_yaml.hpp"
#include "mqtt/topic_filter.hpp"

namespace gateway::config_yaml {

namespace fs = std::filesystem;

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

void parse_mqtt_version(const At& v, mqtt::MqttConfig& m) {
  const auto s = v.str();
  if (s == "5") m.mqtt_version = 5;
  else if (s == "3.1.1") m.mqtt_version = 4;
  else v.fail("'" + s + "' is not 5 (falls back to 3.1.1 when the broker refuses it) or 3.1.1");
}

void parse_mqtt_uris(const At& v, mqtt::MqttConfig& m) {
  m.standby_uris.clear();
  if (!v.is_seq()) {
    m.server_uri = v.str();
    return;
  }
  const auto items = v.items();
  if (items.empty()) v.fail("no broker URI (give one, or a list such as [tcp://a:1883, tcp://b:1883])");
  std::vector<std::string> uris;
  for (const auto& item : items) {
    auto u = item.str();
    if (std::find(uris.begin(), uris.end(), u) != uris.end()) item.fail("'" + u + "' is in the list twice");
    uris.push_back(std::move(u));
  }
  m.server_uri = uris.front();
  m.standby_uris.assign(uris.begin() + 1, uris.end());
}

void parse_mqtt(const At& a, MqttConfig& m, const std::string& dir) {
  a.expect_map({"uri", "client-id", "username", "password", "password-file", "tls", "format", "qos", "heartbeat",
                "heartbeat-min-interval-ms", "queue", "requests-role", "reply-topics", "mqtt-version"});
  auto uri = a.get("uri");
  if (!uri) a.fail("missing key 'uri' (e.g. tcp://localhost:1883)");
  parse_mqtt_uris(*uri, m);
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
  if (auto v = a.get("mqtt-version")) parse_mqtt_version(*v, m);
  if (auto v = a.get("format")) {
    const auto f = v->str();
    if (f == "json") m.format = PayloadFormat::Json;
    else if (f == "protobuf") m.format = PayloadFormat::Protobuf;
    else v->fail("'" + f + "' is not json or protobuf");
  }
  if (auto q = a.get("qos")) {
    if (!q->is_map()) q->fail("expected kind: level pairs, e.g. tpdo: 0");  // read in parse_mqtt_kinds
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
      s->fail("expected kind: mode pairs, e.g. tpdo: outage");  // read in parse_mqtt_kinds
  }
}

void parse_mqtt_kinds(const At& m, MqttConfig& mq, const std::string& file) {
  // Per-kind maps make an At of each entry, which needs the file name (not
  // only its directory). `default` first sets every kind, whatever its
  // place in the map.
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
  if (auto q = m.get("qos"))
    per_kind(*q, [&](EventKind k, const At& v) { mq.qos[k] = static_cast<std::uint8_t>(v.integer(0, 2)); });
  if (auto s = m.get("queue") ? m.get("queue")->get("storage") : std::nullopt) {
    per_kind(*s, [&](EventKind k, const At& v) {
      const auto mode = v.str();
      if (mode == "disk") mq.storage[k] = StorageMode::Disk;
      else if (mode == "outage") mq.storage[k] = StorageMode::Outage;
      else if (mode == "memory") mq.storage[k] = StorageMode::Memory;
      else v.fail("'" + mode + "' is not disk, outage or memory");
    });
  }
}

}  // namespace gateway::config_yaml
