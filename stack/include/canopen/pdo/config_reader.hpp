// Reads a remote node's PDO configuration from the device by SDO upload
// (CiA 301 7.2.2; records 1400h-15FFh / 1600h-17FFh of its RPDOs, 1800h-19FFh
// / 1A00h-1BFFh of its TPDOs, 7.5.2.35-7.5.2.39), so the mapping the device
// really uses can win over its EDS defaults.
//
// Per PDO, one upload at a time: communication sub 1 (COB-ID) and sub 2
// (transmission type), the optional subs the plan names (3 inhibit time,
// 5 event timer, 6 SYNC start: an abort there keeps the earlier value),
// mapping sub 0, then mapping sub 1..sub 0 (none for an MPDO, FEh/FFh).
// An abort from the device (e.g. 06020000h, object does not exist) fails
// that PDO only and the next one is read. A local error (timeout, malformed
// answer) ends the whole read: a node that does not answer is not asked
// again for every remaining object; the PDOs not read get that error.
//
// Sans-I/O: it only drives the SdoClient (which owns the timeouts); the
// caller MUST keep feeding the client frames and time, and keep the client
// alive as long as the reader.
//
// Thread safety: none; use from the SdoClient's thread. `done` runs
// synchronously from the client's completion handlers (or from read() /
// cancel()) and may call read() and cancel() again.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/pdo/remote_config.hpp"
#include "canopen/sdo/client.hpp"

namespace canopen::pdo {

struct PdoReadPlan {
  PdoKey key;
  // Communication subs to read besides 1 and 2 (those the description has).
  std::vector<std::uint8_t> optional_comm_subs;
};

struct PdoReadOutcome {
  PdoKey key;
  std::optional<PdoParameters> parameters;  // set when the PDO was read completely
  // Otherwise: the device's abort (SdoAbort, e.g. NoSuchObject), a local
  // error (SdoAbort::Timeout, ...) or std::errc::operation_canceled.
  std::error_code error;
  std::string detail;  // "TPDO4: 1803h sub 1: <abort text>"
};

struct PdoReadReport {
  std::uint8_t node = 0;
  std::vector<PdoReadOutcome> pdos;  // one per planned PDO, in plan order
  bool cancelled = false;            // cancel() ended it
  // Set when a local error (SdoAbort::Timeout, a full SDO queue, ...) ended
  // the read early; the PDOs after the failing one were not asked for.
  std::error_code stopped;
  std::size_t read_count() const;  // PDOs read completely
  // One line: "7 of 8 PDOs read from the device; TPDO4: 1803h sub 1: <why>".
  std::string summary() const;
};

class PdoConfigReader {
 public:
  using Done = std::function<void(const PdoReadReport&)>;
  using TimeSource = std::function<TimePoint()>;

  // now: the caller's current time, for requests submitted from the
  // previous one's completion handler (which is not given the time).
  PdoConfigReader(sdo::SdoClient& client, TimeSource now);
  // Cancels running reads without calling their `done`.
  ~PdoConfigReader();
  PdoConfigReader(const PdoConfigReader&) = delete;
  PdoConfigReader& operator=(const PdoConfigReader&) = delete;

  // Starts reading `plan` from node 1..127; `done` is called exactly once,
  // never from inside read() unless the plan is empty. When a read of the
  // node is already running, `done` waits for that one's report instead
  // and `plan` is ignored. Errors (nothing starts, done not called):
  // std::errc::invalid_argument for a bad node-ID, the client's submit
  // error (SdoAbort::NoSdoConnection when the node's queue is full).
  std::error_code read(std::uint8_t node, std::vector<PdoReadPlan> plan, Done done, TimePoint now);
  // Ends node's read: its SDO transfer is cancelled, the PDOs not read get
  // operation_canceled, and `done` is called with cancelled = true.
  void cancel(std::uint8_t node, TimePoint now);
  bool busy(std::uint8_t node) const { return runs_.contains(node); }

 private:
  struct Op {
    std::uint16_t index = 0;
    std::uint8_t sub = 0;
    bool optional = false;
  };
  struct Run {
    std::uint64_t generation = 0;
    std::vector<PdoReadPlan> plan;
    std::size_t pdo = 0;  // index into plan
    std::vector<Op> ops;  // of the current PDO
    std::size_t next = 0;
    PdoParameters current;
    std::optional<sdo::RequestId> request;
    PdoReadReport report;
    std::vector<Done> waiters;
  };

  void begin_pdo(Run& run);
  std::error_code submit(std::uint8_t node, Run& run, TimePoint now);
  void step(std::uint8_t node, TimePoint now);
  void on_done(std::uint8_t node, std::uint64_t generation, sdo::TransferResult&& r);
  void finish(std::uint8_t node, bool cancelled);
  void complete(Run run, bool cancelled);  // fills the PDOs not read, calls the waiters

  sdo::SdoClient& client_;
  TimeSource now_;
  std::map<std::uint8_t, Run> runs_;
  std::uint64_t generation_ = 0;
};

}  // namespace canopen::pdo
