// canopen::LocalNode: the gateway's own device on one network, one test per
// CiA 301 rule (section in the test name), fake clock, frames recorded.
#include "canopen/local_node.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "canopen/od/gateway_dictionary.hpp"
#include "unit/stack/nmt/nmt_test_support.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kOwn = 100;
constexpr std::uint32_t kOwnEmcy = 0x80U + kOwn;

struct Rig {
  Rig() : od(od::make_gateway_dictionary(kOwn, od::GatewayIdentity{})) {
    DeviceConfig cfg;
    cfg.node_id = kOwn;
    node = std::make_unique<LocalNode>(
        od, cfg, [this](const can::Frame& f) { bus.push_back(f); },
        [this](const can::Frame& f) { master.push_back(f); });
    node->start(clock.now());  // pre-operational: EMCY and SYNC allowed
    bus.clear();
    master.clear();
  }
  // The EMCY codes sent (0000h: error reset), in order.
  std::vector<std::uint16_t> emcy_codes() const {
    std::vector<std::uint16_t> out;
    for (const auto& f : bus)
      if (f.id == kOwnEmcy) out.push_back(static_cast<std::uint16_t>(f.data[0] | f.data[1] << 8));
    return out;
  }
  void bus_event(can::BusState state, can::BusState previous, can::BusEventCause cause) {
    can::BusEvent ev;
    ev.state = state;
    ev.previous = previous;
    ev.cause = cause;
    node->on_bus_event(ev, clock.now());
  }
  void node_state(std::uint8_t id, NodeStateEvent::Cause cause) {
    NodeStateEvent ev;
    ev.node = id;
    ev.cause = cause;
    if (cause != NodeStateEvent::Cause::Lost) ev.state = NmtState::Operational;
    node->on_node_state(ev, clock.now());
  }

  FakeClock clock;
  od::ObjectDictionary od;
  std::vector<can::Frame> bus, master;
  std::unique_ptr<LocalNode> node;
};

using can::BusEventCause;
using can::BusState;

TEST(LocalNode, Emcy_7_2_7_1_ErrorPassiveIs8120hWhileItLastsWithTheCommunicationBit) {
  Rig r;
  r.bus_event(BusState::ErrorPassive, BusState::ErrorWarning, BusEventCause::ErrorFrame);
  ASSERT_EQ(r.emcy_codes(), std::vector<std::uint16_t>{kEmcyCanErrorPassive});
  EXPECT_NE(r.bus.back().data[2] & emcy::error_register::kCommunication, 0) << "1001h bit 4";
  r.bus_event(BusState::ErrorActive, BusState::ErrorPassive, BusEventCause::ErrorFrame);
  EXPECT_EQ(r.emcy_codes(), (std::vector<std::uint16_t>{kEmcyCanErrorPassive, 0x0000})) << "error reset";
}

TEST(LocalNode, Emcy_7_2_7_1_ReceiveOverflowIs8110hAsAnEvent) {
  Rig r;
  r.bus_event(BusState::ErrorActive, BusState::ErrorActive, BusEventCause::RxOverflow);
  EXPECT_EQ(r.emcy_codes(), (std::vector<std::uint16_t>{kEmcyCanOverrun, 0x0000}));
}

TEST(LocalNode, Emcy_7_2_7_1_RecoveredFromBusOffIs8140hAsAnEvent) {
  Rig r;
  r.bus_event(BusState::ErrorActive, BusState::BusOff, BusEventCause::ControllerRestarted);
  EXPECT_EQ(r.emcy_codes(), (std::vector<std::uint16_t>{kEmcyRecoveredFromBusOff, 0x0000}));
  r.bus.clear();
  r.bus_event(BusState::Down, BusState::BusOff, BusEventCause::LinkDown);
  EXPECT_TRUE(r.emcy_codes().empty()) << "going down is no recovery";
}

TEST(LocalNode, Emcy_7_2_7_1_HeartbeatOrGuardingLossIs8130hWhileAnyNodeIsLost) {
  Rig r;
  r.node_state(5, NodeStateEvent::Cause::Lost);
  r.node_state(6, NodeStateEvent::Cause::Lost);
  EXPECT_EQ(r.emcy_codes(), std::vector<std::uint16_t>{kEmcyLifeGuardOrHeartbeat}) << "once, for the first";
  EXPECT_EQ(r.node->lost_nodes().size(), 2U);
  r.node_state(5, NodeStateEvent::Cause::Heartbeat);
  EXPECT_EQ(r.emcy_codes().size(), 1U) << "node 6 is still lost";
  r.node_state(6, NodeStateEvent::Cause::BootUp);
  EXPECT_EQ(r.emcy_codes(), (std::vector<std::uint16_t>{kEmcyLifeGuardOrHeartbeat, 0x0000}));
}

// Issue 28 item 3, CiA 301 7.2.8.2.2.1: the NMT master guarded the own node
// (100Ch/100Dh set, heartbeat 1017h 0) and stopped: the life guarding event
// is EMCY 8130h with the communication bit (as CANopenNode's devices send
// it) and reaches the application; guarding again resets it. It shares
// 8130h with the lost nodes: raised once while either holds.
TEST(LocalNode, Emcy_7_2_8_2_2_1_LifeGuardingLapseIs8130hUntilGuardedAgain) {
  FakeClock clock;
  auto od = od::make_gateway_dictionary(kOwn, od::GatewayIdentity{});
  ASSERT_FALSE(od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 0)));
  ASSERT_FALSE(od.set(0x100C, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  ASSERT_FALSE(od.set(0x100D, 0, Value::of_unsigned(DataType::Unsigned8, 3)));
  std::vector<can::Frame> bus;
  std::vector<nmt::LifeGuardingEvent> heard;
  DeviceConfig cfg;
  cfg.node_id = kOwn;
  DeviceCallbacks cb;
  cb.on_life_guarding = [&](nmt::LifeGuardingEvent e) { heard.push_back(e); };
  LocalNode node(od, cfg, [&](const can::Frame& f) { bus.push_back(f); }, nullptr, cb);
  node.start(clock.now());
  const auto advance = [&](Duration d) {
    const TimePoint end = clock.now() + d;
    while (node.next_deadline() <= end) {
      if (node.next_deadline() > clock.now()) clock.advance_to(node.next_deadline());
      node.on_time(clock.now());
    }
    clock.advance_to(end);
  };
  const auto emcy = [&] {
    std::vector<std::uint16_t> out;
    for (const auto& f : bus)
      if (f.id == kOwnEmcy) out.push_back(static_cast<std::uint16_t>(f.data[0] | f.data[1] << 8));
    return out;
  };
  const can::Frame guard = test::parse("764#R1");  // 700h + 100: a guarding request
  advance(1s);
  ASSERT_TRUE(node.on_frame(guard, clock.now())) << "the first request starts life guarding";
  advance(299ms);
  EXPECT_TRUE(emcy().empty());
  advance(1ms);  // 100 ms x 3 without a request
  ASSERT_EQ(emcy(), std::vector<std::uint16_t>{kEmcyLifeGuardOrHeartbeat});
  EXPECT_NE(bus.back().data[2] & emcy::error_register::kCommunication, 0) << "1001h bit 4";
  EXPECT_TRUE(node.life_guarding_lost());
  EXPECT_EQ(heard, std::vector<nmt::LifeGuardingEvent>{nmt::LifeGuardingEvent::Occurred}) << "the application hears it";
  // A lost node meanwhile: 8130h is already up.
  NodeStateEvent lost;
  lost.node = 5;
  lost.cause = NodeStateEvent::Cause::Lost;
  node.on_node_state(lost, clock.now());
  EXPECT_EQ(emcy().size(), 1U);
  node.on_frame(guard, clock.now());
  EXPECT_FALSE(node.life_guarding_lost());
  EXPECT_EQ(heard.back(), nmt::LifeGuardingEvent::Resolved);
  EXPECT_EQ(emcy().size(), 1U) << "node 5 is still lost";
  NodeStateEvent back = lost;
  back.cause = NodeStateEvent::Cause::Heartbeat;
  back.state = NmtState::Operational;
  node.on_node_state(back, clock.now());
  EXPECT_EQ(emcy(), (std::vector<std::uint16_t>{kEmcyLifeGuardOrHeartbeat, 0x0000})) << "error reset";
  // And alone: lapse, then guarded again.
  advance(300ms);
  node.on_frame(guard, clock.now());
  EXPECT_EQ(emcy(), (std::vector<std::uint16_t>{kEmcyLifeGuardOrHeartbeat, 0x0000, kEmcyLifeGuardOrHeartbeat, 0x0000}));
}

TEST(LocalNode, Sync_7_5_2_5_OnRequestWithTheCobIdOf1005hToBusAndMaster) {
  Rig r;
  r.node->send_sync(std::nullopt);
  ASSERT_EQ(r.bus.size(), 1U);
  EXPECT_EQ(r.bus[0].id, 0x080U);
  EXPECT_EQ(r.bus[0].len, 0U) << "no counter: no data (7.2.5.2.1)";
  ASSERT_EQ(r.master.size(), 1U) << "the master side's synchronous RPDOs follow it";
  ASSERT_FALSE(r.od.write(0x1005, 0, encode(Value::of_unsigned(DataType::Unsigned32, 0x90))));
  r.node->send_sync(7);
  ASSERT_EQ(r.bus.size(), 2U);
  EXPECT_EQ(r.bus[1].id, 0x090U) << "1005h, not a fixed 080h";
  ASSERT_EQ(r.bus[1].len, 1U);
  EXPECT_EQ(r.bus[1].data[0], 7);
  EXPECT_EQ(r.master.size(), 2U);
}

TEST(LocalNode, WhatTheMasterSideHears_SyncTimeAndEmcyPer1005h1012h1014h) {
  Rig r;
  EXPECT_TRUE(r.node->master_hears(can::Frame::standard(0x080, {})));
  EXPECT_TRUE(r.node->master_hears(can::Frame::standard(0x100, {1, 2, 3, 4, 5, 6})));
  EXPECT_TRUE(r.node->master_hears(can::Frame::standard(kOwnEmcy, {0x10, 0x81, 0x11, 0, 0, 0, 0, 0})));
  EXPECT_FALSE(r.node->master_hears(can::Frame::standard(0x700U + kOwn, {0x7F}))) << "its heartbeat";
  EXPECT_FALSE(r.node->master_hears(can::Frame::standard(0x580U + kOwn, {0x60, 0, 0, 0}))) << "its SDO";
  // 7.5.2.17: the COB-ID changes only while bit 31 says the EMCY is invalid.
  auto write_1014 = [&](std::uint32_t v) { return r.od.write(0x1014, 0, encode(Value::of_unsigned(DataType::Unsigned32, v))); };
  ASSERT_FALSE(write_1014(0x80000000U | kOwnEmcy));
  EXPECT_FALSE(r.node->master_hears(can::Frame::standard(kOwnEmcy, {0, 0, 0, 0, 0, 0, 0, 0}))) << "no EMCY";
  ASSERT_FALSE(write_1014(0xA0));
  EXPECT_TRUE(r.node->master_hears(can::Frame::standard(0x0A0, {0, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_FALSE(r.node->master_hears(can::Frame::standard(kOwnEmcy, {0, 0, 0, 0, 0, 0, 0, 0})));
}

TEST(LocalNode, WhatItHears_7_2_8_3_1_NmtToAllNodesOrToItsOwnId) {
  Rig r;
  EXPECT_TRUE(r.node->hears(can::Frame::standard(0x000, {0x01, 0})));
  EXPECT_TRUE(r.node->hears(can::Frame::standard(0x000, {0x80, kOwn})));
  EXPECT_FALSE(r.node->hears(can::Frame::standard(0x000, {0x01, 5}))) << "another node's";
  EXPECT_FALSE(r.node->hears(can::Frame::standard(0x605, {0x40, 0, 0x10, 0, 0, 0, 0, 0}))) << "not NMT";
}

TEST(LocalNode, OwnFramesTheMasterMustHearReachItFromTheDevice) {
  Rig r;
  r.bus_event(BusState::ErrorActive, BusState::ErrorActive, BusEventCause::RxOverflow);
  ASSERT_EQ(r.master.size(), 2U) << "its EMCYs are published like any node's";
  EXPECT_EQ(r.master[0].id, kOwnEmcy);
}

}  // namespace
}  // namespace canopen
