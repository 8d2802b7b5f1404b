// Internal to the configuration parser (config.cpp and one *_yaml.cpp file
// per section of the file): the YAML node every section parser reads
// through, the helpers they share, and the section parsers parse_config()
// calls. Not for use outside gateway/config/.
//
// Errors are ConfigError (config.hpp), thrown by At::fail(). Thread safety:
// pure functions of their arguments.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "config/config.hpp"

namespace gateway::config_yaml {

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

// `name` against `base_dir` (the configuration file's directory) unless it
// is absolute or either is empty.
std::string resolve(const std::string& base_dir, const std::string& name);
// Usable as one MQTT topic level (the gateway id, Sparkplug ids).
bool valid_topic_level(const std::string& s);
std::chrono::milliseconds ms(const At& a, std::uint64_t max = 65535);
// viewer, operator or admin; also none when allow_none.
Role parse_role(const At& a, bool allow_none = false);

// networks_yaml.cpp
void parse_node(const At& a, NodeConfig& n, const std::string& dir);
void parse_network(const At& a, NetworkConfig& net, std::uint8_t default_node_id, const std::string& dir);
// mqtt_yaml.cpp
void parse_tls_files(const At& t, mqtt::MqttConfig& m, const std::string& dir);
// `mqtt-version`: "5" (with the fallback to 3.1.1) or "3.1.1".
void parse_mqtt_version(const At& v, mqtt::MqttConfig& m);
// uri: one URI or a list of them (server_uri, then standby_uris); the
// scheme and host are checked by main (process.cpp) with the client's rules.
void parse_mqtt_uris(const At& v, mqtt::MqttConfig& m);
void parse_mqtt(const At& a, MqttConfig& m, const std::string& dir);
// mqtt.qos and mqtt.queue.storage, the per-kind maps (after parse_mqtt()
// checked they are maps); `file` as given to parse_config().
void parse_mqtt_kinds(const At& m, MqttConfig& mq, const std::string& file);
// sparkplug_yaml.cpp
void parse_sparkplug(const At& a, SparkplugConfig& sp, const std::string& dir);
// http_yaml.cpp
void parse_http(const At& a, HttpConfig& h, const std::string& dir);
// ascii_yaml.cpp
void parse_ascii(const At& a, AsciiConfig& ac);

}  // namespace gateway::config_yaml
