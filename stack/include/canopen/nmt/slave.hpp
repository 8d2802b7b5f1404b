// NMT slave for the gateway's own node (CiA 301 7.3.2 state machine,
// 7.2.8.3.1 node control, 7.2.8.3.2 heartbeat producer and node/life
// guarding, 7.2.8.3.3 boot-up).
//
// Sans-I/O: the caller feeds received frames and the current time; the
// slave emits frames through the sink. The caller MUST
//   - call start(now) once (power-on): it runs the initialisation and sends
//     the boot-up message;
//   - pass every received frame to on_frame() (frames that are not NMT
//     commands or guarding requests for this node are ignored);
//   - call on_time(now) when now >= next_deadline() (heartbeat, life
//     guarding, and applying a write to 1017h/100Ch/100Dh);
//   - keep the dictionary alive and the slave at one address (it installs
//     write hooks on 100Ch, 100Dh and 1017h that point at it; the
//     destructor removes them);
//   - call reconfigure(now) after changing 100Ch/100Dh/1017h with
//     ObjectDictionary::set() (local writes do not run hooks). SDO writes
//     are picked up by the hooks.
//
// Choices where the standard leaves room:
//   - The initialisation sub-states run synchronously: a reset node command
//     calls on_reset_application, then on_reset_communication (the
//     application restores its parameters there), then the slave re-reads
//     its configuration, sends boot-up and is pre-operational, all inside
//     the call.
//   - The first heartbeat follows the boot-up message (which counts as the
//     first heartbeat) by one producer period; a write to 1017h restarts
//     the period at the time it is applied.
//   - Heartbeat and node guarding are exclusive (7.2.8.3.2.2): while 1017h
//     is non-zero, guarding requests are not answered and life guarding is
//     off.
//   - Life guarding starts with the first guarding request when 100Ch and
//     100Dh are both non-zero; reset communication stops it and clears the
//     toggle bit.
//
// Thread safety: none; use from one thread. Sink and callbacks are called
// synchronously and must not call back into the slave, except that the
// reset callbacks may change the dictionary.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/events.hpp"
#include "canopen/nmt/nmt.hpp"
#include "canopen/od/object_dictionary.hpp"

namespace canopen::nmt {

// Life guarding on the slave side (7.2.8.3.2.1): no guarding request within
// the node life time (Occurred), and requests arriving again (Resolved).
enum class LifeGuardingEvent : std::uint8_t { Occurred, Resolved };

struct SlaveCallbacks {
  // Reset application sub-state: set the manufacturer and profile areas to
  // their power-on values.
  std::function<void()> on_reset_application;
  // Reset communication sub-state: set the communication area (1000h-1FFFh)
  // to its power-on values.
  std::function<void()> on_reset_communication;
  // After every state change among pre-operational, operational, stopped
  // (a reset is reported as initialising -> pre-operational when it ends).
  std::function<void(NmtState now, NmtState before)> on_state_change;
  std::function<void(LifeGuardingEvent)> on_life_guarding;
};

class NmtSlave {
 public:
  // The states of figure 48/49; the first three are the initialisation sub-states.
  enum class State : std::uint8_t {
    ResetApplication,
    ResetCommunication,
    Initialising,
    PreOperational,
    Operational,
    Stopped,
  };

  NmtSlave(od::ObjectDictionary& dictionary, std::uint8_t node_id, FrameSink sink, SlaveCallbacks callbacks = {});
  ~NmtSlave();
  NmtSlave(const NmtSlave&) = delete;
  NmtSlave& operator=(const NmtSlave&) = delete;

  // Power-on: initialisation as after reset node, ending pre-operational
  // with the boot-up message sent. Calling it again behaves as reset node.
  void start(TimePoint now);
  // Handles an NMT command (000h) for this node or all nodes, or a guarding
  // request (RTR on 700h + node). Returns false for any other frame.
  bool on_frame(const can::Frame& frame, TimePoint now);
  // Local node control (7.3.2.3: "local control"), same transitions as received commands.
  void command(NmtCommand cs, TimePoint now);
  // Earliest time on_time() has work: next heartbeat, life time expiry, or
  // TimePoint::min() when a write to 1017h/100Ch/100Dh waits to be applied;
  // TimePoint::max() when idle.
  TimePoint next_deadline() const;
  void on_time(TimePoint now);
  // Re-reads 1017h, 100Ch and 100Dh from the dictionary.
  void reconfigure(TimePoint now);

  State state() const { return state_; }
  // The state as carried in heartbeats; Initialising for the three sub-states.
  NmtState nmt_state() const;
  // Table 37: whether the service may run in the current state.
  bool service_active(Service s) const;
  std::uint8_t node_id() const { return node_; }
  Duration heartbeat_period() const { return heartbeat_period_; }
  Duration life_time() const { return life_time_; }

 private:
  void reset(bool application, TimePoint now);
  void enter(State s);
  void apply_config(TimePoint now);
  void on_guard_request(TimePoint now);

  od::ObjectDictionary* od_;
  std::uint8_t node_;
  FrameSink sink_;
  SlaveCallbacks cb_;
  State state_ = State::Initialising;
  bool started_ = false;

  // Values written over SDO, waiting for on_time() to apply them.
  std::optional<std::uint16_t> pending_heartbeat_;
  std::optional<std::uint16_t> pending_guard_time_;
  std::optional<std::uint8_t> pending_life_factor_;

  Duration heartbeat_period_{};  // 0: producer off
  TimePoint next_heartbeat_ = TimePoint::max();
  std::uint16_t guard_time_ms_ = 0;
  std::uint8_t life_factor_ = 0;
  Duration life_time_{};  // 0: life guarding off
  bool guarding_started_ = false;  // a guarding request has arrived since reset communication
  bool life_lost_ = false;
  TimePoint life_deadline_ = TimePoint::max();
  bool toggle_ = false;
};

}  // namespace canopen::nmt
