// Boot-up configuration of remote nodes, in the spirit of CiA 302-2: when a
// node reports boot-up, read its device type (1000h) and identity (1018h
// sub 1-4) over SDO, check them against the expected values, optionally
// write its configuration from a DCF, then start it with NMT.
//
// Sans-I/O: it only drives an SdoClient (which owns the timeouts) and calls
// send_nmt; it has no timer of its own. The caller MUST
//   - call on_boot_up(node, now) for every NodeStateEvent with cause BootUp
//     of a configured node (unconfigured nodes are ignored);
//   - keep feeding the SdoClient frames and time (its completion handlers
//     drive the sequence), and keep the SdoClient, and every DCF passed in
//     NodeBootConfig::dcf, alive as long as the configurator.
//
// Sequence and events (one BootConfigEvent per step):
//   Identify       reading 1000h and 1018h sub 1-4 starts. Sub 2-4 are
//                  optional unless an expected value is configured for
//                  them: an abort on one of them (not a timeout) is ignored.
//   CheckIdentity  the values read match the expected ones (detail lists them).
//   Configure      DCF writes start (only when dcf is set; see plan_configuration()).
//   Start          NMT start sent (only when start is true).
//   Done           the sequence ended successfully.
//   Failed         any step failed: error is the SDO abort (origin remote or
//                  local, e.g. SdoAbort::Timeout), or a BootError for an
//                  identity mismatch; detail names the object. Nothing more
//                  happens for that boot-up (no start).
// A boot-up during a running sequence cancels its SDO transfer and restarts
// the sequence from Identify.
//
// Nodes powered before the manager (CiA 302-2: the manager boots every
// assigned node at its own start, and whenever one appears without a
// boot-up): the caller calls on_found() when it first hears a configured
// node by heartbeat or guarding, or hears it again in another state after it
// was lost. Pre-operational: the whole sequence, as on a boot-up.
// Operational: the identity check only (no DCF writes, no NMT start; Done's
// detail says so): whoever started it configured it, and rewriting PDOs
// under a running machine would disturb it. Stopped: nothing
// (SDO is not available there). A sequence already running is left alone.
//
// Thread safety: none; use from the SdoClient's thread. on_event and
// send_nmt are called synchronously (from on_boot_up() and from the
// SdoClient's handlers) and may call back into the configurator.
// on_boot_up() never calls send_nmt itself, so it may be called from the
// NmtMaster's event sink while send_nmt uses NmtMaster::send_command.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/events.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/types.hpp"

namespace canopen::master {

// Identity check failures (CiA 302-2 boot-up error codes in parentheses).
enum class BootError : std::uint8_t {
  DeviceTypeMismatch = 1,  // (C) 1000h differs
  VendorIdMismatch,        // (D) 1018h sub 1
  ProductCodeMismatch,     // (M) 1018h sub 2
  RevisionMismatch,        // (N) 1018h sub 3
  SerialNumberMismatch,    // (O) 1018h sub 4
};
const std::error_category& boot_error_category();
std::error_code make_error_code(BootError e);

struct NodeBootConfig {
  // Expected values; nullopt: not checked.
  std::optional<std::uint32_t> device_type, vendor_id, product_code, revision, serial;
  // Write its configuration when set (see plan_configuration()). Must outlive the configurator.
  const eds::DeviceDescription* dcf = nullptr;
  bool start = true;  // send NMT start at the end
};

// Expected values taken from a DCF: 1000h and 1018h sub 1-4 as they stand
// in it (serial only when it differs from its default, i.e. the DCF names
// one device), dcf set to it, start = true.
NodeBootConfig boot_config_from_dcf(const eds::DeviceDescription& dcf);

// One SDO write of the configuration.
struct ConfigWrite {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  Bytes data;
  // Set for the first write of a PDO (its COB-ID with bit 31 set): the
  // configurator reads the COB-ID first and only writes it, as its own
  // value with bit 31 set, when the PDO is valid, so bits 0-29 of a valid
  // PDO are never changed (7.5.2.35).
  bool invalidate = false;
};

// What the configurator writes for a DCF, in this order, by object index:
//   - PDOs (1400h-15FFh with 1600h-17FFh, 1800h-19FFh with 1A00h-1BFFh), at
//     the place of the communication object, whole, every time: invalidate
//     the COB-ID (bit 31), the other writable communication subs, mapping
//     count 0, the mapping entries 1..N, count N, the DCF's COB-ID. Non-
//     writable parts are skipped (static mapping).
//   - 1017h (heartbeat producer time) whenever writable.
//   - Every other writable entry whose value differs from its DefaultValue
//     (entries without DefaultValue are not written: the reader cannot tell
//     a ParameterValue from the type's zero there). 1010h and 1011h are never
//     written: their writes store or restore parameters.
// With PlanScope::AllValues (DCF apply, dcf_transfer.hpp) instead: only
// the configurable entries (configurable_objects() rules, less ObjFlags
// bit 1, plus bit 0 "refuse write on download") that carry a
// ParameterValue, every one of them whatever its DefaultValue; a PDO is
// written whole (as above) when any entry of its communication or mapping
// object carries one, else not at all; 1017h gets no special case.
enum class PlanScope : std::uint8_t { Changed, AllValues };
std::vector<ConfigWrite> plan_configuration(const eds::DeviceDescription& dcf, PlanScope scope = PlanScope::Changed);

class BootConfigurator {
 public:
  using NmtSender = std::function<void(NmtCommand, std::uint8_t node)>;
  using EventHandler = std::function<void(const BootConfigEvent&)>;

  using TimeSource = std::function<TimePoint()>;

  // now: the caller's current time (steady clock, or FakeClock::now in
  // tests). It is needed because the next SDO request is submitted from the
  // previous one's completion handler, which is not passed the time.
  BootConfigurator(sdo::SdoClient& client, NmtSender send_nmt, EventHandler on_event, TimeSource now);
  ~BootConfigurator();
  BootConfigurator(const BootConfigurator&) = delete;
  BootConfigurator& operator=(const BootConfigurator&) = delete;

  // Sets (replaces) the configuration of node 1..127; a sequence already
  // running keeps the old one until the next boot-up. Returns false for a
  // bad node-ID.
  bool configure(std::uint8_t node, NodeBootConfig config);
  void remove(std::uint8_t node);  // cancels a running sequence without an event

  // The node booted: (re)starts its sequence. Ignored for unconfigured nodes.
  void on_boot_up(std::uint8_t node, TimePoint now);

  // The node was heard in `state` without a boot-up (see above). Returns
  // whether a sequence started.
  bool on_found(std::uint8_t node, NmtState state, TimePoint now);

  // Whether a sequence is running for the node.
  bool busy(std::uint8_t node) const;

 private:
  enum class OpKind : std::uint8_t { Read, Write };
  struct Op {
    OpKind kind = OpKind::Read;
    std::uint16_t index = 0;
    std::uint8_t sub = 0;
    Bytes data;
    bool invalidate = false;  // Read the COB-ID, then Write it with bit 31 set if valid
    bool optional = false;    // Read: an abort is ignored
  };
  enum class Phase : std::uint8_t { Identify, Configure };
  struct Run {
    std::uint64_t generation = 0;
    NodeBootConfig config;  // as at the boot-up, so configure() does not change a running sequence
    Phase phase = Phase::Identify;
    std::vector<Op> ops;
    std::size_t next = 0;
    std::optional<sdo::RequestId> request;
    std::map<std::uint32_t, std::uint32_t> read;  // (index << 8 | sub) -> value
    std::string done_detail;                       // the Done event's detail
  };
  struct NodeState {
    NodeBootConfig config;
    std::optional<Run> run;
  };

  void begin(std::uint8_t node, NodeBootConfig config, std::string identify_detail, std::string done_detail,
             TimePoint now);
  void step(std::uint8_t node, TimePoint now);
  void submit(std::uint8_t node, const Op& op, bool invalidate_write, TimePoint now);
  void on_done(std::uint8_t node, std::uint64_t generation, bool invalidate_write, sdo::TransferResult&& r);
  bool check_identity(std::uint8_t node);
  void finish(std::uint8_t node);
  void fail(std::uint8_t node, std::error_code ec, std::string detail);
  void emit(std::uint8_t node, BootConfigEvent::Step s, std::string detail = {},
            std::optional<DeviceIdentity> identity = std::nullopt);
  void stop(std::uint8_t node, TimePoint now);

  sdo::SdoClient& client_;
  NmtSender send_nmt_;
  EventHandler on_event_;
  TimeSource now_;
  std::map<std::uint8_t, NodeState> nodes_;
  std::uint64_t generation_ = 0;
};

}  // namespace canopen::master

template <>
struct std::is_error_code_enum<canopen::master::BootError> : std::true_type {};
