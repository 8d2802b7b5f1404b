// ServiceDriver (socketcan/service_driver.cpp): binds sans-I/O services to
// a channel and the io_context; here on the in-memory bus.
#include "canopen/socketcan/service_driver.hpp"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>

#include "canopen/can/memory_bus.hpp"
#include "canopen/device.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/sdo/client.hpp"

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

// Runs the io_context until `done` or 2 s (a bound for a broken timer,
// never reached when it works).
template <typename Pred>
bool run_until(boost::asio::io_context& io, Pred done) {
  const auto end = std::chrono::steady_clock::now() + 2s;
  while (!done() && std::chrono::steady_clock::now() < end) {
    io.restart();  // a poll() or run that ran out of work stopped it
    io.run_for(5ms);
  }
  return done();
}

od::ObjectDictionary own_dictionary(std::uint16_t heartbeat_ms, std::uint16_t emcy_inhibit) {
  auto od = od::make_gateway_dictionary(5, od::GatewayIdentity{});
  (void)od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, heartbeat_ms));
  (void)od.set(0x1015, 0, Value::of_unsigned(DataType::Unsigned16, emcy_inhibit));
  return od;
}

DeviceConfig node5() {
  DeviceConfig c;
  c.node_id = 5;
  return c;
}

// No one re-arms the timer by hand in the three below: the services report
// their new deadlines (canopen/deadline.hpp) and the driver follows.

TEST(ServiceDriver, AnSdoRequestSubmittedFromOutsideTimesOut) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  sdo::ClientConfig cfg;
  cfg.default_timeout = 20ms;
  sdo::SdoClient client(cfg, [&](const can::Frame& f) { ours->send(f); });
  ServiceDriver driver(io, *ours);  // services outlive the driver
  driver.add(client);
  io.poll();  // the driver idles: nothing to time yet
  std::optional<sdo::TransferResult> result;
  sdo::Request req;
  req.node = 5;  // nobody answers
  req.index = 0x1000;
  req.on_done = [&](sdo::TransferResult&& r) { result = std::move(r); };
  ASSERT_TRUE(client.upload(std::move(req), SteadyClock::now()));
  ASSERT_TRUE(run_until(io, [&] { return result.has_value(); })) << "the timer fired for the new deadline";
  EXPECT_EQ(result->error, make_error_code(SdoAbort::Timeout));
}

TEST(ServiceDriver, ADeviceStartedFromOutsideSendsBootUpAndFirstHeartbeat) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  auto od = own_dictionary(20, 0);
  std::vector<can::Frame> sent;
  Device dev(od, node5(), [&](const can::Frame& f) { sent.push_back(f); });
  ServiceDriver driver(io, *ours);
  driver.add(dev);
  io.poll();
  dev.start(SteadyClock::now());
  ASSERT_EQ(sent.size(), 1U);
  EXPECT_EQ(sent[0].data[0], 0x00) << "boot-up (7.2.8.3.3)";
  ASSERT_TRUE(run_until(io, [&] { return sent.size() >= 2; })) << "the first heartbeat, 1017h later";
  EXPECT_EQ(sent[1].id, 0x705U);
  EXPECT_EQ(sent[1].data[0], 0x7F) << "pre-operational (7.2.8.3.2.2)";
}

TEST(ServiceDriver, AnEmcyRaisedFromOutsideIsSentAfterTheInhibitTime) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  auto od = own_dictionary(0, 200);  // 1015h: 20 ms
  std::vector<can::Frame> emcys;
  Device dev(od, node5(), [&](const can::Frame& f) {
    if (f.id == 0x85) emcys.push_back(f);
  });
  ServiceDriver driver(io, *ours);
  driver.add(dev);
  dev.start(SteadyClock::now());
  io.poll();
  ASSERT_TRUE(dev.raise_emcy(0x5000, 0x01, SteadyClock::now()));
  ASSERT_TRUE(dev.raise_emcy(0x6000, 0x01, SteadyClock::now()));
  ASSERT_EQ(emcys.size(), 1U) << "the second waits for the inhibit time (7.2.7.1)";
  ASSERT_TRUE(run_until(io, [&] { return emcys.size() == 2; })) << "sent when the driver's timer fires";
  EXPECT_EQ(emcys[1].data[0], 0x00);
  EXPECT_EQ(emcys[1].data[1], 0x60);
}

TEST(ServiceDriver, ARemovedServiceIsNoLongerHeard) {
  boost::asio::io_context io;
  can::MemoryBus bus;
  auto ours = bus.attach("ours");
  sdo::SdoClient client({}, [](const can::Frame&) {});
  {
    ServiceDriver driver(io, *ours);
    driver.add(client);
  }
  sdo::Request req;
  req.node = 5;
  req.index = 0x1000;
  // The driver is gone: the client's report reaches no one (no crash).
  EXPECT_TRUE(client.upload(std::move(req), SteadyClock::now()));
  io.poll();
}

}  // namespace
}  // namespace canopen::socketcan
