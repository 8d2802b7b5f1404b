// What the front ends (rest/, the WebSocket event stream, ascii/) may read of
// the running gateway besides the request core (core/request_core.hpp): a
// narrow, read-only status view. Requests go through the core; nothing here
// changes state. The App implements it (app/app_status.hpp), so a front end
// depends on this header, never on app/.
//
// Thread safety: call on the io_context thread (the App's); results that
// are pointers or references are valid until the next event on that thread
// unless said otherwise.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/can/bus_state.hpp"
#include "canopen/events.hpp"
#include "config/config.hpp"
#include "core/request_core.hpp"
#include "history/value_history.hpp"
#include "pipeline/state_cache.hpp"

namespace canopen::eds {
struct DeviceDescription;
}

namespace canopen::od {
class ObjectDictionary;
}

namespace canopen::pdo {
class RemotePdoTable;
}

namespace gateway::trace {
class NetworkTrace;
}

namespace gateway::status {

// Where a configured node's settings come from (GET /api/v1/gateway):
// "config" (the configuration file or flags; the demo's own), or
// "state-dir" (changed at run time) with the file that holds them.
struct NodeOrigin {
  std::uint8_t node = 0;
  std::string source;
  std::string file;
};

// The Sparkplug B edge node's session as GET /api/v1/gateway shows it.
struct SparkplugStatus {
  std::string group_id, edge_node_id;
  std::string state;  // sparkplug::state_name()
  bool connected = false;
  std::string broker;    // the connected broker (normalized URI), "" when none
  int mqtt_version = 0;  // 5 or 4 while connected
  std::optional<std::uint8_t> bd_seq;
  std::optional<std::uint64_t> last_rebirth_ms;  // Unix time
  std::string primary_host_id;                   // "" = none configured
  bool primary_host_online = false;
  std::uint64_t messages_published = 0;
  std::uint64_t commands_received = 0;
};

// The native MQTT connection as GET /api/v1/gateway shows it.
struct MqttStatus {
  bool connected = false;
  std::string broker;                // the connected broker (normalized URI), "" when none
  int mqtt_version = 0;              // 5 or 4 while connected
  std::vector<std::string> brokers;  // every configured broker, in the order they are tried
  std::uint64_t reconnects = 0;
};

class View {
 public:
  virtual ~View() = default;

  // ---- the gateway and its configuration
  // CANOPEN_GATEWAY_VERSION.
  virtual std::string_view version() const = 0;
  virtual const std::string& gateway_id() const = 0;
  virtual std::chrono::steady_clock::time_point started_at() const = 0;
  // The configured networks, numbered from 1 in this order.
  virtual const std::vector<NetworkConfig>& networks() const = 0;
  // The configuration file ("" = command line only): relative file names in
  // run-time node settings resolve against its directory, as in the file.
  virtual const std::string& config_file() const = 0;
  // http.max-program-bytes: the body limit of PUT .../program/{n}.
  virtual std::size_t max_program_bytes() const = 0;

  // ---- what the networks report
  // Every network's nodes, their latest values and EMCYs (pipeline/state_cache.hpp).
  virtual const StateCache& cache() const = 0;
  // The node's EDS/DCF on network `net`, if configured.
  virtual const canopen::eds::DeviceDescription* description(std::uint32_t net, std::uint8_t node) const = 0;
  // The gateway's own dictionary on `net` as it is now; nullptr for an unknown network.
  virtual const canopen::od::ObjectDictionary* own_dictionary(std::uint32_t net) const = 0;
  // The NMT state of the gateway's own node on `net`; nullopt for an unknown network.
  virtual std::optional<canopen::NmtState> own_state(std::uint32_t net) const = 0;
  // The bus state of `net` as its channel reports it now; nullopt for an unknown network.
  virtual std::optional<canopen::can::BusState> bus_state(std::uint32_t net) const = 0;
  // The configured nodes of `net` in node-ID order; empty for an unknown network.
  virtual std::vector<NodeOrigin> node_origins(std::uint32_t net) const = 0;
  // The settings of `net`'s configured nodes as they apply now (the file,
  // the state-dir overlay, run-time changes), in configuration order; empty
  // for an unknown network.
  virtual std::vector<NodeConfig> configured_nodes(std::uint32_t net) const = 0;
  // The PDO configuration in use for the described nodes of `net`; nullptr for an unknown network.
  virtual const canopen::pdo::RemotePdoTable* pdo_config(std::uint32_t net) const = 0;
  // The frame tap of `net` (trace WebSocket, capture ring, bus load); null
  // for an unknown network. Not status itself: trace clients subscribe to
  // it. Holders that may outlive the gateway keep it as a weak_ptr.
  virtual std::shared_ptr<trace::NetworkTrace> frame_tap(std::uint32_t net) const = 0;
  // The TPDO value history; nullptr when history.max-bytes is 0.
  virtual const history::ValueHistory* value_history() const = 0;

  // ---- counters and outputs
  // The request core's counters and SDO latency histogram.
  virtual const core::Counters& counters() const = 0;
  // The native MQTT connection; nullopt unless mqtt is enabled.
  virtual std::optional<MqttStatus> mqtt() const = 0;
  // The Sparkplug B edge node's session; nullopt unless sparkplug is enabled.
  virtual std::optional<SparkplugStatus> sparkplug() const = 0;
  // The process's metrics in the Prometheus text format (/metrics).
  virtual std::string metrics_text() const = 0;
};

}  // namespace gateway::status
