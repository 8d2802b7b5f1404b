// Tests for stack/src/nmt/slave.cpp: the NMT state machine (7.3.2), node
// control (7.2.8.3.1), boot-up (7.2.8.3.3), heartbeat producer and node /
// life guarding on the slave side (7.2.8.3.2), table 37 (7.3.2.2.5).
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/nmt/slave.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "unit/stack/nmt/nmt_test_support.hpp"

namespace canopen::nmt {
namespace {

using namespace std::chrono_literals;
using Strings = std::vector<std::string>;
using S = NmtSlave::State;

constexpr std::uint8_t kNode = 0x7F;

class SlaveTest : public ::testing::Test {
 protected:
  SlaveTest() : od(od::make_gateway_dictionary(kNode, {})) {}

  void make(bool start = true) {
    SlaveCallbacks cb;
    cb.on_reset_application = [this] { calls.push_back("reset application"); };
    cb.on_reset_communication = [this] { calls.push_back("reset communication"); };
    cb.on_state_change = [this](NmtState now, NmtState before) {
      calls.push_back(std::string(to_string(before)) + " -> " + std::string(to_string(now)));
    };
    cb.on_life_guarding = [this](LifeGuardingEvent e) {
      life.push_back(e == LifeGuardingEvent::Occurred ? "occurred" : "resolved");
    };
    slave = std::make_unique<NmtSlave>(od, kNode, log.sink(), std::move(cb));
    if (start) slave->start(clock.now());
  }
  bool rx(const std::string& text) { return slave->on_frame(test::parse(text), clock.now()); }
  // Advances the clock, calling on_time() at each deadline on the way.
  void advance(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      const TimePoint next = slave->next_deadline();
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      slave->on_time(clock.now());
    }
    clock.advance_to(end);
  }
  void sdo_write_u16(std::uint16_t index, std::uint16_t v) {
    const std::uint8_t b[2] = {static_cast<std::uint8_t>(v & 0xFFU), static_cast<std::uint8_t>(v >> 8)};
    ASSERT_FALSE(od.write(index, 0, b));
  }
  void sdo_write_u8(std::uint16_t index, std::uint8_t v) {
    const std::uint8_t b[1] = {v};
    ASSERT_FALSE(od.write(index, 0, b));
  }

  FakeClock clock;
  od::ObjectDictionary od;
  test::FrameLog log;
  Strings calls;
  Strings life;
  std::unique_ptr<NmtSlave> slave;
};

// ---- 7.2.8.3.3 boot-up ---------------------------------------------------------------

TEST_F(SlaveTest, BootUp_7_2_8_3_3_StartSendsBootUpAndEntersPreOperational) {
  make(false);
  EXPECT_TRUE(log.frames.empty());
  slave->start(clock.now());
  EXPECT_EQ(log.take(), (Strings{"77F#00"}));
  EXPECT_EQ(slave->state(), S::PreOperational);
  EXPECT_EQ(slave->nmt_state(), NmtState::PreOperational);
  EXPECT_EQ(calls, (Strings{"reset application", "reset communication", "initialising -> pre-operational"}));
}

TEST_F(SlaveTest, BootUp_7_2_8_3_3_NotStartedIgnoresCommands) {
  make(false);
  EXPECT_TRUE(rx("000#017F"));
  EXPECT_EQ(slave->state(), S::Initialising);
  EXPECT_TRUE(log.frames.empty());
}

// ---- 7.3.2 state diagram: every transition -----------------------------------------------

TEST_F(SlaveTest, NmtStateMachine_7_3_2_StartFromPreOperationalAndStopped) {
  make();
  EXPECT_TRUE(rx("000#017F"));
  EXPECT_EQ(slave->state(), S::Operational);
  EXPECT_TRUE(rx("000#027F"));
  EXPECT_EQ(slave->state(), S::Stopped);
  EXPECT_TRUE(rx("000#017F"));
  EXPECT_EQ(slave->state(), S::Operational);
  EXPECT_EQ(log.take(), (Strings{"77F#00"}));  // no frames for plain transitions
}

TEST_F(SlaveTest, NmtStateMachine_7_3_2_StopFromPreOperationalAndOperational) {
  make();
  rx("000#027F");
  EXPECT_EQ(slave->state(), S::Stopped);
  rx("000#807F");
  rx("000#017F");
  rx("000#027F");
  EXPECT_EQ(slave->state(), S::Stopped);
}

TEST_F(SlaveTest, NmtStateMachine_7_3_2_EnterPreOperationalFromOperationalAndStopped) {
  make();
  rx("000#017F");
  rx("000#807F");
  EXPECT_EQ(slave->state(), S::PreOperational);
  rx("000#027F");
  rx("000#807F");
  EXPECT_EQ(slave->state(), S::PreOperational);
}

TEST_F(SlaveTest, NmtStateMachine_7_3_2_ReportsEachStateChangeOnce) {
  make();
  calls.clear();
  rx("000#017F");
  rx("000#017F");  // already operational: no change
  rx("000#027F");
  rx("000#807F");
  EXPECT_EQ(calls, (Strings{"pre-operational -> operational", "operational -> stopped",
                            "stopped -> pre-operational"}));
}

TEST_F(SlaveTest, NmtStateMachine_7_3_2_ResetNodeFromEveryStateRunsBothSubStatesAndBootsUp) {
  make();
  for (const char* to : {"", "000#017F", "000#027F"}) {
    if (*to != '\0') rx(to);
    log.take();
    calls.clear();
    EXPECT_TRUE(rx("000#817F"));
    EXPECT_EQ(log.take(), (Strings{"77F#00"}));
    EXPECT_EQ(slave->state(), S::PreOperational);
    EXPECT_EQ(calls.at(0), "reset application");
    EXPECT_EQ(calls.at(1), "reset communication");
  }
}

TEST_F(SlaveTest, NmtStateMachine_7_3_2_ResetCommunicationSkipsResetApplication) {
  make();
  rx("000#017F");
  log.take();
  calls.clear();
  EXPECT_TRUE(rx("000#827F"));
  EXPECT_EQ(log.take(), (Strings{"77F#00"}));
  EXPECT_EQ(calls, (Strings{"reset communication", "initialising -> pre-operational"}));
  EXPECT_EQ(slave->state(), S::PreOperational);
}

TEST_F(SlaveTest, NodeControl_7_2_8_3_1_CommandsToOtherNodesAreIgnored) {
  make();
  EXPECT_FALSE(rx("000#0105"));
  EXPECT_FALSE(rx("000#8105"));
  EXPECT_EQ(slave->state(), S::PreOperational);
  EXPECT_EQ(log.take(), (Strings{"77F#00"}));
}

TEST_F(SlaveTest, NodeControl_7_2_8_3_1_NodeZeroAddressesAllNodes) {
  make();
  EXPECT_TRUE(rx("000#0100"));
  EXPECT_EQ(slave->state(), S::Operational);
  EXPECT_TRUE(rx("000#0200"));
  EXPECT_EQ(slave->state(), S::Stopped);
  log.take();
  EXPECT_TRUE(rx("000#8200"));
  EXPECT_EQ(log.take(), (Strings{"77F#00"}));
}

TEST_F(SlaveTest, NodeControl_7_2_8_3_1_MalformedCommandFramesAreIgnored) {
  make();
  EXPECT_FALSE(rx("000#01"));        // too short
  EXPECT_FALSE(rx("000#017F00"));    // too long
  EXPECT_FALSE(rx("000#037F"));      // unknown command specifier
  EXPECT_FALSE(rx("000#R2"));        // remote frame
  EXPECT_FALSE(rx("00000000#017F")); // extended identifier
  EXPECT_FALSE(rx("001#017F"));      // other COB-ID
  EXPECT_EQ(slave->state(), S::PreOperational);
}

TEST_F(SlaveTest, NodeControl_7_3_2_3_LocalControlUsesTheSameTransitions) {
  make();
  slave->command(NmtCommand::Start, clock.now());
  EXPECT_EQ(slave->state(), S::Operational);
  slave->command(NmtCommand::ResetCommunication, clock.now());
  EXPECT_EQ(slave->state(), S::PreOperational);
}

// ---- 7.3.2.2.5 table 37 ----------------------------------------------------------------

TEST_F(SlaveTest, ServiceTable_7_3_2_2_5_ServicesActivePerState) {
  make(false);
  const std::vector<Service> all{Service::Pdo, Service::Sdo, Service::Sync, Service::Time,
                                 Service::Emcy, Service::NodeControl, Service::ErrorControl, Service::BootUp};
  auto active = [&] {
    std::string s;
    for (const Service sv : all) s += slave->service_active(sv) ? 'X' : '.';
    return s;
  };
  //                 PDO SDO SYNC TIME EMCY NMT ERR BOOT
  EXPECT_EQ(active(), ".......X");  // initialising
  slave->start(clock.now());
  EXPECT_EQ(active(), ".XXXXXX.");  // pre-operational
  rx("000#017F");
  EXPECT_EQ(active(), "XXXXXXX.");  // operational
  rx("000#027F");
  EXPECT_EQ(active(), ".....XX.");  // stopped
}

// ---- 7.2.8.3.2.2 heartbeat producer ----------------------------------------------------

TEST_F(SlaveTest, Heartbeat_7_2_8_3_2_ProducerOffWhen1017hIsZero) {
  make();
  log.take();
  EXPECT_EQ(slave->next_deadline(), TimePoint::max());
  advance(10s);
  EXPECT_TRUE(log.frames.empty());
}

TEST_F(SlaveTest, Heartbeat_7_2_8_3_2_ProducerPeriodFollows1017hFromBootUp) {
  ASSERT_FALSE(od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  make();
  const TimePoint boot = clock.now();
  EXPECT_EQ(log.take(), (Strings{"77F#00"}));
  EXPECT_EQ(slave->next_deadline(), boot + 100ms);
  advance(99ms);
  EXPECT_TRUE(log.frames.empty());
  advance(1ms);
  EXPECT_EQ(log.take(), (Strings{"77F#7F"}));
  rx("000#017F");
  advance(100ms);
  EXPECT_EQ(log.take(), (Strings{"77F#05"}));
  rx("000#027F");
  advance(200ms);
  EXPECT_EQ(log.take(), (Strings{"77F#04", "77F#04"}));  // stopped still sends heartbeats
}

TEST_F(SlaveTest, Heartbeat_7_2_8_3_2_WriteTo1017hStartsChangesAndStopsTheProducer) {
  make();
  log.take();
  sdo_write_u16(0x1017, 50);
  EXPECT_EQ(slave->next_deadline(), TimePoint::min());  // wants on_time() to apply the write
  slave->on_time(clock.now());
  EXPECT_EQ(slave->heartbeat_period(), 50ms);
  advance(150ms);
  EXPECT_EQ(log.take(), (Strings{"77F#7F", "77F#7F", "77F#7F"}));
  sdo_write_u16(0x1017, 200);
  advance(199ms);
  EXPECT_TRUE(log.frames.empty());
  advance(1ms);
  EXPECT_EQ(log.take(), (Strings{"77F#7F"}));
  sdo_write_u16(0x1017, 0);
  advance(10s);
  EXPECT_TRUE(log.frames.empty());
  EXPECT_EQ(slave->next_deadline(), TimePoint::max());
}

TEST_F(SlaveTest, Heartbeat_7_2_8_3_2_2_ResetRestartsThePeriodFromTheNewBootUp) {
  ASSERT_FALSE(od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  make();
  advance(60ms);
  log.take();
  rx("000#817F");
  EXPECT_EQ(log.take(), (Strings{"77F#00"}));
  advance(99ms);
  EXPECT_TRUE(log.frames.empty());
  advance(1ms);
  EXPECT_EQ(log.take(), (Strings{"77F#7F"}));
}

TEST_F(SlaveTest, Heartbeat_7_2_8_3_2_ReconfigureReadsLocalSet) {
  make();
  log.take();
  ASSERT_FALSE(od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 30)));
  slave->reconfigure(clock.now());
  advance(30ms);
  EXPECT_EQ(log.take(), (Strings{"77F#7F"}));
}

TEST_F(SlaveTest, Heartbeat_7_2_8_3_2_LateOnTimeKeepsThePeriodGridWithoutBursts) {
  ASSERT_FALSE(od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  make();
  log.take();
  const TimePoint boot = clock.now();
  clock.advance(350ms);
  slave->on_time(clock.now());
  EXPECT_EQ(log.take(), (Strings{"77F#7F"}));
  EXPECT_EQ(slave->next_deadline(), boot + 400ms);
}

// ---- 7.2.8.3.2.1 node guarding and life guarding (slave side) -------------------------

TEST_F(SlaveTest, NodeGuarding_7_2_8_3_2_1_AnswersWithStateAndAlternatingToggle) {
  make();
  log.take();
  EXPECT_TRUE(rx("77F#R1"));
  EXPECT_TRUE(rx("77F#R1"));
  rx("000#017F");
  EXPECT_TRUE(rx("77F#R1"));
  rx("000#027F");
  EXPECT_TRUE(rx("77F#R1"));
  EXPECT_EQ(log.take(), (Strings{"77F#7F", "77F#FF", "77F#05", "77F#84"}));
  EXPECT_FALSE(rx("705#R1"));  // another node's request
  EXPECT_TRUE(log.frames.empty());
}

TEST_F(SlaveTest, NodeGuarding_7_2_8_3_2_1_OnlyResetCommunicationClearsTheToggle) {
  make();
  rx("77F#R1");
  rx("000#017F");  // other state changes keep the toggle
  rx("77F#R1");
  rx("000#827F");
  rx("77F#R1");
  EXPECT_EQ(log.take(), (Strings{"77F#00", "77F#7F", "77F#85", "77F#00", "77F#7F"}));
}

TEST_F(SlaveTest, NodeGuarding_7_2_8_3_2_2_NotAnsweredWhileHeartbeatIsOn) {
  ASSERT_FALSE(od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  make();
  log.take();
  EXPECT_TRUE(rx("77F#R1"));
  EXPECT_TRUE(log.frames.empty());
}

TEST_F(SlaveTest, LifeGuarding_7_2_8_3_2_1_EventAfterGuardTimeTimesLifeTimeFactor) {
  ASSERT_FALSE(od.set(0x100C, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  ASSERT_FALSE(od.set(0x100D, 0, Value::of_unsigned(DataType::Unsigned8, 3)));
  make();
  EXPECT_EQ(slave->life_time(), 300ms);
  advance(10s);  // not started before the first request
  EXPECT_TRUE(life.empty());
  rx("77F#R1");
  advance(299ms);
  EXPECT_TRUE(life.empty());
  rx("77F#R1");  // refreshes
  advance(299ms);
  EXPECT_TRUE(life.empty());
  advance(1ms);
  EXPECT_EQ(life, (Strings{"occurred"}));
  advance(10s);
  EXPECT_EQ(life, (Strings{"occurred"}));  // once
  rx("77F#R1");
  EXPECT_EQ(life, (Strings{"occurred", "resolved"}));
}

TEST_F(SlaveTest, LifeGuarding_7_2_8_3_2_1_OffWhenLifeTimeFactorIsZeroAndWritesApply) {
  sdo_write_u16(0x100C, 100);
  make();
  rx("77F#R1");
  advance(10s);
  EXPECT_TRUE(life.empty());
  sdo_write_u8(0x100D, 2);
  advance(199ms);
  EXPECT_TRUE(life.empty());
  advance(1ms);
  EXPECT_EQ(life, (Strings{"occurred"}));
}

TEST_F(SlaveTest, LifeGuarding_7_2_8_3_2_1_ResetCommunicationWaitsForANewFirstRequest) {
  ASSERT_FALSE(od.set(0x100C, 0, Value::of_unsigned(DataType::Unsigned16, 100)));
  ASSERT_FALSE(od.set(0x100D, 0, Value::of_unsigned(DataType::Unsigned8, 2)));
  make();
  rx("77F#R1");
  rx("000#827F");
  advance(10s);
  EXPECT_TRUE(life.empty());
}

}  // namespace
}  // namespace canopen::nmt
