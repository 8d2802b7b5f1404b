// The gateway minus its front ends: every configured network (SocketCAN or
// the simulated demo bus) with the gateway's own CANopen device on it and
// the master-side services watching the other nodes, the event pipeline,
// and the outputs (log, MQTT, Sparkplug, extra consumers such as the
// WebSocket stream). Requests from every front end are executed by its
// request core (requests(), core/request_core.hpp); what they may read
// besides is status() (status/view.hpp). Front ends are made from those two
// in front_ends.hpp; only app/ and main.cpp include this header, and tests.
//
// Thread safety: everything runs on the one io_context given to the
// constructor; call every method from that thread.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <boost/asio/io_context.hpp>

#include "canopen/can/bus_state.hpp"
#include "canopen/can/channel.hpp"
#include "auth/auth.hpp"
#include "canopen/sdo/client.hpp"
#include "config/config.hpp"
#include "core/request_core.hpp"
#include "messages/event_encoder.hpp"
#include "event_message.hpp"
#include "history/value_history.hpp"
#include "log.hpp"
#include "pipeline/pipeline.hpp"
#include "metrics/registry.hpp"
#include "pipeline/state_cache.hpp"
#include "status/view.hpp"

namespace canopen::eds {
struct DeviceDescription;
}

namespace canopen::od {
class ObjectDictionary;
}

namespace canopen::socketcan {
class LinkMonitor;
}

namespace canopen::can {
class MemoryBus;
}

namespace canopen::sim {
class Simulator;
}

namespace canopen::pdo {
class RemotePdoTable;
struct PdoConfig;
struct PdoReadReport;
}

namespace gateway::mqtt {
class MqttPublisher;
class MqttRequests;
}

namespace gateway::trace {
class NetworkTrace;
}

namespace gateway {

class AppStatus;
class MqttOutput;
class StackOutput;
struct Composition;
struct NetworkUnit;

class App {
 public:
  // Runs on the networks the composition root built for `config`
  // (compose_networks(), composition.hpp), one unit per network in order.
  App(boost::asio::io_context& io, Config config, Logger& log, Composition networks);
  // Builds the networks itself with compose_networks(): throws what it
  // throws (ConfigError for a bad EDS/DCF, socketcan::CanUnavailable).
  App(boost::asio::io_context& io, Config config, Logger& log);
  ~App();
  App(const App&) = delete;
  App& operator=(const App&) = delete;

  // Boot-up of the own node on every network, simulated devices, MQTT,
  // the Sparkplug edge node.
  void start();
  // Each network's last event (bus `down`); MQTT: what is queued and the
  // window allows, the retained node states deleted, the offline status
  // with the stop time and uptime (mqtt_output.hpp); CAN closed;
  // each network's seq stored exactly (config.state_dir). Sparkplug:
  // NDEATH and DISCONNECT while the networks still run. Blocks the io
  // thread up to 2 s each for MQTT and Sparkplug. Afterwards the io_context runs out of work.
  void stop();

  // The request core over this App's networks (REST and MQTT requests):
  // callers without a token of their transport are identified by
  // http.tokens (mqtt.requests-role without one) and rate-limited with
  // http.rate-limit's numbers; audit lines go to the log.
  core::RequestCore& requests() { return core_; }

  // The MQTT request front end (front_ends.hpp: serve_mqtt_requests): the
  // MQTT output's session subscribes to the request topics and hands their
  // PUBLISHes to it, and sends its replies. Before start(); ignored with
  // MQTT off. Without one, requests over MQTT are not served.
  void serve_mqtt_requests(std::unique_ptr<mqtt::MqttRequests> requests);

  // An output fed the stack's events typed, started after MQTT and stopped
  // before it (pipeline/stack_output.hpp; the Sparkplug B edge node,
  // front_ends.hpp: add_sparkplug). Before start(); the App owns it.
  void add_output(std::unique_ptr<StackOutput> output);
  // What the status view's sparkplug() answers (front_ends.hpp:
  // add_sparkplug); what `read` refers to MUST live as long as the App.
  void set_sparkplug_status(std::function<std::optional<status::SparkplugStatus>()> read) {
    sparkplug_status_ = std::move(read);
  }

  // Extra consumer of every outgoing event (e.g. the WebSocket hub).
  void add_consumer(EventPipeline::Consumer c) { pipeline_.add_consumer(std::move(c)); }
  // Whether an extra consumer wants protobuf payloads now (e.g. a WebSocket
  // client that asked for them); asked for every event, so it must be cheap.
  // Without it (and with MQTT in JSON) PDO events are encoded as JSON only.
  void set_protobuf_demand(std::function<bool()> demand) { protobuf_demand_ = std::move(demand); }

  const Config& config() const { return config_; }
  // The bearer tokens of the config.
  const auth::TokenStore& tokens() const { return tokens_; }
  // The HTTP server's authorizer for this configuration (http.auth, its
  // tokens, the role without one, the rate limit). It refers to this App's
  // tokens and logger: the App MUST outlive the server's use of it.
  http::Authorizer http_authorizer();
  const StateCache& cache() const { return cache_; }
  const EventPipeline& pipeline() const { return pipeline_; }
  // The node's EDS/DCF on network `net`, if configured.
  const canopen::eds::DeviceDescription* description(std::uint32_t net, std::uint8_t node) const;
  std::chrono::steady_clock::time_point started_at() const { return started_at_; }
  // The gateway's version (CANOPEN_GATEWAY_VERSION).
  static std::string_view version();

  // The gateway's own dictionary on network `net` (its communication
  // parameters as they are now: SDO writes and NMT resets change them);
  // nullptr for an unknown network.
  const canopen::od::ObjectDictionary* own_dictionary(std::uint32_t net) const;
  // The NMT state of the gateway's own node on network `net` (NMT commands
  // to all nodes or to its node-ID change it); nullopt for an unknown network.
  std::optional<canopen::NmtState> own_state(std::uint32_t net) const;
  // The bus state of network `net` as its channel reports it now; nullopt
  // for an unknown network.
  std::optional<canopen::can::BusState> bus_state(std::uint32_t net) const;
  // The frame tap of network `net` (issue 18: trace WebSocket, capture
  // ring, bus load); null for an unknown network. Holders that may outlive
  // the App (WebSocket sessions) keep it as a weak_ptr.
  std::shared_ptr<trace::NetworkTrace> frame_tap(std::uint32_t net);
  // The TPDO value history (issue 18, GET .../nodes/{node}/history); nullptr
  // when history.max-bytes is 0.
  const history::ValueHistory* value_history() const { return config_.history.max_bytes ? &history_ : nullptr; }
  // The io_context everything runs on (timers of request handlers).
  boost::asio::io_context& io() { return io_; }
  // Frame counters of network `net`'s channel (for /metrics).
  std::optional<canopen::can::ChannelStats> channel_stats(std::uint32_t net) const;
  // The MQTT publisher (e.g. tests: its counters); nullptr when MQTT is off
  // or before start().
  const mqtt::MqttPublisher* mqtt_publisher() const;
  // The Sparkplug B edge node's session (GET /api/v1/gateway) as the
  // function set_sparkplug_status() was given reads it; nullopt without one.
  std::optional<status::SparkplugStatus> sparkplug_status() const;
  // The native MQTT connection; nullopt with MQTT off.
  std::optional<status::MqttStatus> mqtt_status() const;
  // The PDO configuration the gateway uses for the described nodes of
  // network `net` (canopen::Network::pdo_config(): EDS/DCF, then what its
  // SDO writes changed and what was read from the devices); nullptr for an
  // unknown network.
  const canopen::pdo::RemotePdoTable* pdo_config(std::uint32_t net) const;
  // The configuration `node`'s RPDO `number` is produced with now; nullptr
  // when it is not produced (unknown, disabled by COB-ID bit 31, or its
  // mapping does not resolve). Valid until the next event on the io thread.
  const canopen::pdo::PdoConfig* rpdo_config(std::uint32_t net, std::uint8_t node, std::uint16_t number) const;
  // A simulated network only: takes the gateway's side of the in-process
  // bus down or up, as an interface going down would (demos, tests). False
  // for an unknown or real network.
  bool set_simulated_link(std::uint32_t net, bool up);
  // A simulated network only: its in-process bus, e.g. for tests to watch
  // or disturb its frames (can::BusFaults). nullptr for an unknown or real
  // network.
  canopen::can::MemoryBus* simulated_bus(std::uint32_t net);
  // A simulated network's devices (tests: e.g. a device whose stored
  // configuration differs from its EDS, before start()); nullptr for an
  // unknown or real network.
  canopen::sim::Simulator* simulator(std::uint32_t net);

  // Where a configured node's settings come from (GET /api/v1/gateway).
  using NodeOrigin = gateway::status::NodeOrigin;
  // The configured nodes of network `net` in node-ID order; empty for an unknown network.
  std::vector<NodeOrigin> node_origins(std::uint32_t net) const;
  // Their settings as they apply now, in configuration order (status/view.hpp).
  std::vector<NodeConfig> configured_nodes(std::uint32_t net) const;

  // The request counters and SDO latency histogram (GET /api/v1/gateway).
  using Counters = core::Counters;
  const Counters& counters() const { return core_.counters(); }

  // The process's metrics (/metrics). The App's components registered
  // their families when it was built, in the order /metrics writes them:
  // build info, the networks, the request core, events by kind, MQTT. The
  // HTTP server and the uptime follow (install_http_api()). Render
  // and register on the io thread only; the App MUST outlive every render().
  metrics::Registry& metrics() { return metrics_; }

  // What the front ends may read besides the request core (status/view.hpp):
  // the accessors above, read-only. Valid as long as the App.
  const gateway::status::View& status() const;

 private:
  using Net = NetworkUnit;
  Net* net(std::uint32_t number);
  // Hooks a built network up to the pipeline, the logs and the state cache.
  void attach(Net& net);
  void on_stack_event(Net& net, const canopen::Event& ev);
  void log_bus_event(const Net& net, const canopen::can::BusEvent& ev);
  void log_event(const Net& net, const canopen::Event& ev);
  // Writes one audit line ("audit: <line>", UTC time stamped, flushed at once).
  void audit(const std::string& line);
  // The request core's view of the networks (core::Networks, core_networks.cpp).
  struct CoreNetworks;
  static std::unique_ptr<core::Networks> make_core_networks(App& app);
  // Run-time node configuration for the request core (core::NodeSettings,
  // node_config.cpp): applies to the units, keeps in state-dir.
  struct NodeConfigs;

  boost::asio::io_context& io_;
  Config config_;
  Logger& log_;
  auth::TokenStore tokens_;
  metrics::Registry metrics_;
  // Declared before nets_: SDO transfers that end while the networks are
  // torn down still find the core.
  std::unique_ptr<core::Networks> core_networks_;
  std::unique_ptr<NodeConfigs> node_configs_;
  core::RequestCore core_;
  EncodeContext encode_ctx_;
  std::function<bool()> protobuf_demand_;
  StateCache cache_;
  EventPipeline pipeline_;
  history::ValueHistory history_;  // fed by on_stack_event
  std::shared_ptr<canopen::socketcan::LinkMonitor> monitor_;  // interface up/down, shared by networks
  std::vector<std::unique_ptr<Net>> nets_;
  std::chrono::steady_clock::time_point started_at_ = std::chrono::steady_clock::now();
  std::unique_ptr<MqttOutput> mqtt_;  // with MQTT on (config.mqtt.enabled)
  // Outputs of their own (the Sparkplug B edge node): started after MQTT,
  // stopped before it, while the networks still run.
  std::vector<std::unique_ptr<StackOutput>> outputs_;
  std::function<std::optional<status::SparkplugStatus>()> sparkplug_status_;
  std::unique_ptr<AppStatus> status_;  // over this App's accessors
  bool started_ = false;
  bool stopped_ = false;
};

}  // namespace gateway
