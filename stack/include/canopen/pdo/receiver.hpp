// PDO consumer on the gateway (CiA 301 7.2.2, 7.2.3): decodes the TPDOs and
// MPDOs of the configured remote nodes into PdoEvents.
//
// Sans-I/O. The caller MUST
//   - add each remote node with its dictionary (EDS/DCF) before its PDOs
//     arrive (the configuration is read once, at add_node()), and pass a
//     TPDO whose configuration changed on the device to set_tpdo();
//   - pass received frames to on_frame() (frames that are not PDOs are left
//     alone and on_frame() returns false, so handing it the whole bus is fine).
//
// Rules chosen here:
//   - A payload shorter than the mapping: PdoEvent.error, values empty.
//     Longer: decoded from the mapped bytes, the extra bytes ignored and
//     reported in PdoEvent.error (7.5.2.35/36: use the mapped length, signal
//     EMCY) — so a consumer checks `values` for data and `error` for problems.
//   - A standard-ID data frame in the PDO ranges of the pre-defined
//     connection set (181h-57Fh, function codes 0011b-1010b) that no node
//     claims gives a PdoEvent with node 0, number 0 and only raw bytes.
//   - A TPDO set with an `unusable` reason (its mapping does not resolve)
//     keeps its COB-ID: its frames give a PdoEvent with node, number, raw
//     bytes and that reason in `error`, never values.
//   - Synchronous TPDOs (transmission type 0-240) received when the
//     sync-window hook says "outside" are dropped and counted.
//   - RTR frames are never consumed (they are requests, not data).
//   - MPDO (mapping sub 0 = FEh SAM / FFh DAM): SAM values are typed from the
//     producer's dictionary and must be in its scanner list (1FA0h-1FCFh)
//     when it has one; a dispatcher list (1FD0h-1FFFh, set_dispatcher_list)
//     adds the local object in PdoEvent.mpdo. DAM values are typed from the
//     destination's dictionary when that node is configured, else from the
//     producer's, else given as 4 DOMAIN bytes.
//
// Thread safety: none; one thread. Callbacks run synchronously inside
// on_frame()/request() and must not call back into the receiver.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"

namespace canopen::pdo {

// Scanner list entry (UNSIGNED32): block size 31-24, index 23-8, sub 7-0.
struct ScannerEntry {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::uint8_t block = 1;
  static ScannerEntry from_raw(std::uint32_t raw);
  bool covers(std::uint16_t i, std::uint8_t s) const;
};
// Dispatcher list entry (UNSIGNED64): block size 63-56, producer node-ID
// 55-48, producer index 47-32, producer sub 31-24, local index 23-8, local sub 7-0.
struct DispatcherEntry {
  std::uint8_t producer = 0;
  std::uint16_t producer_index = 0;
  std::uint8_t producer_sub = 0;
  std::uint16_t local_index = 0;
  std::uint8_t local_sub = 0;
  std::uint8_t block = 1;
  static DispatcherEntry from_raw(std::uint64_t raw);
};
// Non-zero entries of 1FA0h-1FCFh / 1FD0h-1FFFh (sub 1..sub 0).
std::vector<ScannerEntry> read_scanner_list(const od::ObjectDictionary& od);
std::vector<DispatcherEntry> read_dispatcher_list(const od::ObjectDictionary& od);

class PdoReceiver {
 public:
  using FrameSink = std::function<void(const can::Frame&)>;
  using EventSink = std::function<void(PdoEvent)>;
  // True when `now` is inside the synchronous window of the last SYNC (1007h).
  using SyncWindow = std::function<bool(TimePoint)>;

  // max_bytes: 8 for classic CAN, 64 for CAN FD.
  PdoReceiver(FrameSink sink, EventSink on_event, std::size_t max_bytes = 8);

  // Reads node's TPDOs (1800h/1A00h) and scanner list; replaces an earlier
  // add_node() of the same node. Returns problems (a TPDO that cannot be
  // decoded, a COB-ID already claimed by another node); the rest still works.
  std::vector<std::string> add_node(std::uint8_t node, od::ObjectDictionary dict);
  void remove_node(std::uint8_t node);
  // Replaces (or adds) node's TPDO cfg.number, e.g. after the device was
  // remapped; a COB-ID with bit 31 set takes it off the bus. A non-empty
  // `unusable` (why the mapping cannot be decoded) keeps the COB-ID
  // claimed but decodes nothing (see above). Returns problems as
  // add_node(). The node need not have been added (no MPDO typing then).
  std::vector<std::string> set_tpdo(std::uint8_t node, PdoConfig cfg, std::string unusable = {});
  // Dispatcher list of the gateway's own dictionary; call again after it changes.
  void set_dispatcher_list(const od::ObjectDictionary& local);
  void set_sync_window(SyncWindow in_window) { in_window_ = std::move(in_window); }

  // Returns true when the frame was a PDO (claimed or in the PDO ranges).
  bool on_frame(const can::Frame& f, TimePoint now);
  // Sends an RTR for node's TPDO `number`. False when the TPDO is unknown,
  // invalid (COB-ID bit 31) or does not allow RTR (bit 30).
  bool request(std::uint8_t node, std::uint16_t number, TimePoint now);

  // No timers: present for the common service shape.
  TimePoint next_deadline() const { return TimePoint::max(); }
  void on_time(TimePoint) {}

  std::uint64_t dropped_late() const { return dropped_late_; }
  // The configuration in use for node's TPDO `number`, if any; valid until
  // the next add_node()/remove_node()/set_tpdo().
  const PdoConfig* tpdo(std::uint8_t node, std::uint16_t number) const;

 private:
  struct Node {
    od::ObjectDictionary dict;
    std::vector<PdoConfig> tpdos;                   // in number order
    std::map<std::uint16_t, std::string> unusable;  // TPDO number -> why it is not decoded
    std::vector<ScannerEntry> scanner;
  };
  struct Claim {
    std::uint8_t node;
    std::size_t pdo;  // index into Node::tpdos
  };
  static std::uint64_t key(const CobId& c) { return std::uint64_t{c.can_id()} | (c.extended() ? 1ULL << 32 : 0); }
  void rebuild_claims();
  std::vector<std::string> claim_conflicts(std::uint8_t node) const;
  void decode_mpdo(std::uint8_t owner, const PdoConfig& cfg, const can::Frame& f, PdoEvent& ev) const;

  FrameSink sink_;
  EventSink on_event_;
  std::size_t max_bytes_;
  SyncWindow in_window_;
  std::map<std::uint8_t, Node> nodes_;
  std::map<std::uint64_t, Claim> claims_;
  std::vector<DispatcherEntry> dispatcher_;
  std::uint64_t dropped_late_ = 0;
};

}  // namespace canopen::pdo
