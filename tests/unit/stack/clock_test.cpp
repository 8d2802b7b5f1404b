// Tests for stack/src/clock.cpp: the manually advanced FakeClock and its
// one-shot timers.
#include "canopen/clock.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

namespace canopen {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

TEST(FakeClock, StartsAtGivenTimeAndOnlyMovesWhenAdvanced) {
  const TimePoint start = TimePoint{} + seconds(10);
  FakeClock clock(start);
  EXPECT_EQ(clock.now(), start);
  EXPECT_EQ(clock.now(), start);
  clock.advance(milliseconds(250));
  EXPECT_EQ(clock.now(), start + milliseconds(250));
}

TEST(FakeClock, DefaultStartIsNotTheEpoch) {
  // Protocol code may subtract timeouts from now(); the default start leaves room.
  FakeClock clock;
  EXPECT_GT(clock.now(), TimePoint{});
}

TEST(FakeClock, NoTimersMeansNextDeadlineIsMax) {
  FakeClock clock;
  EXPECT_EQ(clock.pending_timers(), 0U);
  EXPECT_EQ(clock.next_deadline(), TimePoint::max());
}

TEST(FakeClock, TimerDoesNotFireBeforeDeadline) {
  FakeClock clock;
  int fired = 0;
  clock.schedule_after(milliseconds(100), [&] { ++fired; });
  clock.advance(milliseconds(99));
  EXPECT_EQ(fired, 0);
  EXPECT_EQ(clock.pending_timers(), 1U);
  clock.advance(milliseconds(1));
  EXPECT_EQ(fired, 1);
  EXPECT_EQ(clock.pending_timers(), 0U);
}

TEST(FakeClock, TimersAreOneShot) {
  FakeClock clock;
  int fired = 0;
  clock.schedule_after(milliseconds(10), [&] { ++fired; });
  clock.advance(seconds(1));
  clock.advance(seconds(1));
  EXPECT_EQ(fired, 1);
}

TEST(FakeClock, TimersFireInDeadlineOrderNotSchedulingOrder) {
  FakeClock clock;
  std::vector<std::string> order;
  clock.schedule_after(milliseconds(30), [&] { order.push_back("30"); });
  clock.schedule_after(milliseconds(10), [&] { order.push_back("10"); });
  clock.schedule_after(milliseconds(20), [&] { order.push_back("20"); });
  clock.advance(milliseconds(100));
  EXPECT_EQ(order, (std::vector<std::string>{"10", "20", "30"}));
}

TEST(FakeClock, EqualDeadlinesFireInSchedulingOrder) {
  FakeClock clock;
  std::vector<int> order;
  for (int i = 0; i < 5; ++i) clock.schedule_after(milliseconds(10), [&order, i] { order.push_back(i); });
  clock.advance(milliseconds(10));
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4}));
}

TEST(FakeClock, CallbackSeesNowEqualToItsDeadline) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  std::vector<TimePoint> seen;
  clock.schedule(start + milliseconds(7), [&] { seen.push_back(clock.now()); });
  clock.schedule(start + milliseconds(3), [&] { seen.push_back(clock.now()); });
  clock.advance(seconds(1));
  EXPECT_EQ(seen, (std::vector<TimePoint>{start + milliseconds(3), start + milliseconds(7)}));
  EXPECT_EQ(clock.now(), start + seconds(1));
}

TEST(FakeClock, AdvanceToMovesToTargetAndFiresDueTimers) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  int fired = 0;
  clock.schedule(start + milliseconds(5), [&] { ++fired; });
  clock.schedule(start + milliseconds(50), [&] { ++fired; });
  clock.advance_to(start + milliseconds(5));
  EXPECT_EQ(fired, 1);
  EXPECT_EQ(clock.now(), start + milliseconds(5));
  EXPECT_EQ(clock.next_deadline(), start + milliseconds(50));
}

TEST(FakeClock, AdvanceToNeverMovesBackwards) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  clock.advance_to(start - seconds(1));
  EXPECT_EQ(clock.now(), start);
}

TEST(FakeClock, CancelPreventsFiring) {
  FakeClock clock;
  int fired = 0;
  const auto id = clock.schedule_after(milliseconds(10), [&] { ++fired; });
  clock.schedule_after(milliseconds(20), [&] { fired += 10; });
  EXPECT_TRUE(clock.cancel(id));
  EXPECT_EQ(clock.pending_timers(), 1U);
  clock.advance(milliseconds(100));
  EXPECT_EQ(fired, 10);
}

TEST(FakeClock, CancelReturnsFalseForFiredOrCancelledOrUnknownTimers) {
  FakeClock clock;
  const auto fired_id = clock.schedule_after(milliseconds(1), [] {});
  const auto cancelled_id = clock.schedule_after(milliseconds(50), [] {});
  clock.advance(milliseconds(1));
  EXPECT_FALSE(clock.cancel(fired_id));
  EXPECT_TRUE(clock.cancel(cancelled_id));
  EXPECT_FALSE(clock.cancel(cancelled_id));
  EXPECT_FALSE(clock.cancel(9999));
}

TEST(FakeClock, TimerIdsAreDistinct) {
  FakeClock clock;
  const auto a = clock.schedule_after(milliseconds(1), [] {});
  const auto b = clock.schedule_after(milliseconds(1), [] {});
  EXPECT_NE(a, b);
}

TEST(FakeClock, NextDeadlineIsEarliestPendingTimer) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  clock.schedule(start + milliseconds(40), [] {});
  const auto early = clock.schedule(start + milliseconds(15), [] {});
  EXPECT_EQ(clock.next_deadline(), start + milliseconds(15));
  clock.cancel(early);
  EXPECT_EQ(clock.next_deadline(), start + milliseconds(40));
}

TEST(FakeClock, TimerScheduledFromCallbackInsideWindowAlsoFires) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  std::vector<TimePoint> seen;
  clock.schedule(start + milliseconds(10), [&] {
    seen.push_back(clock.now());
    clock.schedule_after(milliseconds(10), [&] { seen.push_back(clock.now()); });
  });
  clock.advance(milliseconds(25));
  EXPECT_EQ(seen, (std::vector<TimePoint>{start + milliseconds(10), start + milliseconds(20)}));
  EXPECT_EQ(clock.now(), start + milliseconds(25));
}

TEST(FakeClock, TimerScheduledFromCallbackBeyondWindowWaits) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  int fired = 0;
  clock.schedule(start + milliseconds(10), [&] { clock.schedule_after(milliseconds(20), [&] { ++fired; }); });
  clock.advance(milliseconds(25));
  EXPECT_EQ(fired, 0);
  EXPECT_EQ(clock.next_deadline(), start + milliseconds(30));
  clock.advance(milliseconds(5));
  EXPECT_EQ(fired, 1);
}

TEST(FakeClock, PeriodicTimerReschedulingItselfFiresOncePerPeriod) {
  // Like a heartbeat producer: every 100 ms, re-armed from its own callback.
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  std::vector<TimePoint> beats;
  std::function<void()> beat = [&] {
    beats.push_back(clock.now());
    clock.schedule_after(milliseconds(100), beat);
  };
  clock.schedule_after(milliseconds(100), beat);
  clock.advance(milliseconds(350));
  ASSERT_EQ(beats.size(), 3U);
  EXPECT_EQ(beats[0], start + milliseconds(100));
  EXPECT_EQ(beats[1], start + milliseconds(200));
  EXPECT_EQ(beats[2], start + milliseconds(300));
}

TEST(FakeClock, CallbackCanCancelALaterTimer) {
  FakeClock clock;
  int fired = 0;
  FakeClock::TimerId later = 0;
  clock.schedule_after(milliseconds(10), [&] { EXPECT_TRUE(clock.cancel(later)); });
  later = clock.schedule_after(milliseconds(20), [&] { ++fired; });
  clock.advance(milliseconds(100));
  EXPECT_EQ(fired, 0);
  EXPECT_EQ(clock.pending_timers(), 0U);
}

TEST(FakeClock, TimerInThePastFiresAtNextAdvanceWithoutMovingTimeBack) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  std::vector<TimePoint> seen;
  clock.schedule(start - seconds(5), [&] { seen.push_back(clock.now()); });
  clock.advance(milliseconds(1));
  ASSERT_EQ(seen.size(), 1U);
  EXPECT_EQ(seen[0], start);
}

TEST(FakeClock, RunDueFiresTimersAtCurrentTimeWithoutMovingIt) {
  const TimePoint start = TimePoint{} + seconds(100);
  FakeClock clock(start);
  int fired = 0;
  clock.schedule(start, [&] { ++fired; });
  clock.schedule(start + milliseconds(1), [&] { fired += 10; });
  clock.run_due();
  EXPECT_EQ(fired, 1);
  EXPECT_EQ(clock.now(), start);
}

}  // namespace
}  // namespace canopen
