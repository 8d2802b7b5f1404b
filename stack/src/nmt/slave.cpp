#include "canopen/nmt/slave.hpp"

#include <algorithm>
#include <chrono>
#include <utility>
#include <variant>

namespace canopen::nmt {

namespace {

constexpr std::uint16_t kGuardTime = 0x100C;
constexpr std::uint16_t kLifeTimeFactor = 0x100D;
constexpr std::uint16_t kProducerHeartbeat = 0x1017;

std::uint64_t unsigned_of(const Value& v) {
  const auto* u = std::get_if<std::uint64_t>(&v.data);
  return u != nullptr ? *u : 0;
}

}  // namespace

NmtSlave::NmtSlave(od::ObjectDictionary& dictionary, std::uint8_t node_id, FrameSink sink, SlaveCallbacks callbacks)
    : od_(&dictionary), node_(node_id), sink_(std::move(sink)), cb_(std::move(callbacks)) {
  // Hooks run before the value is stored and have no time: remember the
  // value and let next_deadline() ask for an on_time() call to apply it.
  od_->on_write(kProducerHeartbeat, [this](od::SubEntry&, const Value& v) {
    pending_heartbeat_ = static_cast<std::uint16_t>(unsigned_of(v));
    return std::error_code{};
  });
  od_->on_write(kGuardTime, [this](od::SubEntry&, const Value& v) {
    pending_guard_time_ = static_cast<std::uint16_t>(unsigned_of(v));
    return std::error_code{};
  });
  od_->on_write(kLifeTimeFactor, [this](od::SubEntry&, const Value& v) {
    pending_life_factor_ = static_cast<std::uint8_t>(unsigned_of(v));
    return std::error_code{};
  });
}

NmtSlave::~NmtSlave() {
  od_->on_write(kProducerHeartbeat, nullptr);
  od_->on_write(kGuardTime, nullptr);
  od_->on_write(kLifeTimeFactor, nullptr);
}

NmtState NmtSlave::nmt_state() const {
  switch (state_) {
    case State::PreOperational: return NmtState::PreOperational;
    case State::Operational: return NmtState::Operational;
    case State::Stopped: return NmtState::Stopped;
    case State::ResetApplication:
    case State::ResetCommunication:
    case State::Initialising: break;
  }
  return NmtState::Initialising;
}

bool NmtSlave::service_active(Service s) const {
  switch (state_) {
    case State::ResetApplication:
    case State::ResetCommunication:
    case State::Initialising:
      return s == Service::BootUp;
    case State::PreOperational:
      return s != Service::Pdo && s != Service::BootUp;
    case State::Operational:
      return s != Service::BootUp;
    case State::Stopped:
      return s == Service::NodeControl || s == Service::ErrorControl;
  }
  return false;
}

void NmtSlave::start(TimePoint now) {
  started_ = true;
  reset(true, now);
}

void NmtSlave::enter(State s) {
  const NmtState before = nmt_state();
  state_ = s;
  const NmtState after = nmt_state();
  if (after != before && after != NmtState::Initialising && cb_.on_state_change) cb_.on_state_change(after, before);
}

void NmtSlave::reset(bool application, TimePoint now) {
  if (application) {
    enter(State::ResetApplication);
    if (cb_.on_reset_application) cb_.on_reset_application();
  }
  enter(State::ResetCommunication);
  if (cb_.on_reset_communication) cb_.on_reset_communication();
  // Reset communication clears the guarding state (7.2.8.3.2.1: the toggle
  // bit is reset only here).
  toggle_ = false;
  guarding_started_ = false;
  life_lost_ = false;
  life_deadline_ = TimePoint::max();
  enter(State::Initialising);
  pending_heartbeat_.reset();
  pending_guard_time_.reset();
  pending_life_factor_.reset();
  heartbeat_period_ = std::chrono::milliseconds(od_->get_unsigned(kProducerHeartbeat, 0).value_or(0));
  guard_time_ms_ = static_cast<std::uint16_t>(od_->get_unsigned(kGuardTime, 0).value_or(0));
  life_factor_ = static_cast<std::uint8_t>(od_->get_unsigned(kLifeTimeFactor, 0).value_or(0));
  life_time_ = std::chrono::milliseconds(std::uint32_t{guard_time_ms_} * life_factor_);
  sink_(make_boot_up_frame(node_));
  // The boot-up message counts as the first heartbeat (7.2.8.3.2.2).
  next_heartbeat_ = heartbeat_period_ > Duration::zero() ? now + heartbeat_period_ : TimePoint::max();
  enter(State::PreOperational);
}

void NmtSlave::command(NmtCommand cs, TimePoint now) {
  if (!started_) return;
  switch (cs) {
    case NmtCommand::Start: enter(State::Operational); break;
    case NmtCommand::Stop: enter(State::Stopped); break;
    case NmtCommand::EnterPreOperational: enter(State::PreOperational); break;
    case NmtCommand::ResetNode: reset(true, now); break;
    case NmtCommand::ResetCommunication: reset(false, now); break;
  }
}

bool NmtSlave::on_frame(const can::Frame& frame, TimePoint now) {
  if (const auto cmd = parse_command_frame(frame)) {
    if (cmd->node != kAllNodes && cmd->node != node_) return false;
    command(cmd->command, now);
    return true;
  }
  if (frame.remote() && !frame.extended() && !frame.fd() && frame.id == kErrorControlBase + node_) {
    on_guard_request(now);
    return true;
  }
  return false;
}

void NmtSlave::on_guard_request(TimePoint now) {
  // Error control runs in every state after initialisation; heartbeat wins
  // over guarding when both are configured.
  if (!started_ || !service_active(Service::ErrorControl) || heartbeat_period_ > Duration::zero()) return;
  sink_(make_error_control_frame(node_, nmt_state(), toggle_));
  toggle_ = !toggle_;
  guarding_started_ = true;
  if (life_time_ > Duration::zero()) life_deadline_ = now + life_time_;
  if (life_lost_) {
    life_lost_ = false;
    if (cb_.on_life_guarding) cb_.on_life_guarding(LifeGuardingEvent::Resolved);
  }
}

TimePoint NmtSlave::next_deadline() const {
  if (pending_heartbeat_ || pending_guard_time_ || pending_life_factor_) return TimePoint::min();
  if (!started_) return TimePoint::max();
  TimePoint next = next_heartbeat_;
  if (!life_lost_) next = std::min(next, life_deadline_);
  return next;
}

void NmtSlave::apply_config(TimePoint now) {
  if (pending_heartbeat_) {
    heartbeat_period_ = std::chrono::milliseconds(*pending_heartbeat_);
    pending_heartbeat_.reset();
    next_heartbeat_ = started_ && heartbeat_period_ > Duration::zero() ? now + heartbeat_period_ : TimePoint::max();
    if (heartbeat_period_ > Duration::zero()) {
      // Heartbeat replaces guarding: life guarding waits for a new first request.
      guarding_started_ = false;
      life_deadline_ = TimePoint::max();
    }
  }
  if (pending_guard_time_ || pending_life_factor_) {
    if (pending_guard_time_) guard_time_ms_ = *pending_guard_time_;
    if (pending_life_factor_) life_factor_ = *pending_life_factor_;
    pending_guard_time_.reset();
    pending_life_factor_.reset();
    life_time_ = std::chrono::milliseconds(std::uint32_t{guard_time_ms_} * life_factor_);
    // A new life time counts from now; 0 switches life guarding off.
    life_deadline_ = guarding_started_ && life_time_ > Duration::zero() ? now + life_time_ : TimePoint::max();
  }
}

void NmtSlave::reconfigure(TimePoint now) {
  pending_heartbeat_ = static_cast<std::uint16_t>(od_->get_unsigned(kProducerHeartbeat, 0).value_or(0));
  pending_guard_time_ = static_cast<std::uint16_t>(od_->get_unsigned(kGuardTime, 0).value_or(0));
  pending_life_factor_ = static_cast<std::uint8_t>(od_->get_unsigned(kLifeTimeFactor, 0).value_or(0));
  apply_config(now);
}

void NmtSlave::on_time(TimePoint now) {
  apply_config(now);
  if (!started_) return;
  if (now >= next_heartbeat_) {
    if (service_active(Service::ErrorControl)) sink_(make_error_control_frame(node_, nmt_state()));
    // Keep the grid: a late call does not shift later heartbeats, and
    // missed periods are not sent in a burst.
    while (next_heartbeat_ <= now) next_heartbeat_ += heartbeat_period_;
  }
  if (!life_lost_ && now >= life_deadline_) {
    life_lost_ = true;
    if (cb_.on_life_guarding) cb_.on_life_guarding(LifeGuardingEvent::Occurred);
  }
}

}  // namespace canopen::nmt
