// The request core: executes one typed Request (request.hpp) from any
// front end and answers with exactly one Result. Everything every front end
// needs happens here, once:
//   - a caller the transport did not check (MQTT) is identified from its
//     token (auth::identify; without one: Settings::anonymous_role) and
//     rate-limited per caller (429 + Retry-After), before anything is
//     logged or done, so a flood of bad tokens is limited too;
//   - the address: the network must exist (404), the node be 1..127 (0 for
//     NMT only; 400), the bus up when the request asks (503);
//   - the role the command needs (required_role; 401/403, with an audit line);
//   - a caller may hold at most auth::caller_share(queue limit) places of a
//     node's SDO queue (429 + Retry-After beyond that), so one caller cannot
//     lock the others out of a node;
//   - SDO semantics: the type (as asked, else the EDS/DCF's, else DOMAIN),
//     values typed and checked against the EDS/DCF limits before anything
//     goes on the bus, the gateway's own node answered from its dictionary;
//   - audit lines for every write, NMT command, SYNC, PDO read and LSS
//     operation, and for every refusal by role;
//   - LSS (CiA 305): one operation per network at a time (409 otherwise),
//     multi-step ones (configure, assign-all, fastscan) as a sequence of
//     single services that ends with all slaves back in waiting state, also
//     after a failure; the last scan's finds kept per network;
//   - remote maintenance (DCF read-back/apply, store/restore, program
//     download): one per node at a time (409), audited, counted;
//   - counters and the SDO latency histogram (/metrics).
// The core reaches the CAN side only through Networks, which the process
// (App) implements over its networks and tests fake.
//
// Thread safety: one io thread. execute() and every Networks call run on
// it; `done` is called exactly once on it, at once for a refusal or later
// (an SDO transfer takes time), never from inside another thread.
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
#include <system_error>
#include <variant>
#include <vector>

#include "auth/auth.hpp"
#include "canopen/can/bus_state.hpp"
#include "canopen/result.hpp"
#include "canopen/sdo/client.hpp"
#include "core/request.hpp"

namespace canopen::eds {
struct DeviceDescription;
}

namespace canopen::od {
class ObjectDictionary;
}

namespace canopen::pdo {
struct PdoConfig;
}

namespace gateway::core {

class NodeSettings;

// One LSS service (CiA 305) as the core asks the network's LSS master for it.
using LssStep = std::variant<LssSwitchGlobal, LssSwitchSelective, LssSetNodeId, LssSetBitTiming,
                             LssActivateBitTiming, LssStore, LssInquiry, LssFastscan>;

// How an LssStep ended.
struct LssOutcome {
  enum class Status : std::uint8_t {
    ok,          // done (an unconfirmed service: sent)
    timeout,     // a confirmed service got no answer in time
    none_found,  // fastscan: no unconfigured device answered
    refused,     // the slave answered with an error code
    failed,      // a local failure (the detail says which)
  };
  Status status = Status::ok;
  std::uint8_t error = 0;     // refused: the slave's error code
  std::uint32_t value = 0;    // an inquiry's answer
  LssAddress address;         // fastscan: the device found
  std::string detail;         // failed: why; refused with FFh: the manufacturer-specific code
};

// How a DCF read-back, a DCF apply or a program download (the network's
// services for a node, canopen::Network) ended. One shape for the three;
// each fills what it has.
struct TransferOutcome {
  // Empty: done (a DCF read-back or apply also when single objects failed:
  // see `objects`). Otherwise what stopped it: an SDO abort code (see
  // `remote`), std::errc::device_or_resource_busy (another transfer runs for
  // the node), std::errc::invalid_argument (nothing to read or write: the
  // EDS/DCF lists no such object), or another code with `detail`.
  std::error_code error;
  bool remote = false;  // `error` is the device's abort (else the gateway's)
  std::string step;     // program download: the step that failed ("stop program (1F51h sub 1)", ...)
  std::string detail;
  std::string text;     // DCF read-back: the DCF
  std::size_t read = 0;  // DCF read-back: objects read
  // DCF read-back: the objects that aborted; DCF apply: every object
  // written, in order, with its outcome.
  std::vector<ObjectOutcome> objects;
  bool stored = false;  // DCF apply: 1010h sub 1 "save" confirmed
  std::optional<ObjectOutcome> store_error;  // DCF apply: the save was refused
  bool reset = false;   // DCF apply: NMT reset node sent
  std::size_t bytes = 0;                        // program download: the image's size
  std::optional<std::uint32_t> identification;  // program download: 1F56h sub n, where the device has it
};
using TransferDone = std::function<void(TransferOutcome)>;

// The CAN side as the core needs it. Networks are numbered 1..count(). The
// core calls only with a network in that range. Implementations let the
// services follow what they are asked (new timer deadlines) themselves.
class Networks {
 public:
  virtual ~Networks() = default;
  virtual std::uint32_t count() const = 0;
  // The gateway's own node-ID on `net`: SDO requests to it are answered by
  // its own dictionary (its socket does not hear its own requests).
  virtual std::uint8_t own_node_id(std::uint32_t net) const = 0;
  virtual const canopen::od::ObjectDictionary& own_dictionary(std::uint32_t net) const = 0;
  // A write to the own dictionary as an SDO download would do it (access,
  // length and limit checks, hooks and observers).
  virtual std::error_code write_own(std::uint32_t net, std::uint16_t index, std::uint8_t sub,
                                    std::span<const std::uint8_t> data) = 0;
  // The node's EDS/DCF; nullptr when none is configured.
  virtual const canopen::eds::DeviceDescription* description(std::uint32_t net, std::uint8_t node) const = 0;
  virtual std::optional<canopen::can::BusState> bus_state(std::uint32_t net) const = 0;
  // SDO transfers (canopen::sdo::SdoClient::upload/download); an error when
  // the node's queue is full (request.on_done then never runs).
  virtual canopen::Result<canopen::sdo::RequestId> sdo_upload(std::uint32_t net, canopen::sdo::Request request) = 0;
  virtual canopen::Result<canopen::sdo::RequestId> sdo_download(std::uint32_t net, canopen::sdo::Request request,
                                                                canopen::Bytes data) = 0;
  virtual void send_nmt(std::uint32_t net, canopen::NmtCommand command, std::uint8_t node) = 0;
  // The configuration `node`'s RPDO `number` is produced with now; nullptr
  // when it is not produced. Valid until the next event on the io thread.
  virtual const canopen::pdo::PdoConfig* rpdo_config(std::uint32_t net, std::uint8_t node,
                                                     std::uint16_t number) const = 0;
  // Errors as PdoTransmitter::set_values/set_raw. On success `sent` gets the
  // PDO's payload after the write.
  virtual std::error_code write_rpdo(std::uint32_t net, std::uint8_t node, std::uint16_t number,
                                     std::span<const canopen::MappedValue> values, const canopen::Bytes* raw,
                                     canopen::Bytes& sent) = 0;
  // One SYNC on the bus, also delivered to the gateway's own services.
  virtual void send_sync(std::uint32_t net, std::optional<std::uint8_t> counter) = 0;
  // Whether the node's PDOs are decoded (it has an EDS/DCF).
  virtual bool has_pdo_table(std::uint32_t net, std::uint8_t node) const = 0;
  // canopen::Network::read_pdo_config; `done` runs once, later, unless an
  // error is returned.
  virtual std::error_code read_pdo_config(std::uint32_t net, std::uint8_t node,
                                          std::function<void(const canopen::pdo::PdoReadReport&)> done) = 0;
  // One LSS service on `net`'s LSS master; `done` runs once, later (a
  // confirmed service on the answer or timeout, an unconfirmed one once
  // sent), unless an error is returned. The core sends one at a time per
  // network and waits for `done` before the next.
  virtual std::error_code lss(std::uint32_t net, const LssStep& step, std::function<void(const LssOutcome&)> done) = 0;
  // Whether `node` is taken on `net` (the gateway's own, configured, or
  // heard): LssAssignAll skips it.
  virtual bool node_in_use(std::uint32_t net, std::uint8_t node) const = 0;
  // Remote maintenance of `node` (canopen::Network's services; each goes
  // through the node's SDO queue and reports progress as `transfer` events
  // in the network's event stream). `done` runs once, later, unless an error
  // is returned (busy: std::errc::device_or_resource_busy; the node's queue
  // full: SdoAbort::NoSdoConnection).
  // DCF read-back of the node's configurable objects (its EDS/DCF's).
  virtual std::error_code dcf_read(std::uint32_t net, std::uint8_t node, TransferDone done) = 0;
  // Writes `dcf`'s values in the boot-up configurator's order (`dcf` is
  // not kept after the call), then stores (1010h sub 1 "save") and resets
  // the node as asked (the reset only after a successful save, or with no
  // save asked).
  virtual std::error_code dcf_apply(std::uint32_t net, std::uint8_t node, const canopen::eds::DeviceDescription& dcf,
                                    bool store, bool reset, TransferDone done) = 0;
  // CiA 302-3 program download of `image` to 1F50h sub `program`.
  virtual std::error_code program_download(std::uint32_t net, std::uint8_t node, std::uint8_t program,
                                           canopen::Bytes image, TransferDone done) = 0;
  // The time for the rate limit and the SDO latency histogram.
  virtual std::chrono::steady_clock::time_point now() const { return std::chrono::steady_clock::now(); }
};

struct Counters {
  std::uint64_t sdo_requests = 0;
  std::uint64_t sdo_aborts = 0;
  std::uint64_t sdo_timeouts = 0;
  std::uint64_t nmt_commands = 0;
  std::uint64_t auth_failures = 0;          // requests refused with 401/403 here (MQTT, NMT resets)
  std::uint64_t sdo_share_refused = 0;      // 429: the caller held its share of the node's SDO queue
  std::uint64_t requests_rate_limited = 0;  // 429: an unchecked (MQTT) caller over the rate limit
  // LSS operations (one per request) by how they ended, and node-IDs given.
  std::uint64_t lss_ok = 0, lss_timeouts = 0, lss_refused = 0, lss_none_found = 0, lss_busy = 0, lss_failed = 0;
  std::uint64_t lss_assigned = 0;
  // Maintenance operations (contract "Remote configuration and
  // maintenance") by kind and how they ended: ok, failed (the device or the
  // transfer), busy (409: another transfer ran for the node).
  enum MaintenanceKind : std::uint8_t { dcf_read, dcf_apply, store, restore, program_download, kMaintenanceKinds };
  enum MaintenanceResult : std::uint8_t { ok, failed, busy, kMaintenanceResults };
  std::array<std::array<std::uint64_t, kMaintenanceResults>, kMaintenanceKinds> maintenance{};
  // SDO transfers on the bus, submit to result (queueing included), as a
  // Prometheus histogram: count per upper bound (seconds; not cumulative),
  // the last slot for slower ones.
  static constexpr std::array<double, 12> kSdoLatencyBounds = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025,
                                                               0.05,   0.1,   0.25,   0.5,   1.0,  2.5};
  std::array<std::uint64_t, kSdoLatencyBounds.size() + 1> sdo_latency_counts{};
  double sdo_latency_sum = 0;  // seconds
  std::uint64_t sdo_latency_count = 0;
};

class RequestCore {
 public:
  struct Settings {
    Role anonymous_role = Role::None;  // unchecked callers without a token (mqtt.requests-role)
    double rate_limit = 0;             // unchecked callers: requests per second (0 = off)
    double rate_burst = 1;
    // Requests that may wait per node behind the running one (the SDO
    // client's ClientConfig::queue_limit).
    std::size_t sdo_queue_limit = canopen::sdo::ClientConfig{}.queue_limit;
  };
  using Done = std::function<void(Result)>;
  // Writes one audit line (the caller time-stamps and flushes it).
  using AuditSink = std::function<void(const std::string& line)>;

  // `networks` and `tokens` MUST outlive the core (and the SDO transfers it
  // started).
  RequestCore(Networks& networks, const auth::TokenStore& tokens, Settings settings, AuditSink audit);

  void execute(Request request, Done done);

  // Run-time node configuration (NodeConfigRead/Write, NodeEdsWrite) goes
  // to `settings` (node_settings.hpp), which MUST outlive the core; without
  // one those commands answer 500.
  void set_node_settings(NodeSettings* settings) { node_settings_ = settings; }

  const Counters& counters() const { return counters_; }
  // The per-caller share of each node's SDO queue.
  std::size_t sdo_share() const { return shares_.share(); }

 private:
  // One request on its way (shared by request_core.cpp and maintenance.cpp).
  struct Context {
    Caller caller;
    std::uint32_t network = 0;
    bool check_bus = false;
    Done done;
  };
  void sdo_read(Context& c, const SdoRead& cmd);
  void sdo_write(Context& c, const SdoWrite& cmd);
  void nmt(Context& c, const Nmt& cmd);
  void rpdo_write(Context& c, const RpdoWrite& cmd);
  void sync(Context& c, const Sync& cmd);
  void pdo_config_read(Context& c, const PdoConfigRead& cmd);
  // NodeConfigRead, NodeConfigWrite, NodeEdsWrite (node_config.cpp).
  void node_config(const Caller& caller, std::uint32_t net, const Command& cmd, const Done& done);
  // LSS: every LSS command; `lss_busy_` holds the network while one runs.
  void lss(Context& c, const Command& cmd);
  struct LssRun;
  void lss_next(std::shared_ptr<LssRun> run);
  void lss_finish(const std::shared_ptr<LssRun>& run, Result result);
  // Remote maintenance (maintenance.cpp): DCF read-back and apply, store and
  // restore, program download. One runs per node at a time (409 otherwise);
  // each holds one place of the caller's share of the node's SDO queue.
  void dcf_read(Context& c, const DcfRead& cmd);
  void dcf_apply(Context& c, const DcfApply& cmd);
  void node_store(Context& c, const NodeStore& cmd);
  void program_download(Context& c, ProgramDownload cmd);  // by value: the image moves on
  struct MaintenanceRun;
  std::optional<Problem> maintenance_start(const Context& c, std::uint8_t node, Counters::MaintenanceKind kind,
                                           const std::string& line);
  void maintenance_end(const MaintenanceRun& run, Result result, const std::string& outcome);
  // 401/403 (counted, audited) when the caller may not do what needs `need`.
  std::optional<Problem> refused(const Context& c, Role need, std::string_view what, std::uint8_t node,
                                 bool command_read);
  std::optional<Problem> bus_refused(const Context& c) const;
  // Takes a place of the node's SDO queue for the caller: the 429 when it
  // holds its share. Every place taken MUST be given back once the request
  // leaves the queue (place_freed), or when the queue refuses it.
  std::optional<Problem> take_sdo_place(const Context& c, std::uint8_t node);
  void place_freed(std::uint32_t net, std::uint8_t node, const std::string& key);
  // After submitting an SDO transfer: the 429 when the node's queue was full.
  std::optional<Problem> submitted(const Context& c, const canopen::Result<canopen::sdo::RequestId>& id,
                                   std::uint8_t node);
  void sdo_finished(std::chrono::steady_clock::time_point submitted_at);
  Problem transfer_failed(const canopen::sdo::TransferResult& res);

  Networks& net_;
  NodeSettings* node_settings_ = nullptr;
  const auth::TokenStore& tokens_;
  Settings settings_;
  AuditSink audit_;
  auth::RateLimiter limiter_;
  auth::QueueShares shares_;
  Counters counters_;
  std::map<std::uint32_t, bool> lss_busy_;                          // per network
  // Per network: a device (or all, switch global) is in LSS configuration
  // state by the gateway's last switch or fastscan (CiA 305: the
  // configuration services need one).
  std::map<std::uint32_t, bool> lss_selected_;
  std::map<std::uint32_t, std::vector<LssDeviceSeen>> lss_found_;  // per network: the last scan's finds
  std::map<std::uint64_t, bool> maintenance_busy_;                  // per sdo_queue_key: one transfer per node
};

}  // namespace gateway::core
