// canopen::Network: the master-side services of one network as one unit,
// and their single event stream (issue 4 item 8): per-network sequence
// numbers without gaps, timestamps from the frames that caused the events.
#include "canopen/network.hpp"

#include <gtest/gtest.h>

#include <variant>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/emcy/emcy.hpp"
#include "canopen/nmt/slave.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/pdo/transmitter.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kDevice = 5;

struct Rig {
  FakeClock clock;
  can::Frame::Clock::time_point wall{std::chrono::seconds(1'800'000'000)};
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> gw_ep = bus.attach("gateway");
  std::unique_ptr<can::MemoryEndpoint> dev_ep = bus.attach("device");
  od::ObjectDictionary own = od::make_gateway_dictionary(127, {});
  eds::DeviceDescription desc = eds::load_device_description(CANOPEN_SOURCE_DIR "/deploy/eds/cia402-drive.eds",
                                                             kDevice);
  od::ObjectDictionary dev_od = desc.od;
  std::vector<Event> events;
  Network net{own, [this](const can::Frame& f) { gw_ep->send(f); }, [this](const Event& e) { events.push_back(e); },
              {}, [this] { return wall; }};
  nmt::NmtSlave slave{dev_od, kDevice, [this](const can::Frame& f) { dev_ep->send(f); }};
  emcy::EmcyProducer emcy{dev_od, [this](const can::Frame& f) { dev_ep->send(f); }};
  pdo::PdoTransmitter tpdo{[this](const can::Frame& f) { dev_ep->send(f); }};

  Rig() {
    // Receive time of every frame: the wall clock at delivery.
    bus.set_time_source([this] { return wall; });
    gw_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) net.on_frame(f, clock.now());
    });
    dev_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) slave.on_frame(f, clock.now());
    });
    EXPECT_TRUE(net.add_node(kDevice, desc.od).empty());
    EXPECT_TRUE(tpdo.add_from(kDevice, pdo::Direction::Transmit, 1, dev_od, clock.now()));
  }
  // Advances both clocks and runs every service's timers.
  void step(Duration d) {
    clock.advance(d);
    wall += std::chrono::duration_cast<can::Frame::Clock::duration>(d);
    if (net.next_deadline() <= clock.now()) net.on_time(clock.now());
    if (slave.next_deadline() <= clock.now()) slave.on_time(clock.now());
    bus.deliver();
  }
  template <typename T>
  std::vector<const Event*> of() const {
    std::vector<const Event*> out;
    for (const auto& e : events)
      if (std::holds_alternative<T>(e.body)) out.push_back(&e);
    return out;
  }
};

TEST(Network, EveryServiceReportsIntoOneStreamWithoutGaps) {
  Rig rig;
  ASSERT_FALSE(rig.dev_od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 100)));  // heartbeat 100 ms
  rig.net.nmt().set_heartbeat_consumer(kDevice, 250ms);
  rig.slave.start(rig.clock.now());  // boot-up (7.2.8.3.3)
  rig.bus.deliver();
  rig.net.nmt().send_command(NmtCommand::Start, kDevice);
  rig.bus.deliver();
  rig.step(100ms);  // heartbeat: operational
  ASSERT_FALSE(rig.tpdo.set_value(kDevice, 1, 0x6041, 0, Value::of_unsigned(DataType::Unsigned16, 0x0637),
                                  rig.clock.now()));
  rig.bus.deliver();
  rig.emcy.raise(0x3210, 0x04, rig.clock.now());
  rig.bus.deliver();
  rig.net.report(can::BusEvent{can::BusState::ErrorWarning, can::BusState::ErrorActive});

  ASSERT_FALSE(rig.events.empty());
  for (std::size_t i = 0; i < rig.events.size(); ++i) EXPECT_EQ(rig.events[i].seq, i + 1) << "seq has a gap at " << i;
  EXPECT_EQ(rig.net.last_seq(), rig.events.size());
  ASSERT_EQ(rig.of<PdoEvent>().size(), 1U);
  const auto& pdo = std::get<PdoEvent>(rig.of<PdoEvent>()[0]->body);
  EXPECT_EQ(pdo.node, kDevice);
  ASSERT_EQ(pdo.values.size(), 1U);
  EXPECT_EQ(pdo.values[0].index, 0x6041);
  EXPECT_EQ(pdo.values[0].value, Value::of_unsigned(DataType::Unsigned16, 0x0637));
  ASSERT_EQ(rig.of<EmcyEvent>().size(), 1U);
  EXPECT_EQ(std::get<EmcyEvent>(rig.of<EmcyEvent>()[0]->body).error_code, 0x3210);
  EXPECT_EQ(rig.of<can::BusEvent>().size(), 1U);
  bool saw_operational = false;
  for (const auto* e : rig.of<NodeStateEvent>()) {
    const auto& s = std::get<NodeStateEvent>(e->body);
    saw_operational = saw_operational || s.state == NmtState::Operational;
  }
  EXPECT_TRUE(saw_operational);
}

TEST(Network, FrameEventsCarryTheFramesReceiveTimeAndTimerEventsTheWallTime) {
  Rig rig;
  rig.net.nmt().set_heartbeat_consumer(kDevice, 250ms);
  const auto boot_time = rig.wall;
  rig.slave.start(rig.clock.now());
  rig.bus.deliver();
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.front().timestamp, boot_time) << "boot-up event stamped with the frame's receive time";

  // The device falls silent: lost exactly 250 ms after its last frame, and
  // that event has no frame, so it carries the wall time of the timer.
  rig.dev_ep->set_link_up(false);
  rig.step(249ms);
  EXPECT_TRUE(rig.of<NodeStateEvent>().size() == 1U) << "not lost before the consumer time";
  rig.step(1ms);
  const auto states = rig.of<NodeStateEvent>();
  ASSERT_EQ(states.size(), 2U);
  EXPECT_EQ(std::get<NodeStateEvent>(states[1]->body).cause, NodeStateEvent::Cause::Lost);
  EXPECT_EQ(states[1]->timestamp, boot_time + 250ms);
  EXPECT_EQ(states[1]->seq, states[0]->seq + 1);
}

}  // namespace
}  // namespace canopen
