#include "canopen/can/bus_state.hpp"

namespace canopen::can {

std::string_view to_string(BusState s) {
  switch (s) {
    case BusState::ErrorActive: return "error-active";
    case BusState::ErrorWarning: return "error-warning";
    case BusState::ErrorPassive: return "error-passive";
    case BusState::BusOff: return "bus-off";
    case BusState::Down: return "down";
  }
  return "unknown";
}

std::string_view to_string(BusEventCause c) {
  switch (c) {
    case BusEventCause::ErrorFrame: return "error-frame";
    case BusEventCause::ControllerRestarted: return "restarted";
    case BusEventCause::LinkDown: return "link-down";
    case BusEventCause::LinkRemoved: return "link-removed";
    case BusEventCause::LinkUp: return "link-up";
    case BusEventCause::RxOverflow: return "rx-overflow";
  }
  return "unknown";
}

std::optional<BusEvent> BusStateTracker::move_to(BusState next, BusEventCause cause) {
  // Same state: only a restart, or a down link that is now removed, is news.
  if (next == state_ && cause != BusEventCause::ControllerRestarted &&
      !(cause == BusEventCause::LinkRemoved && last_cause_ != BusEventCause::LinkRemoved))
    return std::nullopt;
  last_cause_ = cause;
  BusEvent ev;
  ev.previous = state_;
  ev.state = next;
  ev.cause = cause;
  ev.tx_error_counter = tx_errors_;
  ev.rx_error_counter = rx_errors_;
  state_ = next;
  return ev;
}

std::optional<BusEvent> BusStateTracker::on_error_frame(const ErrorFrameInfo& info) {
  if (info.has_counters) {
    tx_errors_ = info.tx_error_counter;
    rx_errors_ = info.rx_error_counter;
  }
  if (info.protocol_error) ++protocol_errors_;
  // A frame can carry several flags; the most severe condition wins.
  if (info.bus_off) return move_to(BusState::BusOff, BusEventCause::ErrorFrame);
  if (info.restarted) return move_to(BusState::ErrorActive, BusEventCause::ControllerRestarted);
  if (info.controller) {
    if (info.rx_passive || info.tx_passive) return move_to(BusState::ErrorPassive, BusEventCause::ErrorFrame);
    if (info.rx_warning || info.tx_warning) return move_to(BusState::ErrorWarning, BusEventCause::ErrorFrame);
    if (info.back_to_active) return move_to(BusState::ErrorActive, BusEventCause::ErrorFrame);
    if (info.rx_overflow) {
      BusEvent ev;
      ev.state = ev.previous = state_;
      ev.cause = BusEventCause::RxOverflow;
      ev.tx_error_counter = tx_errors_;
      ev.rx_error_counter = rx_errors_;
      return ev;
    }
  }
  return std::nullopt;
}

std::optional<BusEvent> BusStateTracker::on_link_down(bool removed) {
  return move_to(BusState::Down, removed ? BusEventCause::LinkRemoved : BusEventCause::LinkDown);
}

std::optional<BusEvent> BusStateTracker::on_link_up() {
  if (state_ != BusState::Down) return std::nullopt;
  tx_errors_ = rx_errors_ = 0;
  return move_to(BusState::ErrorActive, BusEventCause::LinkUp);
}

}  // namespace canopen::can
