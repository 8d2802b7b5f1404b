// ServiceDriver (socketcan/service_driver.cpp): binds sans-I/O services to
// a channel and the io_context; here on the in-memory bus.
#include "canopen/socketcan/service_driver.hpp"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include "canopen/can/memory_bus.hpp"

namespace canopen::socketcan {
namespace {

using namespace std::chrono_literals;

struct Recorder {
  std::vector<can::Frame> frames;
  std::optional<TimePoint> deadline;
  int timer_calls = 0;
  void on_frame(const can::Frame& f, TimePoint) { frames.push_back(f); }
  void on_time(TimePoint) {
    ++timer_calls;
    deadline.reset();
  }
  TimePoint next_deadline() const { return deadline.value_or(TimePoint::max()); }
};

TEST(ServiceDriver, ReceivedFramesReachEveryService) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  auto other = bus.attach("other");
  ServiceDriver driver(io, *ours);
  Recorder a, b;
  driver.add(a);
  driver.add(b);
  other->send(can::Frame::standard(0x181, {1, 2}));
  bus.deliver();
  ASSERT_EQ(a.frames.size(), 1U);
  ASSERT_EQ(b.frames.size(), 1U);
  EXPECT_EQ(a.frames[0].id, 0x181U);
}

TEST(ServiceDriver, OwnBroadcastFramesAreDeliveredLocallyLaterNotReentrantly) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  ServiceDriver driver(io, *ours);
  Recorder a;
  driver.add(a);
  driver.deliver_locally(can::Frame::standard(0x000, {0x01, 0x00}));  // NMT start, all nodes
  driver.deliver_locally(can::Frame::standard(0x080, {}));            // SYNC
  EXPECT_TRUE(a.frames.empty()) << "not from inside the sender's call";
  io.poll();
  ASSERT_EQ(a.frames.size(), 2U);
  EXPECT_EQ(a.frames[0].id, 0x000U);
  EXPECT_EQ(a.frames[1].id, 0x080U);
  EXPECT_NE(a.frames[0].timestamp, can::Frame::Clock::time_point{}) << "stamped like a received frame";
  EXPECT_EQ(bus.pending(), 0U) << "local delivery puts nothing on the bus";
}

TEST(ServiceDriver, LocalDeliveryCanTargetOneService) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  ServiceDriver driver(io, *ours);
  Recorder sender, receiver;
  driver.add(sender);
  driver.add(receiver);
  driver.deliver_locally(can::Frame::standard(0x080, {}), &receiver);
  io.poll();
  EXPECT_TRUE(sender.frames.empty());
  EXPECT_EQ(receiver.frames.size(), 1U);
}

TEST(ServiceDriver, TimerFiresAtTheEarliestDeadline) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  ServiceDriver driver(io, *ours);
  Recorder a;
  a.deadline = SteadyClock::now() + 20ms;
  driver.add(a);
  io.run_for(200ms);
  EXPECT_EQ(a.timer_calls, 1);
}

TEST(ServiceDriver, NothingIsDeliveredAfterTheDriverIsGone) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  Recorder a;
  {
    ServiceDriver driver(io, *ours);
    driver.add(a);
    driver.deliver_locally(can::Frame::standard(0x080, {}));
  }
  io.poll();
  EXPECT_TRUE(a.frames.empty());
}

}  // namespace
}  // namespace canopen::socketcan
