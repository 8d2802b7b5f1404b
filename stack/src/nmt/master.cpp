#include "canopen/nmt/master.hpp"

#include <algorithm>
#include <chrono>
#include <utility>
#include <variant>

namespace canopen::nmt {

namespace {
constexpr std::uint16_t kConsumerHeartbeat = 0x1016;
bool valid_node(std::uint8_t node) { return node >= 1 && node <= kMaxNodeId; }
}  // namespace

Duration producer_heartbeat_time(const od::ObjectDictionary& description) {
  return std::chrono::milliseconds(description.get_unsigned(0x1017, 0).value_or(0) & 0xFFFFU);
}

NmtMaster::NmtMaster(FrameSink sink, EventSink events) : sink_(std::move(sink)), events_(std::move(events)) {}

bool NmtMaster::send_command(NmtCommand cs, std::uint8_t node) {
  if (node > kMaxNodeId) return false;
  sink_(make_command_frame(cs, node));
  return true;
}

void NmtMaster::emit(const EventBody& body, can::Frame::Clock::time_point ts) {
  if (events_) events_(body, ts);
}

bool NmtMaster::on_frame(const can::Frame& frame, TimePoint now) {
  const auto node = error_control_node(frame);
  if (!node || frame.remote() || frame.len < 1) return false;
  const std::uint8_t byte = frame.data[0];
  // Boot-up first: a guarding response never carries state 0, and a node
  // that rebooted while a request was outstanding must still count as booted.
  if (byte == 0x00) {
    on_boot_up(*node, frame, now);
    return true;
  }
  if (auto g = guarding_.find(*node); g != guarding_.end() && g->second.awaiting) {
    on_guard_response(*node, g->second, byte, frame, now);
    return true;
  }
  const auto s = nmt_state_from_byte(byte);
  if (!s || *s == NmtState::Initialising) return true;  // ours, but not a state we know: ignored
  on_heartbeat(*node, *s, frame, now);
  return true;
}

void NmtMaster::report_state(std::uint8_t node, NmtState s, NodeStateEvent::Cause cause, const can::Frame& f) {
  NodeStatus& st = nodes_[node];
  const std::optional<NmtState> previous = st.state;
  st.state = s;
  if (st.lost) {
    st.lost = false;
    emit(NodeStateEvent{node, s, previous, NodeStateEvent::Cause::Recovered}, f.timestamp);
  } else if (previous != s) {
    emit(NodeStateEvent{node, s, previous, cause}, f.timestamp);
  }
}

void NmtMaster::on_boot_up(std::uint8_t node, const can::Frame& f, TimePoint now) {
  NodeStatus& st = nodes_[node];
  const std::optional<NmtState> previous = st.state;
  ++st.boot_ups;
  // The boot-up message carries state 0, initialising (7.2.8.3.3); the node
  // then enters pre-operational by itself, which its next heartbeat or
  // guarding response reports as a change.
  st.state = NmtState::Initialising;
  st.last_seen = now;
  auto_heard(node, now, true, st.lost);
  st.lost = false;
  if (auto c = consumers_.find(node); c != consumers_.end()) c->second.deadline = now + c->second.time;
  if (auto g = guarding_.find(node); g != guarding_.end()) {
    // The node reset communication: its next guarding response has toggle 0.
    g->second.last_toggle = true;
    g->second.life_deadline = now + g->second.guard_time * g->second.life_factor;
  }
  emit(NodeStateEvent{node, NmtState::Initialising, previous, NodeStateEvent::Cause::BootUp}, f.timestamp);
}

void NmtMaster::on_heartbeat(std::uint8_t node, NmtState s, const can::Frame& f, TimePoint now) {
  NodeStatus& st = nodes_[node];
  ++st.heartbeats;
  st.last_seen = now;
  auto_heard(node, now, false, st.lost);
  if (auto c = consumers_.find(node); c != consumers_.end()) c->second.deadline = now + c->second.time;
  emit(HeartbeatEvent{node, s}, f.timestamp);
  report_state(node, s, NodeStateEvent::Cause::Heartbeat, f);
}

void NmtMaster::on_guard_response(std::uint8_t node, Guarding& g, std::uint8_t byte, const can::Frame& f,
                                  TimePoint now) {
  NodeStatus& st = nodes_[node];
  const bool toggle = (byte & kToggleBit) != 0;
  const auto s = nmt_state_from_byte(byte);
  if (toggle == g.last_toggle) {
    // 7.2.8.3.2.1: of two responses with the same toggle bit the later is ignored.
    ++st.toggle_errors;
    return;
  }
  if (!s || *s == NmtState::Initialising) return;
  g.last_toggle = toggle;
  g.awaiting = false;
  g.life_deadline = now + g.guard_time * g.life_factor;
  st.last_seen = now;
  report_state(node, *s, NodeStateEvent::Cause::NodeGuarding, f);
}

void NmtMaster::lose(std::uint8_t node) {
  NodeStatus& st = nodes_[node];
  if (st.lost) return;
  st.lost = true;
  emit(NodeStateEvent{node, std::nullopt, st.state, NodeStateEvent::Cause::Lost}, {});
}

Duration NmtMaster::AutoWatch::p() const {
  if (!enabled) return Duration::zero();
  Duration longest = period;  // a given period is a floor (see the header)
  for (std::size_t k = 0; k < count; ++k) longest = std::max(longest, intervals[k]);
  return longest;
}

void NmtMaster::auto_heard(std::uint8_t node, TimePoint now, bool boot_up, bool was_lost) {
  AutoWatch& w = auto_[node];
  if (!w.enabled) return;
  const auto record = [&w](Duration interval) {
    w.intervals[w.next] = interval;
    w.next = (w.next + 1) % kLearnWindow;
    w.count = std::min(w.count + 1, kLearnWindow);
  };
  if (was_lost) {
    // The gap was no period; the node may come back with another one.
    const Duration p_before = w.p();
    w.count = w.next = 0;
    // Unless it is the second same gap in a row: a producer slower than 3P.
    const Duration gap = w.last_heartbeat && !boot_up ? now - *w.last_heartbeat : Duration::zero();
    const Duration previous = std::exchange(w.recovered_gap, gap);
    constexpr int kSlowProducerGap = 10;
    if (gap > Duration::zero() && previous > Duration::zero() && gap <= kSlowProducerGap * p_before &&
        std::chrono::abs(gap - previous) <= previous / 8) {
      record(gap);
      w.recovered_gap = Duration::zero();
    }
  } else {
    w.recovered_gap = Duration::zero();
    if (!boot_up && w.last_heartbeat) record(now - *w.last_heartbeat);
  }
  // After a boot-up the first heartbeat may follow at any time (7.2.8.3.2.2
  // allows the boot-up to count as the first one): no interval from it.
  w.last_heartbeat = boot_up ? std::nullopt : std::optional<TimePoint>(now);
  const Duration p = w.p();
  w.deadline = p > Duration::zero() ? now + 3 * p : TimePoint::max();
}

bool NmtMaster::set_auto_watch(std::uint8_t node, bool enabled, Duration period) {
  const Report<NmtMaster> deadline_report(*this);  // the driver follows
  if (!valid_node(node)) return false;
  AutoWatch& w = auto_[node];
  if (!enabled) {
    w = AutoWatch{};
    w.enabled = false;
    return true;
  }
  w.enabled = true;
  w.period = std::max(period, Duration::zero());
  // From the next heartbeat on; until then the deadline in force stays.
  return true;
}

bool NmtMaster::set_producer_time(std::uint8_t node, Duration time, TimePoint now) {
  const Report<NmtMaster> deadline_report(*this);
  if (!valid_node(node)) return false;
  AutoWatch& w = auto_[node];
  if (!w.enabled) return true;
  w.period = std::max(time, Duration::zero());
  w.count = w.next = 0;  // intervals of the old period
  w.recovered_gap = Duration::zero();
  w.deadline = w.period > Duration::zero() ? now + 3 * w.period : TimePoint::max();
  return true;
}

Duration NmtMaster::auto_watch_period(std::uint8_t node) const {
  const auto it = auto_.find(node);
  return it == auto_.end() || has_explicit_watch(node) ? Duration::zero() : it->second.p();
}

TimePoint NmtMaster::next_deadline() const {
  TimePoint next = TimePoint::max();
  for (const auto& [node, c] : consumers_) next = std::min(next, c.deadline);
  for (const auto& [node, w] : auto_) {
    if (!has_explicit_watch(node)) next = std::min(next, w.deadline);
  }
  for (const auto& [node, g] : guarding_) next = std::min({next, g.next_request, g.life_deadline});
  return next;
}

void NmtMaster::on_time(TimePoint now) {
  for (auto& [node, c] : consumers_) {
    if (now >= c.deadline) {
      c.deadline = TimePoint::max();  // until the next heartbeat
      lose(node);
    }
  }
  for (auto& [node, w] : auto_) {
    if (now >= w.deadline && !has_explicit_watch(node)) {
      w.deadline = TimePoint::max();  // until the next heartbeat
      lose(node);
    }
  }
  for (auto& [node, g] : guarding_) {
    if (now >= g.next_request) {
      sink_(make_guard_request(node));
      g.awaiting = true;
      while (g.next_request <= now) g.next_request += g.guard_time;
    }
    if (now >= g.life_deadline) {
      g.life_deadline = TimePoint::max();  // until the next accepted response
      lose(node);
    }
  }
}

bool NmtMaster::set_heartbeat_consumer(std::uint8_t node, Duration time) {
  const Report<NmtMaster> deadline_report(*this);  // the driver follows
  if (!valid_node(node)) return false;
  if (time <= Duration::zero()) {
    consumers_.erase(node);
    return true;
  }
  auto [it, inserted] = consumers_.try_emplace(node);
  if (inserted || it->second.time != time) it->second = Consumer{time, TimePoint::max()};
  return true;
}

void NmtMaster::configure_consumers(const od::ObjectDictionary& dictionary) {
  const Report<NmtMaster> deadline_report(*this);  // the driver follows
  std::map<std::uint8_t, Duration> wanted;
  if (const od::Object* obj = dictionary.find(kConsumerHeartbeat)) {
    for (const auto& [sub, entry] : obj->subs) {
      if (sub == 0) continue;
      const auto* v = std::get_if<std::uint64_t>(&entry.value.data);
      if (v == nullptr) continue;
      const auto node = static_cast<std::uint8_t>((*v >> 16) & 0xFFU);
      const auto ms = static_cast<std::uint16_t>(*v & 0xFFFFU);
      if (ms == 0 || !valid_node(node)) continue;
      wanted[node] = std::chrono::milliseconds(ms);
    }
  }
  std::erase_if(consumers_, [&](const auto& kv) { return !wanted.contains(kv.first); });
  for (const auto& [node, time] : wanted) set_heartbeat_consumer(node, time);
}

bool NmtMaster::set_node_guarding(std::uint8_t node, Duration guard_time, std::uint8_t life_time_factor,
                                  TimePoint now) {
  const Report<NmtMaster> deadline_report(*this);  // the driver follows
  if (!valid_node(node)) return false;
  if (guard_time <= Duration::zero() || life_time_factor == 0) {
    guarding_.erase(node);
    return true;
  }
  Guarding g;
  g.guard_time = guard_time;
  g.life_factor = life_time_factor;
  g.next_request = now;
  g.life_deadline = now + guard_time * life_time_factor;
  guarding_[node] = g;
  return true;
}

const NodeStatus* NmtMaster::node(std::uint8_t id) const {
  const auto it = nodes_.find(id);
  return it == nodes_.end() ? nullptr : &it->second;
}

}  // namespace canopen::nmt
