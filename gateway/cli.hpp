// Command line of canopen-gateway (the API contract's "Command line"; the
// whole of it, with defaults, is help_text()).
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "log.hpp"

namespace gateway {

// One --eds NODE=FILE: the EDS/DCF describing remote node NODE (on every network).
struct EdsOption {
  int node = 0;
  std::string file;
  friend bool operator==(const EdsOption&, const EdsOption&) = default;
};

// What the command line says; a flag that was not given is empty, so the
// configuration file's value (or the default) stays (flags win over the file).
struct CliOptions {
  std::optional<std::string> config_file;    // --config
  std::vector<std::string> can_interfaces;   // one network each, numbered from 1
  std::optional<int> node_id;                // the gateway's own CANopen node-ID (default 127)
  std::vector<EdsOption> eds;                // in command-line order, one per node
  std::optional<std::string> mqtt_uri;       // --mqtt: turns MQTT on
  std::optional<std::string> mqtt_format;    // "json" or "protobuf"
  std::optional<std::string> http;           // ADDR:PORT, checked
  std::optional<std::string> gateway_id;     // MQTT topic level, default the host name
  std::optional<std::string> sparkplug_group;  // --sparkplug GROUP_ID: the Sparkplug B edge node on
  std::optional<std::string> ascii;          // --ascii ADDR:PORT or unix:PATH: the CiA 309-3 server on
  bool demo = false;                         // add a simulated network
  std::optional<LogLevel> log_level;
  bool help = false;
  bool version = false;
};

// "ADDR:PORT" with an IPv4 address, a host name or [IPv6]; false when malformed.
bool split_host_port(const std::string& text, std::string& host, unsigned short& port);

// Bad command line: what() is one line naming the flag and the reason, with
// the quoted input made printable() (no raw control characters).
class UsageError : public std::runtime_error {
 public:
  explicit UsageError(const std::string& what) : std::runtime_error(printable(what)) {}
};

// Parses argv (without argv[0]). Throws UsageError.
CliOptions parse_cli(const std::vector<std::string>& args);

// The synopsis: "usage: canopen-gateway [--config FILE] ..." (a few lines).
std::string usage_text();
// What --help prints: the synopsis, then every flag with what it does and
// its default, the exit statuses and where to read on. At most 80 columns.
std::string help_text();

}  // namespace gateway
