// PDO producer on the gateway (CiA 301 7.2.2): process data the gateway
// writes to a remote node's RPDO (COB-ID and mapping from the node's
// 1400h/1600h), or to one of the gateway's own TPDOs (add() with a
// PdoConfig).
//
// Transmission types (7.2.2.2, 7.5.2.35):
//   0        acyclic synchronous: sent on the next SYNC after a change
//   1-240    cyclic synchronous: every n-th SYNC; with a SYNC start value
//            (sub 6, non-zero) and a SYNC counter, first at the SYNC whose
//            counter equals the start value, then every n-th
//   252      synchronous RTR-only: data sampled at SYNC, sent on an RTR
//   253      event-driven RTR-only: sent on an RTR
//   254/255  event-driven: sent on each change; an event during the inhibit
//            time (100 us units) is held back and sent when it ends (not
//            lost); the event timer (ms, 0 = off) resends when no event came.
// Any valid PDO whose COB-ID allows RTR is also sent on an RTR for it.
//
// Sans-I/O. The caller MUST
//   - call on_sync() for every SYNC received (with its counter, if any);
//   - call on_time(now) when now >= next_deadline() (inhibit and event timers);
//   - pass received frames to on_frame() for RTRs (others are ignored).
// Writes (set_value/set_values/set_raw) are events: with types 254/255 they
// may send at once, from inside the call. They, add*(), reconfigure() and
// on_sync() report the new deadline to the on_deadline_change() observer
// (canopen/deadline.hpp).
//
// Thread safety: none; one thread. The sink is called synchronously and must
// not call back into the transmitter.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <system_error>
#include <utility>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/deadline.hpp"
#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/result.hpp"

namespace canopen::pdo {

class PdoTransmitter : public DeadlineSource {
 public:
  using FrameSink = std::function<void(const can::Frame&)>;

  explicit PdoTransmitter(FrameSink sink) : sink_(std::move(sink)) {}

  // Configures node's RPDO `number` from the node's dictionary. The initial
  // payload holds the mapped objects' current values from `dict`. Returns the
  // payload length. Errors: read_pdo()'s, or NoSuchObject when the COB-ID is
  // invalid (bit 31) or the PDO is an MPDO. Replaces an earlier add().
  Result<std::size_t> add_rpdo(std::uint8_t node, std::uint16_t number, const od::ObjectDictionary& dict,
                               TimePoint now, std::size_t max_bytes = 8) {
    return add_from(node, Direction::Receive, number, dict, now, max_bytes);
  }
  // The same for either direction: Direction::Transmit with the gateway's own
  // dictionary produces one of its TPDOs (1800h/1A00h); `node` is then the
  // gateway's node-ID, used only as the key.
  Result<std::size_t> add_from(std::uint8_t node, Direction dir, std::uint16_t number,
                               const od::ObjectDictionary& dict, TimePoint now, std::size_t max_bytes = 8);
  // The same from a ready configuration; the payload starts zeroed.
  Result<std::size_t> add(std::uint8_t node, PdoConfig cfg, TimePoint now);
  void remove(std::uint8_t node, std::uint16_t number);
  // The PDO's configuration changed on the device (7.5.2.35-7.5.2.38):
  // replaces it like add(), but objects mapped before and after keep their
  // latest values; objects newly mapped start with their value in
  // `initial` (the node's description) when given, else 0. A configuration
  // add() refuses (COB-ID bit 31 set, MPDO) removes the PDO and returns
  // that error. Nothing is sent.
  Result<std::size_t> reconfigure(std::uint8_t node, PdoConfig cfg, TimePoint now,
                                  const od::ObjectDictionary* initial = nullptr);
  // The configuration in use for node's PDO `number`; nullptr when none.
  // Valid until the next add/reconfigure/remove.
  const PdoConfig* config(std::uint8_t node, std::uint16_t number) const;

  // NoSuchObject: PDO not added; NotMappable: index/sub not in its mapping;
  // LengthMismatch: the value's type is not the mapped type. Nothing changes
  // unless all values fit.
  std::error_code set_value(std::uint8_t node, std::uint16_t number, std::uint16_t index, std::uint8_t sub,
                            const Value& v, TimePoint now);
  std::error_code set_values(std::uint8_t node, std::uint16_t number, std::span<const MappedValue> values,
                             TimePoint now);
  // bytes must be exactly the mapped length (LengthMismatch otherwise).
  std::error_code set_raw(std::uint8_t node, std::uint16_t number, std::span<const std::uint8_t> bytes,
                          TimePoint now);

  void on_sync(std::optional<std::uint8_t> counter, TimePoint now);
  // Returns true when f was an RTR for one of these PDOs (and it was sent).
  bool on_frame(const can::Frame& f, TimePoint now);
  TimePoint next_deadline() const;
  void on_time(TimePoint now);

  const Bytes* payload(std::uint8_t node, std::uint16_t number) const;

 private:
  struct Tx {
    PdoConfig cfg;
    Bytes payload;
    Bytes sampled;                     // type 252: payload at the last SYNC
    bool changed = false;              // type 0: a write since the last send
    bool held = false;                 // 254/255: an event waits for the inhibit time
    std::optional<TimePoint> inhibit_until;
    std::optional<TimePoint> timer_due;  // event timer
    unsigned sync_count = 0;
    bool started = false;  // SYNC start value seen
  };
  using Key = std::pair<std::uint8_t, std::uint16_t>;

  Tx* find(std::uint8_t node, std::uint16_t number);
  void event(Tx& tx, TimePoint now);
  void send(Tx& tx, const Bytes& data, TimePoint now);

  FrameSink sink_;
  std::map<Key, Tx> pdos_;
};

}  // namespace canopen::pdo
