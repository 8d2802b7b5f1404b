// One node's settings, typed: the keys of one `nodes:` entry of the
// configuration file (deploy/gateway.example.yaml), which is also what the
// run-time configuration (contract "Remote configuration and maintenance",
// PUT .../nodes/{node}/config) takes and answers. The YAML/JSON text is a
// wire format: config/ reads and writes it (parse_node_config,
// node_config_json); the request core and the App see only these structs.
//
// Pure data; thread-safe.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace gateway {

struct GuardingConfig {
  std::chrono::milliseconds guard_time{0};  // 100Ch of the node; 0 = no guarding
  std::uint8_t life_time_factor = 0;        // 100Dh
};

// Boot-up handling of one node in the spirit of CiA 302 (master/boot_configurator.hpp).
struct BootConfig {
  bool check_identity = true;  // compare 1000h/1018h with the EDS/DCF
  bool configure = false;      // write the DCF's PDO, heartbeat and ParameterValue entries
  bool start = false;          // NMT start once configured
  // Read the node's PDO configuration (1400h-1BFFh) from the device after
  // the identity check and DCF download, before the NMT start, so its real
  // mapping wins over the EDS (Network::configure_boot). nullopt: the
  // network's setting.
  std::optional<bool> read_pdo_config;
};

// An object listed in a node's `sparkplug-metrics` ("2300h", "6060h:0"):
// read by SDO for the node's Sparkplug DBIRTH. No sub-index: every
// sub-object of a record/array in the EDS (sub 0 for a variable).
struct SparkplugObject {
  std::uint16_t index = 0;
  std::optional<std::uint8_t> sub;
  friend bool operator==(const SparkplugObject&, const SparkplugObject&) = default;
};

struct NodeConfig {
  std::uint8_t id = 0;
  std::string name;     // optional; shown in the API and dashboard
  std::string eds;      // EDS or DCF file ("" = none: values arrive raw)
  // heartbeat-consumer-ms. nullopt ("auto", the default): watched anyway,
  // lost after 3 x P without a heartbeat, P the node's 1017h from its
  // EDS/DCF or else learnt from its heartbeats. 0: not watched. Otherwise
  // the gateway's 1016h consumer time for the node.
  std::optional<std::chrono::milliseconds> heartbeat_consumer;
  GuardingConfig guarding;
  std::optional<BootConfig> boot;  // nullopt: only watch the node
  std::vector<SparkplugObject> sparkplug_metrics;  // contract "Sparkplug B"
};

}  // namespace gateway
