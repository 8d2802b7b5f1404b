// Tests for stack/src/can/memory_bus.cpp: the in-memory CAN bus used by the
// protocol unit tests (delivery rules, re-entrancy and fault injection).
#include "canopen/can/memory_bus.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace canopen::can {
namespace {

// Records everything an endpoint receives and reports.
struct Recorder {
  std::vector<Frame> frames;
  std::vector<std::size_t> batch_sizes;
  std::vector<BusEvent> events;

  void attach_to(Channel& ch) {
    ch.on_frames([this](std::span<const Frame> fs) {
      batch_sizes.push_back(fs.size());
      frames.insert(frames.end(), fs.begin(), fs.end());
    });
    ch.on_bus_event([this](const BusEvent& ev) { events.push_back(ev); });
  }
};

Frame numbered(std::uint32_t id, std::uint8_t n) { return Frame::standard(id, {n}); }

std::vector<std::uint8_t> first_bytes(const std::vector<Frame>& frames) {
  std::vector<std::uint8_t> out;
  for (const auto& f : frames) out.push_back(f.data[0]);
  return out;
}

TEST(MemoryBus, EveryOtherEndpointReceivesAndSenderDoesNot) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  Recorder ra, rb, rc;
  ra.attach_to(*a);
  rb.attach_to(*b);
  rc.attach_to(*c);

  const Frame f = Frame::standard(0x181, {1, 2, 3});
  EXPECT_EQ(a->send(f), SendStatus::Accepted);
  EXPECT_EQ(bus.deliver(), 1U);

  EXPECT_TRUE(ra.frames.empty());
  ASSERT_EQ(rb.frames.size(), 1U);
  ASSERT_EQ(rc.frames.size(), 1U);
  EXPECT_EQ(rb.frames[0], f);
  EXPECT_EQ(rc.frames[0], f);
  EXPECT_EQ(a->stats().tx_frames, 1U);
  EXPECT_EQ(a->stats().rx_frames, 0U);
  EXPECT_EQ(b->stats().rx_frames, 1U);
  EXPECT_EQ(c->stats().rx_frames, 1U);
}

TEST(MemoryBus, SendOnlyQueuesUntilDeliver) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  a->send(numbered(0x100, 1));
  a->send(numbered(0x100, 2));
  EXPECT_TRUE(rb.frames.empty());
  EXPECT_EQ(bus.pending(), 2U);
  EXPECT_EQ(bus.frames_sent(), 2U);
}

TEST(MemoryBus, DeliverOneStepsFrameByFrame) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  a->send(numbered(0x100, 1));
  a->send(numbered(0x100, 2));
  EXPECT_TRUE(bus.deliver_one());
  EXPECT_EQ(first_bytes(rb.frames), (std::vector<std::uint8_t>{1}));
  EXPECT_EQ(bus.pending(), 1U);
  EXPECT_TRUE(bus.deliver_one());
  EXPECT_EQ(first_bytes(rb.frames), (std::vector<std::uint8_t>{1, 2}));
  EXPECT_FALSE(bus.deliver_one());
  EXPECT_EQ(bus.deliver(), 0U);
}

TEST(MemoryBus, KeepsSendOrderAcrossSenders) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  Recorder rc;
  rc.attach_to(*c);
  for (std::uint8_t i = 0; i < 50; ++i) {
    (i % 2 == 0 ? *a : *b).send(numbered(0x200, i));
  }
  EXPECT_EQ(bus.deliver(), 50U);
  std::vector<std::uint8_t> want(50);
  for (std::uint8_t i = 0; i < 50; ++i) want[i] = i;
  EXPECT_EQ(first_bytes(rc.frames), want);
  // One handler call per frame.
  EXPECT_EQ(rc.batch_sizes, std::vector<std::size_t>(50, 1));
}

TEST(MemoryBus, DeliverIncludesFramesSentByHandlersDuringDelivery) {
  MemoryBus bus;
  auto client = bus.attach("client");
  auto server = bus.attach("server");
  Recorder rclient;
  rclient.attach_to(*client);
  // The server answers every request (0x600) with a response (0x580).
  server->on_frames([&](std::span<const Frame> fs) {
    for (const auto& f : fs) {
      if (f.id == 0x600) server->send(Frame::standard(0x580, {f.data[0]}));
    }
  });
  client->send(numbered(0x600, 7));
  client->send(numbered(0x600, 8));
  EXPECT_EQ(bus.deliver(), 4U);
  EXPECT_EQ(bus.pending(), 0U);
  ASSERT_EQ(rclient.frames.size(), 2U);
  EXPECT_EQ(rclient.frames[0], numbered(0x580, 7));
  EXPECT_EQ(rclient.frames[1], numbered(0x580, 8));
}

TEST(MemoryBus, ReplyIsNotReceivedInsideTheSendThatCausedIt) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  bool in_send = false;
  bool received_inside_send = false;
  b->on_frames([&](std::span<const Frame>) { received_inside_send = received_inside_send || in_send; });
  in_send = true;
  a->send(numbered(0x100, 1));
  in_send = false;
  bus.deliver();
  EXPECT_FALSE(received_inside_send);
}

TEST(MemoryBus, DeliverStopsAtMaxFramesToGuardAgainstPingPong) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  a->on_frames([&](std::span<const Frame> fs) { a->send(fs[0]); });
  b->on_frames([&](std::span<const Frame> fs) { b->send(fs[0]); });
  a->send(numbered(0x100, 1));
  EXPECT_EQ(bus.deliver(100), 100U);
  EXPECT_EQ(bus.pending(), 1U);
}

TEST(MemoryBus, InvalidFrameIsRejectedAndCounted) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  EXPECT_EQ(a->send(Frame::standard(0x800, {1})), SendStatus::Invalid);
  EXPECT_EQ(bus.pending(), 0U);
  EXPECT_EQ(bus.frames_sent(), 0U);
  EXPECT_EQ(a->stats().tx_dropped, 1U);
  EXPECT_EQ(a->stats().tx_frames, 0U);
}

TEST(MemoryBus, FdAndExtendedFramesPassUnchanged) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  std::vector<std::uint8_t> bytes(64);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 3);
  Frame fd = Frame::extended_id(0x1FFFFFFF, bytes);
  fd.set(FrameFlag::BitRateSwitch);
  ASSERT_TRUE(fd.valid());
  EXPECT_EQ(a->send(fd), SendStatus::Accepted);
  EXPECT_EQ(a->send(Frame::rtr(0x123, 5)), SendStatus::Accepted);
  bus.deliver();
  ASSERT_EQ(rb.frames.size(), 2U);
  EXPECT_EQ(rb.frames[0], fd);
  EXPECT_EQ(rb.frames[1], Frame::rtr(0x123, 5));
}

TEST(MemoryBus, EndpointReportsNameAndStartsErrorActive) {
  MemoryBus bus;
  auto a = bus.attach("can-sim0");
  EXPECT_EQ(a->name(), "can-sim0");
  EXPECT_EQ(a->state(), BusState::ErrorActive);
}

TEST(MemoryBus, HandlerDestroyingItsOwnEndpointIsSafe) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  Recorder rc;
  rc.attach_to(*c);
  int b_calls = 0;
  b->on_frames([&](std::span<const Frame>) {
    ++b_calls;
    b.reset();  // last statement: the handler is gone afterwards
  });
  a->send(numbered(0x100, 1));
  a->send(numbered(0x100, 2));
  EXPECT_EQ(bus.deliver(), 2U);
  EXPECT_EQ(b, nullptr);
  EXPECT_EQ(b_calls, 1);
  EXPECT_EQ(first_bytes(rc.frames), (std::vector<std::uint8_t>{1, 2}));
}

TEST(MemoryBus, HandlerDestroyingAnEndpointThatAlreadyReceivedIsSafe) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  Recorder rb;
  rb.attach_to(*b);
  c->on_frames([&](std::span<const Frame>) { b.reset(); });  // b is before c
  a->send(numbered(0x100, 1));
  a->send(numbered(0x100, 2));
  EXPECT_EQ(bus.deliver(), 2U);
  EXPECT_EQ(first_bytes(rb.frames), (std::vector<std::uint8_t>{1}));
}

// A handler destroys an endpoint that comes *after* it in the delivery list
// while the frame is still being handed out. The destroyed endpoint must be
// skipped without touching it. Run in a child process so that a sanitizer
// report fails this test only, not the whole binary.
TEST(MemoryBusDeathTest, HandlerDestroyingAnEndpointNotYetDeliveredToIsSafe) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        MemoryBus bus;
        auto a = bus.attach("a");
        auto b = bus.attach("b");
        auto c = bus.attach("c");
        auto d = bus.attach("d");
        int c_calls = 0;
        int d_calls = 0;
        b->on_frames([&](std::span<const Frame>) { c.reset(); });
        c->on_frames([&](std::span<const Frame>) { ++c_calls; });
        d->on_frames([&](std::span<const Frame>) { ++d_calls; });
        a->send(numbered(0x100, 1));
        const std::size_t n = bus.deliver();
        const bool ok = n == 1 && c == nullptr && c_calls == 0 && d_calls == 1;
        std::exit(ok ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

// Delivery targets are the endpoints attached when the frame is handed out.
// A handler that destroys one endpoint and attaches another must not make the
// new one receive the frame being delivered (it was sent before the new
// endpoint existed), whatever address the allocator gives the new endpoint.
TEST(MemoryBusDeathTest, EndpointAttachedInPlaceOfDestroyedOneDoesNotGetCurrentFrame) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        MemoryBus bus;
        auto a = bus.attach("a");
        auto b = bus.attach("b");
        auto c = bus.attach("c");
        std::unique_ptr<MemoryEndpoint> late;
        int late_calls = 0;
        b->on_frames([&](std::span<const Frame>) {
          if (late) return;
          c.reset();
          late = bus.attach("late");
          late->on_frames([&](std::span<const Frame>) { ++late_calls; });
        });
        a->send(numbered(0x100, 1));
        bus.deliver();
        std::exit(late_calls == 0 ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST(MemoryBus, BusKeepsWorkingAfterEndpointsDestroyedDuringDelivery) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  auto d = bus.attach("d");
  Recorder ra, rd;
  ra.attach_to(*a);
  rd.attach_to(*d);
  // b destroys c and itself on the first frame.
  b->on_frames([&](std::span<const Frame>) {
    c.reset();
    b.reset();
  });
  a->send(numbered(0x100, 1));
  EXPECT_EQ(bus.deliver(), 1U);
  EXPECT_EQ(b, nullptr);
  EXPECT_EQ(c, nullptr);

  auto e = bus.attach("e");
  Recorder re;
  re.attach_to(*e);
  a->send(numbered(0x100, 2));
  d->send(numbered(0x100, 3));
  EXPECT_EQ(bus.deliver(), 2U);
  EXPECT_EQ(first_bytes(rd.frames), (std::vector<std::uint8_t>{1, 2}));
  EXPECT_EQ(first_bytes(re.frames), (std::vector<std::uint8_t>{2, 3}));
  EXPECT_EQ(first_bytes(ra.frames), (std::vector<std::uint8_t>{3}));
}

TEST(MemoryBus, EndpointAttachedByHandlerJoinsAfterTheCurrentFrame) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  std::unique_ptr<MemoryEndpoint> late;
  Recorder rlate;
  b->on_frames([&](std::span<const Frame>) {
    if (!late) {
      late = bus.attach("late");
      rlate.attach_to(*late);
    }
  });
  a->send(numbered(0x100, 1));
  a->send(numbered(0x100, 2));
  EXPECT_EQ(bus.deliver(), 2U);
  EXPECT_EQ(first_bytes(rlate.frames), (std::vector<std::uint8_t>{2}));
}

TEST(MemoryBus, HandlerDestroyingAnEndpointItJustAttachedIsSafe) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  Recorder rc;
  rc.attach_to(*c);
  b->on_frames([&](std::span<const Frame>) {
    auto tmp = bus.attach("tmp");
    tmp.reset();
  });
  a->send(numbered(0x100, 1));
  a->send(numbered(0x100, 2));
  EXPECT_EQ(bus.deliver(), 2U);
  EXPECT_EQ(first_bytes(rc.frames), (std::vector<std::uint8_t>{1, 2}));
}

TEST(MemoryBus, NestedDeliveryFromHandlerDeliversEachFrameOncePerReceiver) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  auto d = bus.attach("d");
  Recorder rc;
  rc.attach_to(*c);
  int nested = 0;
  b->on_frames([&](std::span<const Frame>) {
    if (nested++ == 0) {
      d.reset();      // destroyed inside the nested delivery's outer frame
      bus.deliver();  // a handler pumping the bus itself
    }
  });
  for (std::uint8_t i = 0; i < 3; ++i) a->send(numbered(0x100, i));
  bus.deliver();
  EXPECT_EQ(bus.pending(), 0U);
  auto got = first_bytes(rc.frames);
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, (std::vector<std::uint8_t>{0, 1, 2}));
  EXPECT_EQ(nested, 3);
  // The bus is consistent afterwards.
  auto e = bus.attach("e");
  Recorder re;
  re.attach_to(*e);
  a->send(numbered(0x100, 9));
  bus.deliver();
  EXPECT_EQ(first_bytes(re.frames), (std::vector<std::uint8_t>{9}));
  EXPECT_EQ(rc.frames.size(), 4U);
}

TEST(MemoryBus, FramesFromDestroyedSenderStillReachOthers) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  a->send(numbered(0x100, 1));
  a.reset();
  EXPECT_EQ(bus.deliver(), 1U);
  EXPECT_EQ(first_bytes(rb.frames), (std::vector<std::uint8_t>{1}));
}

TEST(MemoryBus, EndpointAttachedLaterReceivesLaterFrames) {
  MemoryBus bus;
  auto a = bus.attach("a");
  a->send(numbered(0x100, 1));
  bus.deliver();
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  a->send(numbered(0x100, 2));
  bus.deliver();
  EXPECT_EQ(first_bytes(rb.frames), (std::vector<std::uint8_t>{2}));
}

// ---- link state ------------------------------------------------------------

TEST(MemoryBus, LinkDownEndpointNeitherSendsNorReceives) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder ra, rb;
  ra.attach_to(*a);
  rb.attach_to(*b);

  b->set_link_up(false);
  EXPECT_EQ(b->state(), BusState::Down);
  EXPECT_EQ(b->send(numbered(0x100, 1)), SendStatus::QueueFull);
  EXPECT_EQ(b->stats().tx_dropped, 1U);
  EXPECT_EQ(bus.pending(), 0U);

  a->send(numbered(0x100, 2));
  bus.deliver();
  EXPECT_TRUE(rb.frames.empty());
  EXPECT_TRUE(ra.frames.empty());
  EXPECT_EQ(b->stats().rx_frames, 0U);
}

TEST(MemoryBus, LinkChangesAreReportedAsBusEvents) {
  MemoryBus bus;
  auto a = bus.attach("a");
  Recorder ra;
  ra.attach_to(*a);

  a->set_link_up(false);
  ASSERT_EQ(ra.events.size(), 1U);
  EXPECT_EQ(ra.events[0].cause, BusEventCause::LinkDown);
  EXPECT_EQ(ra.events[0].previous, BusState::ErrorActive);
  EXPECT_EQ(ra.events[0].state, BusState::Down);

  a->set_link_up(false);  // no change, no event
  EXPECT_EQ(ra.events.size(), 1U);

  a->set_link_up(true);
  ASSERT_EQ(ra.events.size(), 2U);
  EXPECT_EQ(ra.events[1].cause, BusEventCause::LinkUp);
  EXPECT_EQ(ra.events[1].previous, BusState::Down);
  EXPECT_EQ(ra.events[1].state, BusState::ErrorActive);

  a->set_link_up(true);  // already up
  EXPECT_EQ(ra.events.size(), 2U);
}

TEST(MemoryBus, EndpointBackUpSendsAndReceivesAgain) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder ra, rb;
  ra.attach_to(*a);
  rb.attach_to(*b);
  b->set_link_up(false);
  a->send(numbered(0x100, 1));
  bus.deliver();
  b->set_link_up(true);
  a->send(numbered(0x100, 2));
  EXPECT_EQ(b->send(numbered(0x100, 3)), SendStatus::Accepted);
  bus.deliver();
  EXPECT_EQ(first_bytes(rb.frames), (std::vector<std::uint8_t>{2}));
  EXPECT_EQ(first_bytes(ra.frames), (std::vector<std::uint8_t>{3}));
}

// ---- timestamps ------------------------------------------------------------

TEST(MemoryBus, TimeSourceStampsFrames) {
  MemoryBus bus;
  const auto t0 = Frame::Clock::time_point(std::chrono::seconds(1'700'000'000));
  auto t = t0;
  bus.set_time_source([&] { return t; });
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  a->send(numbered(0x100, 1));
  t += std::chrono::milliseconds(5);
  a->send(numbered(0x100, 2));
  bus.deliver();
  ASSERT_EQ(rb.frames.size(), 2U);
  EXPECT_EQ(rb.frames[0].timestamp, t0);
  EXPECT_EQ(rb.frames[1].timestamp, t0 + std::chrono::milliseconds(5));
}

TEST(MemoryBus, WithoutTimeSourceSenderTimestampIsKept) {
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  Frame f = numbered(0x100, 1);
  f.timestamp = Frame::Clock::time_point(std::chrono::seconds(42));
  a->send(f);
  bus.deliver();
  ASSERT_EQ(rb.frames.size(), 1U);
  EXPECT_EQ(rb.frames[0].timestamp, f.timestamp);
}

// ---- fault injection -------------------------------------------------------

std::vector<std::uint8_t> run_faulty(BusFaults faults, std::uint8_t count, std::uint64_t* lost = nullptr) {
  MemoryBus bus(std::move(faults));
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  for (std::uint8_t i = 0; i < count; ++i) a->send(numbered(0x100, i));
  bus.deliver();
  if (lost) *lost = bus.frames_lost();
  return first_bytes(rb.frames);
}

TEST(MemoryBusFaults, LossOfOneDeliversNothing) {
  BusFaults faults;
  faults.loss = 1.0;
  std::uint64_t lost = 0;
  EXPECT_TRUE(run_faulty(faults, 100, &lost).empty());
  EXPECT_EQ(lost, 100U);
}

TEST(MemoryBusFaults, LossCountsFramesSentAndLost) {
  BusFaults faults;
  faults.loss = 1.0;
  MemoryBus bus(faults);
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  EXPECT_EQ(a->send(numbered(0x100, 1)), SendStatus::Accepted);  // lost on the wire, not refused
  EXPECT_EQ(bus.frames_sent(), 1U);
  EXPECT_EQ(bus.frames_lost(), 1U);
  EXPECT_EQ(bus.pending(), 0U);
}

TEST(MemoryBusFaults, NoFaultsByDefault) {
  std::uint64_t lost = 1;
  const auto got = run_faulty({}, 200, &lost);
  ASSERT_EQ(got.size(), 200U);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], i);
  EXPECT_EQ(lost, 0U);
}

TEST(MemoryBusFaults, PartialLossWithSeedIsRepeatableAndKeepsOrder) {
  BusFaults faults;
  faults.loss = 0.3;
  faults.seed = 1234;
  std::uint64_t lost = 0;
  const auto first = run_faulty(faults, 200, &lost);
  EXPECT_EQ(run_faulty(faults, 200), first);
  EXPECT_EQ(first.size() + lost, 200U);
  EXPECT_GT(lost, 0U);
  EXPECT_LT(lost, 200U);
  EXPECT_TRUE(std::is_sorted(first.begin(), first.end()));
}

TEST(MemoryBusFaults, DuplicateVerdictDeliversTwice) {
  BusFaults faults;
  faults.verdict = [](const Frame& f, std::uint64_t) {
    return f.data[0] == 1 ? FrameVerdict::Duplicate : FrameVerdict::Deliver;
  };
  EXPECT_EQ(run_faulty(faults, 3), (std::vector<std::uint8_t>{0, 1, 1, 2}));
}

TEST(MemoryBusFaults, VerdictSeesBusIndexAndCanDrop) {
  BusFaults faults;
  std::vector<std::uint64_t> indices;
  faults.verdict = [&indices](const Frame&, std::uint64_t index) {
    indices.push_back(index);
    return index % 2 == 0 ? FrameVerdict::Drop : FrameVerdict::Deliver;
  };
  std::uint64_t lost = 0;
  EXPECT_EQ(run_faulty(faults, 6, &lost), (std::vector<std::uint8_t>{1, 3, 5}));
  EXPECT_EQ(lost, 3U);
  EXPECT_EQ(indices, (std::vector<std::uint64_t>{0, 1, 2, 3, 4, 5}));
}

TEST(MemoryBusFaults, VerdictOverridesProbabilities) {
  BusFaults faults;
  faults.loss = 1.0;
  faults.verdict = [](const Frame&, std::uint64_t) { return FrameVerdict::Deliver; };
  EXPECT_EQ(run_faulty(faults, 4), (std::vector<std::uint8_t>{0, 1, 2, 3}));
}

TEST(MemoryBusFaults, DuplicateProbabilityOfOneDeliversEveryFrameTwice) {
  BusFaults faults;
  faults.duplicate = 1.0;
  EXPECT_EQ(run_faulty(faults, 3), (std::vector<std::uint8_t>{0, 0, 1, 1, 2, 2}));
}

TEST(MemoryBusFaults, ReorderWithFixedSeedIsRepeatableAndDeliversEachFrameOnce) {
  BusFaults faults;
  faults.reorder = 0.5;
  faults.seed = 42;
  const auto first = run_faulty(faults, 200);
  const auto second = run_faulty(faults, 200);
  EXPECT_EQ(first, second);

  ASSERT_EQ(first.size(), 200U);
  auto sorted = first;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) EXPECT_EQ(sorted[i], i) << "missing or duplicated frame";
  EXPECT_FALSE(std::is_sorted(first.begin(), first.end())) << "reorder=0.5 should reorder something";
}

TEST(MemoryBusFaults, DifferentSeedsGiveDifferentReorderings) {
  BusFaults a;
  a.reorder = 0.5;
  a.seed = 1;
  BusFaults b = a;
  b.seed = 2;
  EXPECT_NE(run_faulty(a, 200), run_faulty(b, 200));
}

TEST(MemoryBusFaults, SetFaultsReseedsGenerator) {
  BusFaults faults;
  faults.reorder = 0.5;
  faults.seed = 7;
  MemoryBus bus;
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  for (int round = 0; round < 2; ++round) {
    bus.set_faults(faults);
    for (std::uint8_t i = 0; i < 100; ++i) a->send(numbered(0x100, i));
    bus.deliver();
  }
  ASSERT_EQ(rb.frames.size(), 200U);
  const std::vector<Frame> round1(rb.frames.begin(), rb.frames.begin() + 100);
  const std::vector<Frame> round2(rb.frames.begin() + 100, rb.frames.end());
  EXPECT_EQ(round1, round2);
  EXPECT_EQ(first_bytes(round1), run_faulty(faults, 100));
}

TEST(MemoryBusFaults, ClearingFaultsRestoresReliableDelivery) {
  BusFaults faults;
  faults.loss = 1.0;
  MemoryBus bus(faults);
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  Recorder rb;
  rb.attach_to(*b);
  a->send(numbered(0x100, 1));
  bus.set_faults({});
  a->send(numbered(0x100, 2));
  bus.deliver();
  EXPECT_EQ(first_bytes(rb.frames), (std::vector<std::uint8_t>{2}));
}

}  // namespace
}  // namespace canopen::can
