// canopen::DeadlineSource (deadline.hpp): the sans-I/O services report
// their next deadline themselves when a call from outside moves it, so
// whoever runs their timer follows without being told. Fake clock, no Asio.
#include "canopen/deadline.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/device.hpp"
#include "canopen/network.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/sdo/client.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;

// Every report a service makes.
struct Reports {
  std::vector<TimePoint> seen;
  DeadlineSource::Observer observer() {
    return [this](TimePoint next) { seen.push_back(next); };
  }
  std::optional<TimePoint> last() const {
    return seen.empty() ? std::nullopt : std::optional<TimePoint>(seen.back());
  }
};

od::ObjectDictionary dictionary(std::uint8_t node, std::uint16_t heartbeat_ms = 0, std::uint16_t emcy_inhibit = 0) {
  auto od = od::make_gateway_dictionary(node, od::GatewayIdentity{});
  (void)od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, heartbeat_ms));
  (void)od.set(0x1015, 0, Value::of_unsigned(DataType::Unsigned16, emcy_inhibit));
  return od;
}

DeviceConfig config(std::uint8_t node) {
  DeviceConfig c;
  c.node_id = node;
  return c;
}

TEST(DeadlineSource, AnSdoRequestSubmittedFromOutsideReportsItsTimeout) {
  FakeClock clock;
  sdo::ClientConfig cfg;
  cfg.default_timeout = 50ms;
  sdo::SdoClient client(cfg, [](const can::Frame&) {});
  Reports r;
  client.on_deadline_change(r.observer());
  sdo::Request req;
  req.node = 5;
  req.index = 0x1000;
  const auto id = client.upload(std::move(req), clock.now());
  ASSERT_TRUE(id);
  ASSERT_EQ(r.last(), clock.now() + 50ms) << "the initiate's response timeout (7.2.4.3)";
  EXPECT_EQ(client.next_deadline(), *r.last());
  // Cancelled: nothing left to time.
  EXPECT_TRUE(client.cancel(*id, clock.now()));
  EXPECT_EQ(r.last(), TimePoint::max());
}

TEST(DeadlineSource, ADeviceStartedFromOutsideReportsItsFirstHeartbeat) {
  FakeClock clock;
  auto od = dictionary(5, 100);
  std::vector<can::Frame> sent;
  Device dev(od, config(5), [&](const can::Frame& f) { sent.push_back(f); });
  Reports r;
  dev.on_deadline_change(r.observer());
  dev.start(clock.now());
  ASSERT_EQ(sent.size(), 1U);
  EXPECT_EQ(sent[0].id, 0x705U) << "boot-up (7.2.8.3.3)";
  ASSERT_EQ(r.seen.size(), 1U) << "one report per outside call";
  EXPECT_EQ(r.last(), clock.now() + 100ms) << "the first heartbeat one 1017h period later (7.2.8.3.2.2)";
}

TEST(DeadlineSource, AnEmcyHeldBackByTheInhibitTimeIsReported) {
  FakeClock clock;
  auto od = dictionary(5, 0, 100);  // 1015h: 100 x 100 us = 10 ms
  std::vector<can::Frame> sent;
  Device dev(od, config(5), [&](const can::Frame& f) { sent.push_back(f); });
  dev.start(clock.now());
  Reports r;
  dev.on_deadline_change(r.observer());
  ASSERT_TRUE(dev.raise_emcy(0x5000, 0x01, clock.now()));
  ASSERT_TRUE(dev.raise_emcy(0x6000, 0x01, clock.now()));
  EXPECT_EQ(r.last(), clock.now() + 10ms) << "the second EMCY waits for the inhibit time (7.2.7.1)";
}

TEST(DeadlineSource, ADirectDictionaryWriteAsksForOnTimeAtOnce) {
  FakeClock clock;
  auto od = dictionary(5);
  Device dev(od, config(5), [](const can::Frame&) {});
  dev.start(clock.now());
  Reports r;
  dev.on_deadline_change(r.observer());
  // 1006h reconfigures the SYNC producer, which the Device does at its next on_time().
  ASSERT_FALSE(od.write(0x1006, 0, encode(Value::of_unsigned(DataType::Unsigned32, 10000))));
  EXPECT_EQ(r.last(), TimePoint::min());
}

TEST(DeadlineSource, ANetworkPassesOnWhatItsServicesReport) {
  FakeClock clock;
  auto own = dictionary(127);
  sdo::ClientConfig cfg;
  cfg.default_timeout = 30ms;
  Network net(own, [](const can::Frame&) {}, [](const Event&) {}, cfg);
  Reports r;
  net.on_deadline_change(r.observer());
  sdo::Request req;
  req.node = 5;
  req.index = 0x1000;
  ASSERT_TRUE(net.sdo().upload(std::move(req), clock.now()));
  EXPECT_EQ(r.last(), clock.now() + 30ms) << "SDO request through sdo()";
  clock.advance(5ms);
  ASSERT_TRUE(net.nmt().set_node_guarding(6, 100ms, 3, clock.now()));
  EXPECT_EQ(r.last(), clock.now()) << "the first guarding request (7.2.8.3.2.1) at once, through nmt()";
  EXPECT_EQ(net.next_deadline(), clock.now());
}

}  // namespace
}  // namespace canopen
