// The gateway process minus main(): every configured network (SocketCAN or
// the simulated demo bus) with the gateway's own CANopen device on it and
// the master-side services watching the other nodes, the event pipeline,
// and the outputs (log, MQTT, WebSocket). Requests from MQTT (and REST) come
// in through handle_request().
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
#include "auth.hpp"
#include "canopen/sdo/client.hpp"
#include "config.hpp"
#include "request_codec.hpp"
#include "event_encoder.hpp"
#include "event_message.hpp"
#include "log.hpp"
#include "pipeline.hpp"
#include "requests.hpp"
#include "state_cache.hpp"

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

namespace gateway {

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

  // Boot-up of the own node on every network, simulated devices, MQTT.
  void start();
  // Each network's last event (bus `down`); MQTT: what is queued and the
  // window allows, the retained node states deleted, the offline status
  // with the stop time and uptime (publisher.hpp, Farewell); CAN closed;
  // each network's seq stored exactly (config.state_dir). Blocks the io
  // thread up to 2 s for MQTT. Afterwards the io_context runs out of work.
  void stop();

  // SDO read/write and NMT requests (REST and MQTT). The reply comes
  // later, on the io thread, exactly once. A request that is not
  // `authenticated` (MQTT) is identified by its token (config: http.tokens,
  // mqtt.requests-role without one) and rate-limited per caller with
  // http.rate-limit's numbers (429); every request's role is checked
  // against auth::required_role (401/403, with an audit line). A caller
  // (ApiRequest::caller) may have at most auth::caller_share(SDO queue
  // limit) SDO requests queued or running per node (429 with Retry-After
  // beyond that), so one caller cannot lock the others out of a node.
  void handle_request(const ApiRequest& request, ReplyFn reply);

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
  // Frame counters of network `net`'s channel (for /metrics).
  std::optional<canopen::can::ChannelStats> channel_stats(std::uint32_t net) const;
  // The MQTT publisher's counters; nullopt when MQTT is off.
  struct MqttCounters {
    bool connected = false;
    std::uint64_t published = 0, acked = 0, dropped = 0, queue_depth = 0, queue_bytes = 0, reconnects = 0;
    std::uint64_t requests_refused = 0;  // dropped unanswered for their reply address
    // Storage (mqtt/outbound_queue.hpp, disk_queue.hpp).
    std::uint64_t memory_depth = 0;      // messages waiting in memory
    std::uint64_t spilled = 0;           // `outage` messages written to disk (broker away, memory full)
    std::uint64_t storage_bytes = 0;     // bytes the queue wrote to its files
    std::uint64_t storage_syncs = 0;     // its fdatasync calls
    std::uint64_t storage_errors = 0;    // failed writes
    bool storage_failing = false;        // writes failing now (disk full)
    std::uint64_t corrupt_records = 0;   // skipped as corrupt at start
    std::uint64_t corrupt_bytes = 0;
    std::uint64_t stalls = 0;            // delivery restarts by the stall detector
    std::map<std::string, std::uint64_t> dropped_by_reason;  // "storage_full" -> n
  };
  std::optional<MqttCounters> mqtt_counters() const;
  // Process data to `node`'s RPDO `number` (COB-ID and mapping from its
  // EDS/DCF): either values (typed as mapped) or raw bytes (exactly the
  // mapped length). Errors as PdoTransmitter::set_values/set_raw
  // (NoSuchObject: no such network, node or RPDO). On success `sent`
  // (optional) gets the PDO's payload after the write. Audited as done by
  // `who` ("" = anonymous).
  std::error_code write_rpdo(std::uint32_t net, std::uint8_t node, std::uint16_t number,
                             std::span<const canopen::MappedValue> values, const canopen::Bytes* raw,
                             canopen::Bytes* sent = nullptr, std::string_view who = {});
  // The PDO configuration the gateway uses for the described nodes of
  // network `net` (canopen::Network::pdo_config(): EDS/DCF, then what its
  // SDO writes changed and what was read from the devices); nullptr for an
  // unknown network.
  const canopen::pdo::RemotePdoTable* pdo_config(std::uint32_t net) const;
  // The configuration `node`'s RPDO `number` is produced with now; nullptr
  // when it is not produced (unknown, disabled by COB-ID bit 31, or its
  // mapping does not resolve). Valid until the next event on the io thread.
  const canopen::pdo::PdoConfig* rpdo_config(std::uint32_t net, std::uint8_t node, std::uint16_t number) const;
  // Reads `node`'s PDO configuration from the device by SDO
  // (canopen::Network::read_pdo_config); the decoder and producer follow,
  // then `done` runs once on the io thread. Errors (done not called):
  // SdoAbort::NoSuchObject for an unknown network or a node without
  // EDS/DCF, SdoAbort::NoSdoConnection when its SDO queue is full.
  // Audited as done by `who` ("" = anonymous).
  std::error_code read_pdo_config(std::uint32_t net, std::uint8_t node,
                                  std::function<void(const canopen::pdo::PdoReadReport&)> done,
                                  std::string_view who = {});
  // Sends one SYNC (with the counter when given) on network `net` and
  // delivers it to the gateway's own services (synchronous RPDOs). False
  // for an unknown network. Audited as done by `who` ("" = anonymous).
  bool send_sync(std::uint32_t net, std::optional<std::uint8_t> counter, std::string_view who = {});
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

  struct Counters {
    std::uint64_t sdo_requests = 0;
    std::uint64_t sdo_aborts = 0;
    std::uint64_t sdo_timeouts = 0;
    std::uint64_t nmt_commands = 0;
    std::uint64_t auth_failures = 0;  // requests refused with 401/403 here (MQTT, NMT resets)
    std::uint64_t sdo_share_refused = 0;   // 429: the caller held its share of the node's SDO queue
    std::uint64_t requests_rate_limited = 0;  // 429: an MQTT caller over the rate limit
    // SDO transfers on the bus, submit to result (queueing included), as a
    // Prometheus histogram: count per upper bound (seconds; not cumulative),
    // the last slot for slower ones.
    static constexpr std::array<double, 12> kSdoLatencyBounds = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025,
                                                                 0.05,   0.1,   0.25,   0.5,   1.0,  2.5};
    std::array<std::uint64_t, kSdoLatencyBounds.size() + 1> sdo_latency_counts{};
    double sdo_latency_sum = 0;  // seconds
    std::uint64_t sdo_latency_count = 0;
  };
  const Counters& counters() const { return counters_; }

 private:
  using Net = NetworkUnit;
  Net* net(std::uint32_t number);
  // Hooks a built network up to the pipeline, the logs and the state cache.
  void attach(Net& net);
  void on_stack_event(Net& net, const canopen::Event& ev);
  void log_bus_event(const Net& net, const canopen::can::BusEvent& ev);
  void log_event(const Net& net, const canopen::Event& ev);
  void sdo_read(Net& net, const ApiRequest& req, ReplyFn reply);
  void sdo_write(Net& net, const ApiRequest& req, ReplyFn reply);
  void nmt(Net& net, const ApiRequest& req, ReplyFn reply);
  // The 401/403 reply (and audit line) when req.role may not do what needs
  // `need`; nullopt when it may.
  std::optional<ApiReply> refused(const Net& net, const ApiRequest& req, Role need, std::string_view what,
                                  const ReplyOptions& opts);
  // Writes one audit line ("audit: <line>", UTC time stamped, flushed at once).
  void audit(const std::string& line);
  // Records one finished SDO transfer's latency.
  void sdo_finished(std::chrono::steady_clock::time_point submitted_at);
  // A failed SDO transfer: counted, and turned into its reply (422/504/502).
  ApiReply transfer_failed(const canopen::sdo::TransferResult& res, const ReplyOptions& opts);
  // After submitting an SDO transfer: 429 when the node's queue was full,
  // else the driver follows the new deadline.
  void submitted(Net& net, const canopen::Result<canopen::sdo::RequestId>& id, std::uint8_t node,
                 const std::string& caller, const ReplyOptions& opts, const ReplyFn& reply);
  // Takes a place of the node's SDO queue for req.caller: the 429 reply
  // when the caller holds its share. Every place taken MUST be given back
  // once the request leaves the queue (sdo_place_freed), or when the
  // queue refuses it (submitted).
  std::optional<ApiReply> take_sdo_place(const Net& net, const ApiRequest& req, const ReplyOptions& opts);
  void sdo_place_freed(std::uint32_t net, std::uint8_t node, const std::string& caller);
  void start_mqtt();
  // The gateway status (MQTT payload format) as of now: time and uptime.
  std::string status_payload(bool online) const;

  boost::asio::io_context& io_;
  Config config_;
  Logger& log_;
  auth::TokenStore tokens_;
  auth::RateLimiter request_limiter_;  // MQTT requests, per caller (REST: the HTTP authorizer's)
  auth::QueueShares sdo_shares_;       // per network/node SDO queue, per caller
  EncodeContext encode_ctx_;
  std::function<bool()> protobuf_demand_;
  StateCache cache_;
  EventPipeline pipeline_;
  std::shared_ptr<canopen::socketcan::LinkMonitor> monitor_;  // interface up/down, shared by networks
  std::vector<std::unique_ptr<Net>> nets_;
  struct Mqtt;
  std::unique_ptr<Mqtt> mqtt_;
  Counters counters_;
  std::chrono::steady_clock::time_point started_at_ = std::chrono::steady_clock::now();
  bool started_ = false;
  bool stopped_ = false;
};

}  // namespace gateway
