#include "canopen/clock.hpp"

#include <algorithm>

namespace canopen {

FakeClock::TimerId FakeClock::schedule(TimePoint at, std::function<void()> fn) {
  const TimerId id = next_id_++;
  timers_.emplace(Key{at, id}, std::move(fn));
  return id;
}

bool FakeClock::cancel(TimerId id) {
  auto it = std::find_if(timers_.begin(), timers_.end(), [id](const auto& kv) { return kv.first.id == id; });
  if (it == timers_.end()) return false;
  timers_.erase(it);
  return true;
}

void FakeClock::advance_to(TimePoint t) {
  t = std::max(t, now_);
  while (!timers_.empty() && timers_.begin()->first.at <= t) {
    auto node = timers_.extract(timers_.begin());
    now_ = std::max(now_, node.key().at);
    node.mapped()();
  }
  now_ = t;
}

TimePoint FakeClock::next_deadline() const {
  return timers_.empty() ? TimePoint::max() : timers_.begin()->first.at;
}

}  // namespace canopen
