// DCF read-back and DCF apply (CiA 306 device configuration files): read a
// node's configuration into a DCF, and write a DCF's values to a node.
//
// Which objects are configuration (configurable_objects(), used by both):
//   - communication profile area 1000h-1FFFh: every entry that is readable
//     AND writable (PDO communication and mapping parameters included),
//     except 1003h (error history; writing sub 0 clears it), 1010h/1011h
//     (store/restore commands) and 1F50h-1F5Fh (program download: domains
//     and commands, CiA 302-3);
//   - application area 2000h-9FFFh: entries that are readable AND writable
//     and NOT PDO-mappable (mappable ones are process data, not settings);
//   - never DOMAIN entries (unbounded data, not a parameter), never entries
//     with CiA 306 ObjFlags bit 1 "refuse read on scan" (for the read-back;
//     the apply honours bit 0 "refuse write on download" instead);
//   - nothing above 9FFFh.
//
// DCF read-back (DcfReader): uploads every configurable object, one at a
// time through the SdoClient's queue of the node (so other requests to the
// node interleave), and decodes each by its EDS type. An object that
// aborts (device abort, or a reply that does not decode as the type) is
// listed in report.failed and the read goes on. A local timeout ends the
// read early (report.stopped = SdoAbort::Timeout): the node is not
// answering, and waiting one timeout per remaining object would only delay
// the same answer.
//
// DCF apply (DcfApplier): writes, in the boot-up configurator's order
// (plan_configuration(dcf, PlanScope::AllValues): PDOs disabled through
// their COB-ID bit 31 before remapping, mapping count 0, entries, count,
// then the DCF's COB-ID), every writable configurable entry that carries a
// ParameterValue in the DCF (not only those differing from DefaultValue: a
// read-back DCF must restore a device that drifted). An abort does not stop
// it: one outcome per write, in the order written. A local timeout ends it
// early, as for the read. Then, as the options say, 1010h sub 1 := "save"
// and NMT reset node (the reset only after a successful save, or when no
// save was asked: a reset after a failed save would throw the applied
// values away). Every successful write to 1400h-1BFFh goes through the
// SdoClient's download observer, so a Network's PDO decoder follows it.
//
// Events: TransferEvent (operation DcfRead / DcfApply) through on_event:
// Running at the start (total = objects), Running after every object
// (done = objects finished), then one Done (objects that aborted are not a
// failure; detail sums them up) or Failed (stopped early; error and detail
// say why). The run's Done handler is called after that last event.
//
// Sans-I/O: only the SdoClient (and, for the reset, an NmtSender) are
// driven; the caller MUST keep feeding the client frames and time and keep
// it alive as long as these objects.
//
// Thread safety: none; use from the SdoClient's thread. Handlers run
// synchronously from the client's handlers (never from start()) and may
// call back into the service.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/events.hpp"
#include "canopen/master/boot_configurator.hpp"
#include "canopen/master/transfer_error.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/types.hpp"

namespace canopen::master {

// The "save" / "load" signatures of 1010h / 1011h (CiA 301 7.5.2.13/14),
// as the UNSIGNED32 whose little-endian bytes spell the word.
inline constexpr std::uint32_t kStoreSignature = 0x65766173;    // "save"
inline constexpr std::uint32_t kRestoreSignature = 0x64616F6C;  // "load"

struct ObjectAddress {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  friend auto operator<=>(const ObjectAddress&, const ObjectAddress&) = default;
};

// The entries a DCF read-back reads, by index and sub-index (see top).
std::vector<ObjectAddress> configurable_objects(const eds::DeviceDescription& description);
// The rule of configurable_objects() for one entry, without the ObjFlags.
bool is_configuration_entry(std::uint16_t index, const od::SubEntry& entry);

// What happened to one object.
struct ObjectResult {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::error_code error;  // empty: read / written
  sdo::Origin origin = sdo::Origin::None;
  std::string detail;     // the abort's text, or what went wrong locally
};

struct DcfReadReport {
  std::uint8_t node = 0;
  std::map<ObjectAddress, Value> values;  // what was read, by the EDS types
  std::vector<ObjectResult> failed;       // objects that aborted, in reading order
  std::size_t total = 0;                  // objects to read
  std::error_code stopped;                // set when the read ended early (timeout, cancel)
  std::string detail;                     // why it stopped
  bool cancelled = false;
};

// The DCF text (CiA 306) of a read-back: [FileInfo] and [DeviceInfo] of the
// EDS (FileName/LastEDS/Description noting the read-back), [DeviceComissioning]
// with NodeID = node_id, the object lists, and every object section of the
// EDS with its keys as the EDS has them plus ParameterValue = the value read
// (for objects in `values`; others keep only their DefaultValue). Numbers
// follow the EDS's own convention per entry: hex (0x...) where its
// DefaultValue was written in hex, decimal otherwise. eds::parse of the
// result (with no node-ID given) reads back the same values.
std::string write_dcf(const eds::DeviceDescription& eds, std::uint8_t node_id,
                      const std::map<ObjectAddress, Value>& values);

class DcfReader {
 public:
  using EventHandler = std::function<void(const TransferEvent&)>;
  using Done = std::function<void(const DcfReadReport&)>;
  using TimeSource = std::function<TimePoint()>;

  DcfReader(sdo::SdoClient& client, EventHandler on_event, TimeSource now);
  ~DcfReader();  // cancels running reads without events
  DcfReader(const DcfReader&) = delete;
  DcfReader& operator=(const DcfReader&) = delete;

  // Reads configurable_objects(description) from `node` (the description
  // is not kept after the call). Errors (nothing started, done not called):
  // TransferError::BadNode, Busy, NothingToTransfer, the client's submit error.
  std::error_code start(std::uint8_t node, const eds::DeviceDescription& description, Done done, TimePoint now);
  bool busy(std::uint8_t node) const;
  // Ends a running read (report: cancelled, stopped = GeneralError); false if none.
  bool cancel(std::uint8_t node, TimePoint now);

 private:
  struct Run;
  void submit(std::uint8_t node, TimePoint now);
  void on_done(std::uint8_t node, std::uint64_t gen, sdo::TransferResult&& r);
  void finish(std::uint8_t node, std::error_code stopped, std::string detail, bool cancelled = false);

  sdo::SdoClient& client_;
  EventHandler on_event_;
  TimeSource now_;
  std::map<std::uint8_t, Run> runs_;
  std::uint64_t generation_ = 0;
};

struct DcfApplyOptions {
  bool store = false;  // 1010h sub 1 := "save" after the writes
  bool reset = false;  // NMT reset node at the end (see top)
  std::optional<Duration> timeout = std::nullopt;  // SDO timeout per transfer; nullopt: the client's
};

struct DcfApplyReport {
  std::uint8_t node = 0;
  std::vector<ObjectResult> objects;  // one per write, in the order written
  std::size_t total = 0;              // writes planned
  std::size_t failed = 0;             // of `objects`, those with an error
  bool stored = false;                // 1010h sub 1 "save" confirmed
  std::optional<ObjectResult> store_error;  // the save was refused
  bool reset = false;                 // NMT reset node sent
  std::error_code stopped;            // set when the apply ended early (timeout, cancel)
  std::string detail;
  bool cancelled = false;
};

class DcfApplier {
 public:
  using EventHandler = std::function<void(const TransferEvent&)>;
  using Done = std::function<void(const DcfApplyReport&)>;
  using TimeSource = std::function<TimePoint()>;
  using NmtSender = std::function<void(NmtCommand, std::uint8_t node)>;

  DcfApplier(sdo::SdoClient& client, NmtSender send_nmt, EventHandler on_event, TimeSource now);
  ~DcfApplier();  // cancels running applies without events
  DcfApplier(const DcfApplier&) = delete;
  DcfApplier& operator=(const DcfApplier&) = delete;

  // Writes `dcf` to `node` (planned inside this call; the dcf is not kept).
  // Errors (nothing started, done not called): TransferError::BadNode,
  // Busy, NothingToTransfer (no writable entry with a ParameterValue and
  // neither store nor reset asked), the client's submit error.
  std::error_code start(std::uint8_t node, const eds::DeviceDescription& dcf, DcfApplyOptions options, Done done,
                        TimePoint now);
  bool busy(std::uint8_t node) const;
  bool cancel(std::uint8_t node, TimePoint now);

 private:
  struct Run;
  void step(std::uint8_t node, TimePoint now);
  void on_done(std::uint8_t node, std::uint64_t gen, sdo::TransferResult&& r);
  void finish(std::uint8_t node, std::error_code stopped, std::string detail, bool cancelled = false);

  sdo::SdoClient& client_;
  NmtSender send_nmt_;
  EventHandler on_event_;
  TimeSource now_;
  std::map<std::uint8_t, Run> runs_;
  std::uint64_t generation_ = 0;
};

}  // namespace canopen::master
