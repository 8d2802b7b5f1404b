// The gateway's configuration: a YAML file (deploy/gateway.example.yaml
// shows every key) merged with the command line of ../shared/api-contract.md,
// flags winning. Loading is an edge of the process, so errors are
// exceptions: ConfigError::what() is one line naming the file, the line, the
// key and the reason ("gw.yaml:12: networks[0].nodes[1].eds: file not found").
//
// Pure data and functions; thread-safe.
#pragma once

#include <boost/json/object.hpp>
#include <boost/json/value.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/lss/frames.hpp"
#include "cli.hpp"
#include "core/node_entry.hpp"
#include "http/http_config.hpp"
#include "mqtt/mqtt_config.hpp"
#include "event_message.hpp"
#include "log.hpp"
#include "role.hpp"

namespace gateway {

// what() is one line; quoted input in it is made printable() (log.hpp).
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(const std::string& what) : std::runtime_error(printable(what)) {}
};

struct SyncConfig {
  std::chrono::microseconds period{0};  // 1006h; 0 = the gateway produces no SYNC
  std::uint8_t counter_overflow = 0;    // 1019h; 0 = no counter
  std::chrono::microseconds window{0};  // 1007h; 0 = no window
};

struct TimeConfig {
  bool produce = false;  // 1012h bit 30
  std::chrono::milliseconds period{1000};
};

// The built-in simulated devices of a simulated network (as in --demo).
struct SimulationConfig {
  std::chrono::milliseconds tpdo_period{200};   // new process values; 0 = never change
  std::chrono::milliseconds heartbeat{500};
  std::chrono::milliseconds emcy_period{20000};  // 0 = no periodic EMCY
};

// One device that `lss.assign` gives its node-ID at start-up (contract "LSS
// master"): selected by its LSS address (1018h sub 1..4), configured with
// `node_id`, stored when `store`.
struct LssAssignConfig {
  canopen::lss::Identity identity;
  std::uint8_t node_id = 0;
  bool store = true;
};

// The gateway's own node as masters and tools see it (1000h, 1018h): the
// `gateway:` keys device-type, vendor-id and serial-number, the same on
// every network (issue 28 item 4). The product code and revision come from
// the program itself (app/network_unit.cpp).
struct OwnIdentity {
  // 1000h: bits 0..15 309, the CiA 309 series (access to CANopen from
  // other networks: what this gateway is); bits 16..31 0.
  std::uint32_t device_type = 309;
  std::uint32_t vendor_id = 0;  // 1018h sub 1: 0 until the operator has a CiA vendor-ID to give
  // 1018h sub 4: merge() defaults it to serial_from_machine_id(), so two
  // gateways on one bus (or two tools' views of them) differ.
  std::optional<std::uint32_t> serial;
};

// 1018h sub 4 from the text of /etc/machine-id (32 hex digits, random per
// installation): its first 8 hex digits; nullopt when the text is not one.
std::optional<std::uint32_t> serial_from_machine_id(const std::string& text);

struct NetworkConfig {
  std::string interface;     // SocketCAN interface; "" for the simulated demo network
  bool simulated = false;    // --demo or simulated: true: in-process bus with simulated devices
  SimulationConfig simulation;
  std::uint32_t bitrate = 0; // informative only (the interface is configured outside)
  std::uint8_t node_id = 127;  // the gateway's own node-ID on this network
  std::chrono::milliseconds heartbeat_producer{1000};  // the gateway's 1017h
  OwnIdentity identity;  // Config::identity, copied by merge()
  SyncConfig sync;
  TimeConfig time;
  // boot: {read-pdo-config: true}: BootConfig::read_pdo_config for every
  // node with an EDS/DCF that does not set it itself (nodes without boot:
  // get a boot-up sequence that only reads the PDO configuration).
  bool read_pdo_config = false;
  // boot: {at-start: ...}: what the gateway does at its own start for the
  // nodes with boot: (CiA 302-2 lets the manager choose). AsFound: nothing
  // is sent; each node gets its sequence when first heard (pre-operational:
  // all of it; operational: the identity check only). ResetCommunication:
  // NMT reset-communication to each such node (one by one, never node 0, so
  // devices the gateway does not manage are left alone), so every one boots
  // again and is configured from its boot-up.
  enum class BootAtStart { AsFound, ResetCommunication };
  BootAtStart boot_at_start = BootAtStart::AsFound;
  std::vector<NodeConfig> nodes;
  // lss: {assign: [...]}: at start-up each listed device is selected, given
  // its node-ID (and stored); an absent device is logged, never fatal.
  std::vector<LssAssignConfig> lss_assign;
  // capture: {ring-seconds, max-bytes}: the ring of the network's last
  // frames that GET .../capture?last= reads (issue 18). Memory grows with
  // the traffic up to max-bytes; ring-seconds 0 turns the ring off.
  struct Capture {
    std::uint32_t ring_seconds = 60;
    std::uint64_t max_bytes = 16u << 20;
  } capture;
};

// The MQTT and HTTP settings are the components' own structs
// (mqtt/mqtt_config.hpp, http/http_config.hpp: their defaults live there);
// the gateway's keys that the components do not read extend them here.
using mqtt::PayloadFormat;
using mqtt::StorageMode;

struct MqttConfig : mqtt::MqttConfig {
  bool enabled = false;
  // Where server_uri came from, to start a message about it: "--mqtt
  // tcp://x:1", "gw.yaml:12: mqtt.uri" (merge()). client_id: default
  // "canopen-gateway-<gateway id>" (merge()); gateway_id and the status
  // payloads are filled in by the App.
  std::string uri_origin;
  bool heartbeat = true;         // publish heartbeat events at all
  std::chrono::milliseconds heartbeat_min_interval{0};  // per node; 0 = every heartbeat
  // Role of an MQTT request that carries no token (anyone who may publish
  // to the request topics on the broker). nullopt (not set): None, a token
  // is required, also without http.tokens; --demo without tokens sets
  // viewer (the README's tour reads over MQTT).
  std::optional<Role> requests_role;
};

// The Sparkplug B edge node (contract "Sparkplug B"): its own MQTT session
// (own client id, NDEATH as its Will) to mqtt.uri's broker unless `uri`
// says otherwise. Connection settings left empty come from `mqtt`.
struct SparkplugConfig {
  bool enabled = false;          // --sparkplug GROUP_ID or sparkplug.group-id
  std::string origin;            // "--sparkplug G", "gw.yaml:40: sparkplug.group-id" (messages)
  std::string uri_origin;        // "gw.yaml:41: sparkplug.uri", or mqtt's uri_origin when inherited
  std::string group_id;          // no '+', '/', '#'
  std::string edge_node_id;      // "" = the gateway id (merge() fills it in)
  std::string primary_host_id;   // "" = none
  bool aliases = false;          // sparkplug.aliases
  Role commands_role = Role::Operator;  // sparkplug.commands-role; None ignores NCMD/DCMD writes
  // The MQTT connection: server_uri "" = mqtt's; client_id default
  // "canopen-gateway-<gateway id>-spb"; username/password/TLS as mqtt's
  // unless given here. gateway_id and the status payloads are unused.
  mqtt::MqttConfig mqtt;
};

struct TokenConfig {
  std::string name;    // who, in the audit log
  Role role = Role::Viewer;
  std::string sha256;  // hex SHA-256 of the bearer token
};

struct HttpConfig : http::HttpConfig {
  // Where address and port came from, with the value, to start a message
  // about them: "--http 0.0.0.0:8080", "gw.yaml:30: http.listen
  // 0.0.0.0:8080", "http.listen not set, default 127.0.0.1:8080" (merge()).
  // address is an IP literal once merge()d ("localhost" becomes 127.0.0.1).
  std::string listen_origin;
  std::string tls_origin;  // "gw.yaml:31: http.tls"
  std::vector<TokenConfig> tokens;
  // On by default (off in --demo). With tokens, every request but the
  // dashboard's files and the OpenAPI document needs one. Without tokens
  // the listener must be loopback, and local callers act as admin.
  bool auth = true;
  // Off loopback with auth on, plain HTTP would carry the tokens in clear
  // text: refused unless TLS is configured or this is set.
  bool plain_http = false;
  double rate_limit = 50;  // requests per second per client address (0 = no limit)
  double rate_burst = 100;
  // The largest program image PUT .../program/{n} takes (http.max-program-bytes);
  // every other route keeps max_body_bytes. The image is held in memory
  // while it is downloaded.
  std::size_t max_program_bytes = 16 * 1024 * 1024;
  // static_dir (http.web-root): "" = the built-in default (main).

  bool loopback() const { return address == "127.0.0.1" || address == "::1" || address == "localhost"; }
  // What a caller without a token may do (Role::None: nothing).
  Role anonymous_role() const { return !auth || tokens.empty() ? Role::Admin : Role::None; }
};

// The CiA 309-3 ASCII server (contract "CiA 309-3 ASCII interface",
// ascii/ascii_server.hpp). The socket itself has no authentication, so it
// listens on loopback or a unix socket unless allow_remote says otherwise.
struct AsciiConfig {
  bool enabled = false;  // --ascii ADDR, or an `ascii:` section
  std::string listen = "127.0.0.1:60000";  // or "unix:/path" (cocomm's defaults: port 60000)
  // "--ascii 0.0.0.0:60000", "gw.yaml:40: ascii.listen 0.0.0.0:60000", for messages (merge()).
  std::string listen_origin;
  bool allow_remote = false;
  // What every ASCII client may do: ascii.role, or by default REST's
  // tokenless rule (merge() always sets it): admin when no tokens are
  // configured and the socket is loopback or unix only, else operator.
  std::optional<Role> role;
  std::chrono::seconds idle_timeout{300};  // 0 = never closed for idleness
  std::size_t max_clients = 16;
};

struct Config {
  std::string source;      // the file it came from ("" = command line only)
  std::string gateway_id;  // default: host name
  std::uint8_t node_id = 127;  // gateway.node-id: the own node-ID where a network does not say
  OwnIdentity identity;        // gateway.device-type, vendor-id, serial-number
  LogLevel log_level = LogLevel::Info;
  // Each network's event seq (seq-net<N>) and, by default, the MQTT queue.
  // merge() always sets it; "" (a Config built by hand) keeps nothing.
  std::string state_dir;
  // Where state_dir and mqtt.queue_dir came from, for messages:
  // "gw.yaml:3: gateway.state-dir", "STATE_DIRECTORY (systemd)", ... (merge()).
  std::string state_dir_origin, queue_dir_origin;
  bool demo = false;
  std::vector<NetworkConfig> networks;  // numbered from 1 in this order
  MqttConfig mqtt;
  HttpConfig http;
  SparkplugConfig sparkplug;
  AsciiConfig ascii;
  // history: {max-bytes}: the in-memory history of TPDO values the
  // dashboard's charts read (GET .../nodes/{node}/history, issue 18).
  // 0 = off; else 1 MiB..16 GiB. Default 64 MiB (history/value_history.hpp).
  struct History {
    std::uint64_t max_bytes = std::uint64_t{64} << 20;
  } history;
};

// Parses YAML text; `file` is used in error messages only. Relative file
// names inside (EDS, TLS) are resolved against the file's directory.
Config parse_config(const std::string& yaml_text, const std::string& file);
// One `nodes:` entry on its own (a mapping in YAML or JSON: JSON is YAML),
// checked by the same rules and with the same reasons as in a file
// (run-time configuration, the state-dir overlay). `source` starts the
// messages ("request body", a file name); `lines`: whether they name the
// line; relative eds/dcf names resolve against `dir`. Throws ConfigError.
NodeConfig parse_node_config(std::string_view text, const std::string& source, const std::string& dir,
                             bool lines = true);
// The built-in EDS of a demo node, as its settings name it.
inline constexpr std::string_view kBuiltInEds = "(built in)";
// One `nodes:` entry from JSON (a PUT .../config body or a state-dir
// overlay file), checked by parse_node_config(); on a simulated network
// (`net`) `"eds": "(built in)"` names the demo's own description.
// `source`/`lines`/`dir` as parse_node_config(). Throws ConfigError.
NodeConfig node_config_from_json(const boost::json::value& settings, const NetworkConfig& net,
                                 const std::string& source, const std::string& dir, bool lines);
// A PUT .../nodes/{node}/config body (a JSON object of one `nodes:` entry;
// "id" may be left out: the path's node) as node_config_from_json() reads
// it for network `net`, relative file names against the directory of
// `config_file` (the configuration file; "" = none). Throws ConfigError
// ("request body: ...").
NodeConfig node_config_from_request(boost::json::value body, std::uint8_t node, const NetworkConfig& net,
                                    const std::string& config_file);
// `n` as the keys of its `nodes:` entry (parse_node_config() reads it back
// to the same NodeConfig): id, name, eds, heartbeat-consumer-ms ("auto" or
// ms), guarding, boot, sparkplug-metrics; absent keys are the defaults.
boost::json::object node_config_json(const NodeConfig& n);
// Reads and parses a file. Throws ConfigError.
Config load_config(const std::string& file);
// Applies the command line on top (flags win) and checks the result as a
// whole (at least one network, unique interfaces and node-IDs, EDS files
// exist). --demo turns authentication off only on a loopback listener
// without tokens (api-contract); otherwise the normal rules apply. Throws
// ConfigError (or UsageError for flag problems).
Config merge(Config base, const CliOptions& cli);
// Start-up check of the directories the gateway writes (merge()d config):
// state_dir always, mqtt.queue_dir with MQTT on. Creates them if missing and
// creates and removes a file in each. Throws ConfigError naming the key,
// where it came from (file:line, flag, environment or default), the
// directory and the reason. A full file system passes (ENOSPC: the gateway
// runs on and drops by its policy). Call before anything listens or opens
// CAN.
void check_state_dirs(const Config& c);
// The host name, sanitised into an MQTT topic level.
std::string default_gateway_id();

}  // namespace gateway
