// Time as the sans-I/O protocol code sees it: a monotonic time point passed
// in by the caller. Production code passes std::chrono::steady_clock::now();
// tests pass FakeClock::now() and move time by hand.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <utility>

namespace canopen {

using SteadyClock = std::chrono::steady_clock;
using TimePoint = SteadyClock::time_point;
using Duration = SteadyClock::duration;

// A manually advanced clock with one-shot timers, for deterministic tests.
// Timers fire in deadline order (ties in scheduling order) with now() equal
// to their deadline, so a callback sees exactly the time it asked for.
// Not thread-safe.
class FakeClock {
 public:
  using TimerId = std::uint64_t;

  explicit FakeClock(TimePoint start = TimePoint{} + std::chrono::hours(1)) : now_(start) {}

  TimePoint now() const { return now_; }

  // Schedules fn at `at` (in the past means: at the next advance). Returns an
  // id for cancel(). fn may schedule or cancel timers.
  TimerId schedule(TimePoint at, std::function<void()> fn);
  TimerId schedule_after(Duration d, std::function<void()> fn) { return schedule(now_ + d, std::move(fn)); }
  // Returns false when the timer already fired or was cancelled.
  bool cancel(TimerId id);

  // Moves time forward to now()+d, firing due timers on the way.
  void advance(Duration d) { advance_to(now_ + d); }
  // Moves time to t (never backwards), firing due timers on the way.
  void advance_to(TimePoint t);
  // Fires timers due at the current time without moving it.
  void run_due() { advance_to(now_); }

  std::size_t pending_timers() const { return timers_.size(); }
  // Deadline of the earliest timer, or TimePoint::max() when none.
  TimePoint next_deadline() const;

 private:
  struct Key {
    TimePoint at;
    TimerId id;
    bool operator<(const Key& o) const { return at != o.at ? at < o.at : id < o.id; }
  };
  TimePoint now_;
  TimerId next_id_ = 1;
  std::map<Key, std::function<void()>> timers_;
};

}  // namespace canopen
