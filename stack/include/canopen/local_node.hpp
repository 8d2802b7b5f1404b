// The gateway's own CANopen device on one network, as one sans-I/O unit:
// the Device on the gateway's dictionary plus the CiA 301 rules that only a
// device sharing its process with the network's NMT master needs.
//
//   - Its EMCYs for its own communication problems (7.2.7.1, table 21;
//     error register bit 4 "communication"), from the channel's bus events
//     and the master side's node states: CAN overrun 8110h (raised and
//     cleared at once: an event, not a condition), error passive 8120h
//     (raised while it lasts), life guard / heartbeat error 8130h (raised
//     while any consumed heartbeat or guarded node is lost, or while the
//     NMT master has not guarded this node within its node life time,
//     100Ch x 100Dh: 7.2.8.2.2.1's life guarding event, which CANopenNode's
//     devices report the same way), recovered from bus-off 8140h (an event).
//   - SYNC on request (send_sync) with the COB-ID of 1005h (7.5.2.5), like
//     the periodic SYNC its Device produces.
//   - Which frames the two sides of the process must hear of each other (a
//     socket does not receive its own frames): master_hears() for the own
//     node's frames - SYNC (1005h) and TIME (1012h) drive the master side's
//     synchronous RPDOs and consumers, its EMCY (1014h) is published like
//     any node's -, hears() for the master's - NMT commands to all nodes or
//     to the own node-ID (7.2.8.3.1). Not the LSS master's requests (7E5h):
//     the own node is no LSS slave, its node-ID is the configuration's.
//
// The caller MUST keep the dictionary alive as long as the LocalNode, feed
// it like a Device (on_frame/on_time/next_deadline; it reports other
// deadline changes itself, canopen/deadline.hpp) and pass it every bus
// event and every NodeStateEvent of the master side.
//
// Thread safety: none; use from one thread. The sinks are called
// synchronously and must not call back into the LocalNode.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <set>

#include "canopen/can/bus_state.hpp"
#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/deadline.hpp"
#include "canopen/device.hpp"
#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"

namespace canopen {

// Emergency error codes of the own node's communication problems (CiA 301
// 7.2.7.1, table 21).
inline constexpr std::uint16_t kEmcyCanOverrun = 0x8110;            // CAN overrun (objects lost)
inline constexpr std::uint16_t kEmcyCanErrorPassive = 0x8120;       // CAN in error passive mode
inline constexpr std::uint16_t kEmcyLifeGuardOrHeartbeat = 0x8130;  // life guard error or heartbeat error
inline constexpr std::uint16_t kEmcyRecoveredFromBusOff = 0x8140;   // recovered from bus off

class LocalNode : public DeadlineSource {
 public:
  using FrameSink = std::function<void(const can::Frame&)>;

  // bus: every frame the node sends. to_master: those of them the master
  // side must hear as well (master_hears()); may be empty.
  LocalNode(od::ObjectDictionary& dictionary, DeviceConfig config, FrameSink bus, FrameSink to_master,
            DeviceCallbacks callbacks = {});
  LocalNode(const LocalNode&) = delete;
  LocalNode& operator=(const LocalNode&) = delete;

  // Power-on (Device::start): boot-up, then heartbeats.
  void start(TimePoint now) { device_.start(now); }
  bool on_frame(const can::Frame& frame, TimePoint now) {
    now_ = now;
    return device_.on_frame(frame, now);
  }
  void on_time(TimePoint now) {
    now_ = now;
    device_.on_time(now);
  }
  TimePoint next_deadline() const { return device_.next_deadline(); }

  // A state change of the channel: 8120h while error passive, 8110h on a
  // receive overflow, 8140h when the controller is back from bus-off.
  void on_bus_event(const can::BusEvent& ev, TimePoint now);
  // A node state of the master side: 8130h from the first lost node until
  // none is lost any more (a boot-up, heartbeat or guarding answer of each).
  void on_node_state(const NodeStateEvent& ev, TimePoint now);
  // Nodes lost now (heartbeat or guarding), as counted for 8130h.
  const std::set<std::uint8_t>& lost_nodes() const { return lost_; }
  // Whether the master's guarding of this node has lapsed (life guarding
  // event Occurred, not yet Resolved). The callbacks' on_life_guarding
  // hears both after the EMCY went out.
  bool life_guarding_lost() const { return life_lost_; }

  // One SYNC now, with the COB-ID of 1005h and the counter when given
  // (7.2.5.2.1: 0 or 1 data bytes); sent whatever the NMT state, as a
  // request of the gateway's user. It goes to the bus and the master side.
  void send_sync(std::optional<std::uint8_t> counter);

  // Whether the master side must hear `own_frame`, a frame this node sent:
  // SYNC with the COB-ID of 1005h, TIME of 1012h, EMCY of 1014h.
  bool master_hears(const can::Frame& own_frame) const;
  // Whether this node must hear `master_frame`, sent by the master side:
  // an NMT command to all nodes or to this node-ID.
  bool hears(const can::Frame& master_frame) const;

  Device& device() { return device_; }
  const Device& device() const { return device_; }
  NmtState state() const { return device_.state(); }
  std::uint8_t node_id() const { return device_.node_id(); }

 private:
  void sent(const can::Frame& f);
  void on_life_guarding(nmt::LifeGuardingEvent e, TimePoint now);
  // 8130h while a node is lost or life guarding has lapsed.
  void update_guard_emcy(bool was_raised, TimePoint now);
  bool guard_emcy_raised() const { return life_lost_ || !lost_.empty(); }

  od::ObjectDictionary& od_;
  FrameSink bus_;
  FrameSink to_master_;
  std::function<void(nmt::LifeGuardingEvent)> user_life_guarding_;
  // The time of the call that caused the event: Device's callback has none.
  TimePoint now_{};
  bool life_lost_ = false;
  Device device_;
  std::set<std::uint8_t> lost_;
};

}  // namespace canopen
