// Integration: our NmtMaster against our NmtSlave over the in-memory bus
// with a fake clock (7.2.8.3 boot-up, node control, heartbeat, consumer
// timeout and recovery; node guarding against the slave's responses).
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/clock.hpp"
#include "canopen/nmt/master.hpp"
#include "canopen/nmt/slave.hpp"
#include "canopen/od/gateway_dictionary.hpp"

namespace canopen::nmt {
namespace {

using namespace std::chrono_literals;

constexpr std::uint8_t kSlave = 5;

class Network {
 public:
  Network() : od(od::make_gateway_dictionary(kSlave, {})) {
    slave_ep = bus.attach("slave");
    master_ep = bus.attach("master");
    slave = std::make_unique<NmtSlave>(od, kSlave, [this](const can::Frame& f) { slave_ep->send(f); });
    master = std::make_unique<NmtMaster>([this](const can::Frame& f) { master_ep->send(f); },
                                         [this](const EventBody& b, can::Frame::Clock::time_point) {
                                           if (const auto* n = std::get_if<NodeStateEvent>(&b)) states.push_back(*n);
                                           if (const auto* h = std::get_if<HeartbeatEvent>(&b)) heartbeats.push_back(*h);
                                         });
    slave_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) slave->on_frame(f, clock.now());
    });
    master_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) master->on_frame(f, clock.now());
    });
  }

  // Runs both services until `end`, delivering frames after every step.
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      bus.deliver();
      const TimePoint next = std::min(master->next_deadline(), slave->next_deadline());
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      master->on_time(clock.now());
      slave->on_time(clock.now());
    }
    clock.advance_to(end);
    bus.deliver();
  }

  FakeClock clock;
  can::MemoryBus bus;
  od::ObjectDictionary od;
  std::unique_ptr<can::MemoryEndpoint> slave_ep;
  std::unique_ptr<can::MemoryEndpoint> master_ep;
  std::unique_ptr<NmtSlave> slave;
  std::unique_ptr<NmtMaster> master;
  std::vector<NodeStateEvent> states;
  std::vector<HeartbeatEvent> heartbeats;
};

TEST(NmtMasterSlave, Heartbeat_7_2_8_3_BootUpStartHeartbeatLostAndRecovered) {
  Network n;
  ASSERT_FALSE(n.od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  n.master->set_heartbeat_consumer(kSlave, 250ms);

  n.slave->start(n.clock.now());
  n.bus.deliver();
  ASSERT_EQ(n.states.size(), 1U);
  EXPECT_EQ(n.states[0].cause, NodeStateEvent::Cause::BootUp);
  EXPECT_EQ(n.states[0].state, NmtState::Initialising) << "the state the boot-up message carries";
  EXPECT_EQ(n.master->node(kSlave)->boot_ups, 1U);

  n.master->send_command(NmtCommand::Start, kSlave);
  n.bus.deliver();
  EXPECT_EQ(n.slave->state(), NmtSlave::State::Operational);
  n.run_for(100ms);
  ASSERT_EQ(n.heartbeats.size(), 1U);
  EXPECT_EQ(n.heartbeats[0].state, NmtState::Operational);
  ASSERT_EQ(n.states.size(), 2U);
  EXPECT_EQ(n.states[1].cause, NodeStateEvent::Cause::Heartbeat);
  EXPECT_EQ(n.states[1].previous, NmtState::Initialising);
  EXPECT_EQ(n.states[1].state, NmtState::Operational);

  // The slave falls silent (link down): lost 250 ms after its last heartbeat.
  const TimePoint last = n.clock.now();
  n.slave_ep->set_link_up(false);
  n.run_for(249ms);
  EXPECT_EQ(n.states.size(), 2U);
  n.run_for(1ms);
  ASSERT_EQ(n.states.size(), 3U);
  EXPECT_EQ(n.states[2].cause, NodeStateEvent::Cause::Lost);
  EXPECT_EQ(n.clock.now(), last + 250ms);

  // Back on the bus: the next heartbeat recovers it.
  n.slave_ep->set_link_up(true);
  n.run_for(100ms);
  ASSERT_EQ(n.states.size(), 4U);
  EXPECT_EQ(n.states[3].cause, NodeStateEvent::Cause::Recovered);
  EXPECT_EQ(n.states[3].state, NmtState::Operational);
  EXPECT_FALSE(n.master->node(kSlave)->lost);
}

TEST(NmtMasterSlave, NodeControl_7_2_8_3_1_ResetNodeToAllGivesANewBootUp) {
  Network n;
  n.slave->start(n.clock.now());
  n.bus.deliver();
  n.master->send_command(NmtCommand::Stop, 0);
  n.bus.deliver();
  EXPECT_EQ(n.slave->state(), NmtSlave::State::Stopped);
  n.master->send_command(NmtCommand::ResetNode, 0);
  n.bus.deliver();
  EXPECT_EQ(n.slave->state(), NmtSlave::State::PreOperational);
  EXPECT_EQ(n.master->node(kSlave)->boot_ups, 2U);
}

TEST(NmtMasterSlave, NodeGuarding_7_2_8_3_2_1_GuardingAndLifeGuardingBothWays) {
  Network n;
  ASSERT_FALSE(n.od.set(0x100C, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  ASSERT_FALSE(n.od.set(0x100D, 0, Value::of_unsigned(DataType::Unsigned8, 3)));
  std::vector<LifeGuardingEvent> life;
  SlaveCallbacks cb;
  cb.on_life_guarding = [&](LifeGuardingEvent e) { life.push_back(e); };
  n.slave = std::make_unique<NmtSlave>(n.od, kSlave, [&n](const can::Frame& f) { n.slave_ep->send(f); }, cb);
  n.slave->start(n.clock.now());
  n.master->set_node_guarding(kSlave, 100ms, 3, n.clock.now());
  n.master->send_command(NmtCommand::Start, kSlave);
  n.run_for(1s);
  EXPECT_EQ(n.master->node(kSlave)->state, NmtState::Operational);
  EXPECT_EQ(n.master->node(kSlave)->toggle_errors, 0U);
  EXPECT_FALSE(n.master->node(kSlave)->lost);
  EXPECT_TRUE(life.empty());

  // The master stops guarding: the slave reports life guarding after 300 ms.
  n.master->set_node_guarding(kSlave, 0ms, 0, n.clock.now());
  n.run_for(300ms);
  EXPECT_EQ(life, (std::vector<LifeGuardingEvent>{LifeGuardingEvent::Occurred}));
}

}  // namespace
}  // namespace canopen::nmt
