// The publisher's stall decision on a fake clock (issue 12, item 5): the
// sync timer running between a publish and its send is normal operation;
// only a real stall (no acknowledgement while in flight, or messages left
// waiting with nothing scheduled to send them) restarts delivery.
#include "mqtt/stall_detector.hpp"

#include <gtest/gtest.h>

#include "canopen/clock.hpp"

using gateway::mqtt::StallDetector;
using Verdict = StallDetector::Verdict;
using namespace std::chrono_literals;

namespace {

struct Rig {
  canopen::FakeClock clock;
  StallDetector det;
  Rig() { det.reset(clock.now()); }
  // Checks every 100 ms (the sync timer) for `d` with the same observation;
  // returns the first verdict other than Ok (Ok if none).
  Verdict run(std::chrono::milliseconds d, StallDetector::Observation o) {
    for (auto t = 0ms; t < d; t += 100ms) {
      clock.advance(100ms);
      if (auto v = det.check(clock.now(), o); v != Verdict::Ok) return v;
    }
    return Verdict::Ok;
  }
};

const StallDetector::Observation kPushedNotYetSent{0, true, true};  // pump posted
const StallDetector::Observation kWaitingUnscheduled{0, true, false};
const StallDetector::Observation kInFlight{16, true, false};
const StallDetector::Observation kIdle{0, false, false};

}  // namespace

// The race of the old check: a publish queued a message and posted its
// pump; the timer ran first and saw "pending, nothing in flight". However
// often that happens (a slow machine: every tick), it is no stall.
TEST(StallDetector, PushThenTickRaceIsNotAStall) {
  Rig r;
  EXPECT_EQ(r.run(120s, kPushedNotYetSent), Verdict::Ok);
  // Alternating with the send going out and being acknowledged.
  for (int i = 0; i < 600; ++i) {
    r.clock.advance(100ms);
    ASSERT_EQ(r.det.check(r.clock.now(), i % 2 == 0 ? kPushedNotYetSent : kInFlight), Verdict::Ok) << i;
    r.det.progress(r.clock.now());
  }
}

// Messages waiting with nothing in flight and nothing scheduled: a stall
// once that lasted the idle timeout, not before.
TEST(StallDetector, WaitingWithNothingScheduledIsAStallAfterTheIdleTimeout) {
  Rig r;
  EXPECT_EQ(r.run(4800ms, kWaitingUnscheduled), Verdict::Ok);
  EXPECT_EQ(r.run(400ms, kWaitingUnscheduled), Verdict::Idle);
  // It starts over: the next verdict needs a whole timeout again.
  EXPECT_EQ(r.run(4800ms, kWaitingUnscheduled), Verdict::Ok);
  EXPECT_EQ(r.run(400ms, kWaitingUnscheduled), Verdict::Idle);
}

// A moment of waiting that resolves (the send got scheduled) restarts the
// idle clock.
TEST(StallDetector, BriefWaitsDoNotAddUp) {
  Rig r;
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(r.run(3s, kWaitingUnscheduled), Verdict::Ok) << i;
    ASSERT_EQ(r.run(100ms, kPushedNotYetSent), Verdict::Ok) << i;
  }
}

// In flight without any acknowledgement for 30 s: a stall.
TEST(StallDetector, NoAcknowledgementFor30sWhileInFlightIsAStall) {
  Rig r;
  EXPECT_EQ(r.run(29s, kInFlight), Verdict::Ok);
  EXPECT_EQ(r.run(2s, kInFlight), Verdict::NoProgress);
}

// Acknowledgements keep coming: never a stall, however long it runs.
TEST(StallDetector, SteadyProgressIsNeverAStall) {
  Rig r;
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(r.run(20s, kInFlight), Verdict::Ok) << i;
    r.det.progress(r.clock.now());
  }
}

// After an hour without traffic (no progress because nothing was sent),
// the first message in flight gets the full 30 s.
TEST(StallDetector, FirstMessageAfterALongIdleSpellGetsTheFullTimeout) {
  Rig r;
  EXPECT_EQ(r.run(3600s, kIdle), Verdict::Ok);
  EXPECT_EQ(r.run(29s, kInFlight), Verdict::Ok);
  EXPECT_EQ(r.run(2s, kInFlight), Verdict::NoProgress);
}

// A reconnect (reset) starts the timeouts over.
TEST(StallDetector, ResetStartsOver) {
  Rig r;
  EXPECT_EQ(r.run(25s, kInFlight), Verdict::Ok);
  r.det.reset(r.clock.now());
  EXPECT_EQ(r.run(29s, kInFlight), Verdict::Ok);
}
