// CAN controller state as seen by the gateway, and the rules that move it.
//
// The state follows ISO 11898-1 fault confinement as reported by the Linux
// driver through error frames (linux/can/error.h), plus `Down` for an
// interface that is administratively down or gone. This file has no I/O:
// the SocketCAN adapter decodes error frames into ErrorFrameInfo and feeds
// them to BusStateTracker.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace canopen::can {

enum class BusState : std::uint8_t {
  ErrorActive,   // normal operation
  ErrorWarning,  // an error counter reached 96
  ErrorPassive,  // an error counter reached 128
  BusOff,        // transmit error counter passed 255; the controller left the bus
  Down,          // interface down, removed, or not yet opened
};

// Why the state changed (or an event worth reporting without a state change).
enum class BusEventCause : std::uint8_t {
  ErrorFrame,        // controller reported a fault-confinement change
  ControllerRestarted,  // driver restarted the controller after bus-off
  LinkDown,          // interface set down
  LinkRemoved,       // interface deleted
  LinkUp,            // interface (back) up; socket (re)opened
  RxOverflow,        // kernel or controller dropped received frames
};

std::string_view to_string(BusState s);     // "error-active", "error-warning", ...
std::string_view to_string(BusEventCause c);  // "error-frame", "link-down", ...

struct BusEvent {
  BusState state = BusState::Down;
  BusState previous = BusState::Down;
  BusEventCause cause = BusEventCause::LinkUp;
  std::uint16_t tx_error_counter = 0;  // from the controller when it reports them
  std::uint16_t rx_error_counter = 0;
  std::uint64_t dropped = 0;  // frames lost, for RxOverflow
};

// Content of one Linux CAN error frame that matters for the bus state.
struct ErrorFrameInfo {
  bool bus_off = false;
  bool restarted = false;
  bool controller = false;       // CAN_ERR_CRTL present; the flags below are valid
  bool rx_warning = false, tx_warning = false;
  bool rx_passive = false, tx_passive = false;
  bool back_to_active = false;
  bool rx_overflow = false, tx_overflow = false;
  bool protocol_error = false;   // bit/stuff/form/ack errors: counted, no state change
  bool has_counters = false;
  std::uint8_t tx_error_counter = 0, rx_error_counter = 0;
};

// Folds error frames and link changes into a current state.
// Not thread-safe; owned by one channel.
class BusStateTracker {
 public:
  BusState state() const { return state_; }

  // Returns the event to report when the frame changes the state or signals
  // a restart or overflow; nullopt when it changes nothing.
  std::optional<BusEvent> on_error_frame(const ErrorFrameInfo& info);
  // Link transitions from the interface monitor.
  std::optional<BusEvent> on_link_down(bool removed);
  std::optional<BusEvent> on_link_up();

  std::uint64_t protocol_errors() const { return protocol_errors_; }

 private:
  std::optional<BusEvent> move_to(BusState next, BusEventCause cause);

  BusState state_ = BusState::Down;
  BusEventCause last_cause_ = BusEventCause::LinkDown;
  std::uint16_t tx_errors_ = 0, rx_errors_ = 0;
  std::uint64_t protocol_errors_ = 0;
};

}  // namespace canopen::can
