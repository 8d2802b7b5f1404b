// LSS master (CiA 305): every service of the master side, sans-I/O.
//
// One service runs at a time; others wait in a queue (LSS has one pair of
// COB-IDs for all slaves, so two services at once would read each other's
// answers). Each service ends with exactly one call of its handler: a
// typed result or an error (lss/error.hpp: LssError, or a slave's error
// answer). Handlers never run inside the call that submitted the service:
// they run inside on_frame() or on_time(), so a caller may submit the next
// service from a handler.
//
// The caller MUST
//   - pass every received frame to on_frame() (only 7E4h is used);
//   - call on_time(now) when now >= next_deadline();
// submits and cancel_all() report the new deadline to the
// on_deadline_change() observer (canopen/deadline.hpp).
//
// Timing, as chosen here:
//   - A confirmed service (switch selective, configure, store, inquire)
//     ends at its answer or after `timeout` with LssError::Timeout.
//   - Unconfirmed services (switch global, activate bit timing) are done
//     when sent; their handler runs at the next on_time().
//   - Identify (remote slave, non-configured) and every fastscan step wait
//     the whole step window (`scan_step_timeout`), answered or not: several
//     slaves may answer one request and an answer that came late would
//     otherwise be read as the answer to the next request.
//
// Fastscan (facts C.2): the reset (BitChecked 80h) first; when nobody
// answers it, the scan ends at once with NoUnconfiguredSlave, so an empty
// bus costs one step window, not 133. Then per part: 32 bit steps (no
// answer means the bit is 1) and a verify step, which moves the matching
// slaves on; the last verify (LSSNext < LSSSub) puts the one found into
// configuration state, and the scan ends with its identity, selected. A
// full scan of four SCAN parts is 1 + 4 x 32 + 4 = 133 exchanges.
// A lost answer during a bit step reads as bit 1, so the part value is
// wrong and no slave answers its verify step: the scan then restarts from
// the reset (after a switch state global to waiting, in case the lost
// frame was the last verify's answer and the slave already is in
// configuration state), at most `fastscan_restarts` times, then ends with
// ScanFailed. A lost answer to the reset reads as an empty bus.
//
// Thread safety: none; use from one thread. Handlers and the sink are
// called synchronously and must not call on_frame()/on_time() themselves.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <system_error>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/deadline.hpp"
#include "canopen/lss/error.hpp"
#include "canopen/lss/frames.hpp"
#include "canopen/result.hpp"

namespace canopen::lss {

struct MasterConfig {
  // Confirmed services: the answer is one frame from the one slave in
  // configuration state, so waiting long costs nothing when it answers.
  Duration timeout = std::chrono::seconds(1);
  // One fastscan step or identify window. 100 ms as CANopenNode's gateway
  // and Lely use (facts C.2): a full scan of one device takes 133 windows,
  // 13.3 s at 100 ms, where CANopenNode's 1 s default gives the 2-3 minutes
  // users complain about (CANopenNode#597). Much shorter risks missing
  // answers: LSS frames have the lowest priority on the bus.
  Duration scan_step_timeout = std::chrono::milliseconds(100);
  // Services waiting behind the running one.
  std::size_t queue_limit = 16;
  // Fastscan restarts after a verify step nobody answered (see top).
  unsigned fastscan_restarts = 2;
};

// The empty success of services that return nothing.
struct Ack {};

template <typename T>
using Handler = std::function<void(Result<T>)>;

// What fastscan does with one part of the address.
enum class PartScan : std::uint8_t {
  Scan,   // find it bit by bit (32 steps + verify)
  Match,  // the value is known (FastscanRequest::known): verify step only
  Skip,   // not checked at all; not allowed for the vendor-ID, nor for all
          // of product, revision and serial (the last verify needs LSSNext < LSSSub)
};

struct FastscanRequest {
  std::array<PartScan, 4> parts{PartScan::Scan, PartScan::Scan, PartScan::Scan, PartScan::Scan};
  Identity known;                          // the values of Match parts
  std::optional<Duration> step_timeout;    // overrides MasterConfig::scan_step_timeout
};

struct FastscanResult {
  // Empty: found; identity is the device's, now in configuration state.
  // NoUnconfiguredSlave, ScanFailed, Cancelled otherwise.
  std::error_code error;
  Identity identity;           // Skip parts are 0
  std::size_t exchanges = 0;   // requests sent (each one step window), restarts included
  unsigned restarts = 0;
};

struct AssignAllRequest {
  // The node-IDs to give, in this order; empty: first_node_id..127 without `in_use`.
  std::vector<std::uint8_t> node_ids;
  std::uint8_t first_node_id = 1;
  std::vector<std::uint8_t> in_use;  // node-IDs already on the bus
  bool store = true;                 // store configuration after each configure node-ID
  std::optional<Duration> step_timeout;
};

struct Assignment {
  Identity identity;
  std::uint8_t node_id = 0;
  bool stored = false;
  std::error_code store_error;  // the slave's answer when store failed; the node-ID is still set
};

struct AssignAllResult {
  std::vector<Assignment> assigned;
  // Empty: ended because no unconfigured device answered any more. Else why
  // it stopped early (ScanFailed, NoFreeNodeId, Timeout, a slave's error
  // answer to configure node-ID, Cancelled); `assigned` holds what was done.
  std::error_code error;
  std::size_t exchanges = 0;  // every request frame sent, all fastscans included
};

using FastscanHandler = std::function<void(const FastscanResult&)>;
using AssignAllHandler = std::function<void(const AssignAllResult&)>;

class LssMaster : public DeadlineSource {
 public:
  LssMaster(MasterConfig config, FrameSink sink);
  ~LssMaster();
  LssMaster(const LssMaster&) = delete;
  LssMaster& operator=(const LssMaster&) = delete;

  // Applies to services started after the call.
  void set_config(const MasterConfig& config) { config_ = config; }
  const MasterConfig& config() const { return config_; }

  // Every submit returns an error and queues nothing for a bad argument
  // (std::errc::invalid_argument) or a full queue (LssError::QueueFull).

  // Switch state global (cs 04h, unconfirmed): all slaves to `mode`.
  std::error_code switch_state_global(Mode mode, Handler<Ack> done, TimePoint now);
  // Switch state selective (cs 40h..43h, answer 44h): the slave with this
  // identity to configuration state. Timeout when no slave has it.
  std::error_code switch_state_selective(const Identity& id, Handler<Ack> done, TimePoint now);
  // Configure node-ID (cs 11h) of the slave in configuration state: 1..127,
  // or FFh to unconfigure it. Slave errors: NodeIdOutOfRange, NodeIdManufacturer.
  std::error_code configure_node_id(std::uint8_t node_id, Handler<Ack> done, TimePoint now);
  // Configure bit timing (cs 13h): table 0 index (bit_timing_index()).
  // Slave errors: BitTimingNotSupported, BitTimingManufacturer.
  std::error_code configure_bit_timing(std::uint8_t table, std::uint8_t index, Handler<Ack> done, TimePoint now);
  // Activate bit timing (cs 15h, unconfirmed, to all slaves in configuration
  // state): each switches after the delay and waits it again before sending.
  // The caller must switch its own controller within that window.
  std::error_code activate_bit_timing(std::uint16_t switch_delay_ms, Handler<Ack> done, TimePoint now);
  // Store configuration (cs 17h). Slave errors: StoreNotSupported,
  // StoreMediaAccess, StoreManufacturer.
  std::error_code store_configuration(Handler<Ack> done, TimePoint now);
  // Inquire one part of the identity (cs 5Ah..5Dh) / all four in turn / the
  // node-ID (cs 5Eh; FFh: none active) of the slave in configuration state.
  std::error_code inquire_identity(Part part, Handler<std::uint32_t> done, TimePoint now);
  std::error_code inquire_address(Handler<Identity> done, TimePoint now);
  std::error_code inquire_node_id(Handler<std::uint8_t> done, TimePoint now);
  // Identify remote slave (cs 46h..4Bh): true when any slave in the range
  // answered (4Fh) within the step window. Error: invalid_argument when a
  // low bound is above its high bound.
  std::error_code identify_remote_slave(const IdentityRange& range, Handler<bool> done, TimePoint now);
  // Identify non-configured remote slave (cs 4Ch): true when any slave
  // without a node-ID answered (50h) within the step window.
  std::error_code identify_non_configured(Handler<bool> done, TimePoint now);
  // Fastscan (cs 51h, see top). invalid_argument for a Skip the protocol
  // cannot do (see PartScan).
  std::error_code fastscan(const FastscanRequest& request, FastscanHandler done, TimePoint now);
  // Assign-all (facts C.4 item 1): switch all to waiting, then until nobody
  // unconfigured answers: fastscan, configure node-ID with the next ID,
  // store (when asked), switch all to waiting (an unconfigured slave then
  // takes its new node-ID and boots with it). invalid_argument for a node-ID
  // outside 1..127 in node_ids or first_node_id.
  std::error_code assign_all(const AssignAllRequest& request, AssignAllHandler done, TimePoint now);

  // Ends the running and the waiting services with LssError::Cancelled.
  void cancel_all(TimePoint now);

  // Returns true when the frame was an LSS slave frame (7E4h).
  bool on_frame(const can::Frame& frame, TimePoint now);
  void on_time(TimePoint now);
  // TimePoint::max() when idle.
  TimePoint next_deadline() const;

  bool busy() const;
  // Services waiting plus running.
  std::size_t pending() const;

  // Implementation detail (lss/master_*.cpp): one running service.
  class Job;

 private:
  friend class Job;
  std::error_code submit(std::unique_ptr<Job> job, TimePoint now);
  void start_next(TimePoint now);
  void finish_current(TimePoint now);

  MasterConfig config_;
  FrameSink sink_;
  std::unique_ptr<Job> current_;
  std::deque<std::unique_ptr<Job>> queue_;
  std::unique_ptr<Job> retired_;  // finished inside its own call; freed at the next call from outside
  TimePoint deadline_ = TimePoint::max();
  bool in_call_ = false;          // inside on_frame()/on_time(): a job may be on the stack
  struct CallScope {
    explicit CallScope(bool& flag) : flag_(flag), was_(flag) { flag_ = true; }
    ~CallScope() { flag_ = was_; }
    bool& flag_;
    bool was_;
  };
};

}  // namespace canopen::lss
