#include "canopen/local_node.hpp"

#include <utility>

#include "canopen/cob_id.hpp"
#include "canopen/emcy/emcy.hpp"
#include "canopen/nmt/nmt.hpp"

namespace canopen {

namespace {

// COB-IDs as the Device's producers read them (their defaults when absent).
std::uint32_t cob_id(const od::ObjectDictionary& od, std::uint16_t index, std::uint32_t fallback) {
  return static_cast<std::uint32_t>(od.get_unsigned(index, 0).value_or(fallback));
}

}  // namespace

LocalNode::LocalNode(od::ObjectDictionary& dictionary, DeviceConfig config, FrameSink bus, FrameSink to_master,
                     DeviceCallbacks callbacks)
    : od_(dictionary),
      bus_(std::move(bus)),
      to_master_(std::move(to_master)),
      user_life_guarding_(std::exchange(callbacks.on_life_guarding, nullptr)),
      device_(dictionary, config, [this](const can::Frame& f) { sent(f); },
              [&callbacks, this] {
                callbacks.on_life_guarding = [this](nmt::LifeGuardingEvent e) { on_life_guarding(e, now_); };
                return std::move(callbacks);
              }()) {
  device_.on_deadline_change([this](TimePoint next) { report_deadline(next); });
}

void LocalNode::sent(const can::Frame& f) {
  bus_(f);
  if (to_master_ && master_hears(f)) to_master_(f);
}

void LocalNode::on_bus_event(const can::BusEvent& ev, TimePoint now) {
  using can::BusState;
  constexpr std::uint8_t kCommunication = emcy::error_register::kCommunication;
  if (ev.state == BusState::ErrorPassive) device_.raise_emcy(kEmcyCanErrorPassive, kCommunication, now);
  if (ev.state == BusState::ErrorActive) device_.clear_emcy(kEmcyCanErrorPassive, now);
  if (ev.cause == can::BusEventCause::RxOverflow) {
    device_.raise_emcy(kEmcyCanOverrun, kCommunication, now);
    device_.clear_emcy(kEmcyCanOverrun, now);
  }
  if (ev.previous == BusState::BusOff && ev.state != BusState::BusOff && ev.state != BusState::Down) {
    device_.raise_emcy(kEmcyRecoveredFromBusOff, kCommunication, now);
    device_.clear_emcy(kEmcyRecoveredFromBusOff, now);
  }
}

void LocalNode::on_node_state(const NodeStateEvent& ev, TimePoint now) {
  const bool was_raised = guard_emcy_raised();
  if (ev.cause == NodeStateEvent::Cause::Lost) {
    lost_.insert(ev.node);
  } else {
    lost_.erase(ev.node);
  }
  update_guard_emcy(was_raised, now);
}

void LocalNode::on_life_guarding(nmt::LifeGuardingEvent e, TimePoint now) {
  const bool was_raised = guard_emcy_raised();
  life_lost_ = e == nmt::LifeGuardingEvent::Occurred;
  update_guard_emcy(was_raised, now);
  if (user_life_guarding_) user_life_guarding_(e);
}

void LocalNode::update_guard_emcy(bool was_raised, TimePoint now) {
  const bool raised = guard_emcy_raised();
  if (raised && !was_raised) device_.raise_emcy(kEmcyLifeGuardOrHeartbeat, emcy::error_register::kCommunication, now);
  if (!raised && was_raised) device_.clear_emcy(kEmcyLifeGuardOrHeartbeat, now);
}

void LocalNode::send_sync(std::optional<std::uint8_t> counter) {
  const std::uint8_t data[1] = {counter.value_or(0)};
  sent(frame_for_cob_id(cob_id(od_, 0x1005, 0x80), data, counter ? 1 : 0));
}

bool LocalNode::master_hears(const can::Frame& own_frame) const {
  if (matches_cob_id(own_frame, cob_id(od_, 0x1005, 0x80))) return true;
  if (matches_cob_id(own_frame, cob_id(od_, 0x1012, 0x100))) return true;
  const std::uint32_t emcy = cob_id(od_, 0x1014, 0x80U + node_id());
  return (emcy & kCobIdBit31) == 0 && matches_cob_id(own_frame, emcy);
}

bool LocalNode::hears(const can::Frame& master_frame) const {
  const auto cmd = nmt::parse_command_frame(master_frame);
  return cmd && (cmd->node == nmt::kAllNodes || cmd->node == node_id());
}

}  // namespace canopen
