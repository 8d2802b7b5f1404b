// Tests for stack/src/nmt/master.cpp: node control commands (7.2.8.3.1),
// node tracking from boot-up (7.2.8.3.3) and heartbeats, heartbeat consumer
// (7.2.8.3.2.2, 1016h) and node guarding master (7.2.8.3.2.1).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <variant>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/nmt/master.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "unit/stack/nmt/nmt_test_support.hpp"

namespace canopen::nmt {
namespace {

using namespace std::chrono_literals;
using Strings = std::vector<std::string>;

std::string state_text(const std::optional<NmtState>& s) { return s ? std::string(to_string(*s)) : "-"; }

std::string cause_text(NodeStateEvent::Cause c) {
  switch (c) {
    case NodeStateEvent::Cause::BootUp: return "boot-up";
    case NodeStateEvent::Cause::Heartbeat: return "heartbeat";
    case NodeStateEvent::Cause::NodeGuarding: return "guarding";
    case NodeStateEvent::Cause::Lost: return "lost";
    case NodeStateEvent::Cause::Recovered: return "recovered";
  }
  return "?";
}

// Events as text: "state 5 boot-up -/pre-operational", "hb 5 operational".
std::string event_text(const EventBody& body) {
  if (const auto* n = std::get_if<NodeStateEvent>(&body)) {
    return "state " + std::to_string(n->node) + " " + cause_text(n->cause) + " " + state_text(n->previous) + "/" +
           state_text(n->state);
  }
  if (const auto* h = std::get_if<HeartbeatEvent>(&body)) {
    return "hb " + std::to_string(h->node) + " " + std::string(to_string(h->state));
  }
  return "other";
}

class MasterTest : public ::testing::Test {
 protected:
  MasterTest()
      : master(log.sink(), [this](const EventBody& b, can::Frame::Clock::time_point ts) {
          events.push_back(event_text(b));
          stamps.push_back(ts);
        }) {}

  bool rx(const std::string& text, can::Frame::Clock::time_point ts = {}) {
    can::Frame f = test::parse(text);
    f.timestamp = ts;
    return master.on_frame(f, clock.now());
  }
  void advance(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      const TimePoint next = master.next_deadline();
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      master.on_time(clock.now());
    }
    clock.advance_to(end);
  }
  Strings take_events() {
    Strings out;
    out.swap(events);
    return out;
  }

  FakeClock clock;
  test::FrameLog log;
  Strings events;
  std::vector<can::Frame::Clock::time_point> stamps;
  NmtMaster master;
};

// ---- 7.2.8.3.1 node control ----------------------------------------------------------------

TEST_F(MasterTest, NodeControl_7_2_8_3_1_CommandFramesForOneNodeAndAll) {
  EXPECT_TRUE(master.send_command(NmtCommand::Start, 5));
  EXPECT_TRUE(master.send_command(NmtCommand::Stop, 5));
  EXPECT_TRUE(master.send_command(NmtCommand::EnterPreOperational, 127));
  EXPECT_TRUE(master.send_command(NmtCommand::ResetNode, 0));
  EXPECT_TRUE(master.send_command(NmtCommand::ResetCommunication, 0));
  EXPECT_FALSE(master.send_command(NmtCommand::Start, 128));
  EXPECT_EQ(log.take(), (Strings{"000#0105", "000#0205", "000#807F", "000#8100", "000#8200"}));
}

// ---- 7.2.8.3.3 boot-up and node tracking -----------------------------------------------------

TEST_F(MasterTest, BootUp_7_2_8_3_3_BootUpIsReportedAndCounted) {
  const auto ts = can::Frame::Clock::time_point{} + 42s;
  EXPECT_TRUE(rx("705#00", ts));
  // The boot-up message carries state 0: initialising.
  EXPECT_EQ(take_events(), (Strings{"state 5 boot-up -/initialising"}));
  EXPECT_EQ(stamps.at(0), ts);
  rx("705#00");
  EXPECT_EQ(take_events(), (Strings{"state 5 boot-up initialising/initialising"}));
  const NodeStatus* st = master.node(5);
  ASSERT_NE(st, nullptr);
  EXPECT_EQ(st->boot_ups, 2U);
  EXPECT_EQ(st->state, NmtState::Initialising);
  EXPECT_EQ(st->last_seen, clock.now());
  EXPECT_EQ(master.node(6), nullptr);
}

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_2_EveryHeartbeatIsAnEventStateChangesOnce) {
  rx("705#00");
  take_events();
  rx("705#7F");  // the node entered pre-operational after its boot-up: one change
  EXPECT_EQ(take_events(), (Strings{"hb 5 pre-operational", "state 5 heartbeat initialising/pre-operational"}));
  rx("705#7F");
  EXPECT_EQ(take_events(), (Strings{"hb 5 pre-operational"}));
  rx("705#05");
  EXPECT_EQ(take_events(), (Strings{"hb 5 operational", "state 5 heartbeat pre-operational/operational"}));
  rx("705#05");
  EXPECT_EQ(take_events(), (Strings{"hb 5 operational"}));
  rx("70A#04");  // a node never booted: previous unknown
  EXPECT_EQ(take_events(), (Strings{"hb 10 stopped", "state 10 heartbeat -/stopped"}));
  EXPECT_EQ(master.node(5)->heartbeats, 4U);
}

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_2_ForeignAndMalformedFramesAreIgnored) {
  EXPECT_FALSE(rx("700#05"));   // node-ID 0
  EXPECT_FALSE(rx("780#05"));   // outside 701h..77Fh
  EXPECT_FALSE(rx("705#R1"));   // a guarding request, not a response
  EXPECT_FALSE(rx("705#"));     // empty
  EXPECT_FALSE(rx("185#05"));
  EXPECT_TRUE(rx("705#33"));    // our COB-ID, unknown state: ignored
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(master.node(5), nullptr);
}

// ---- 7.2.8.3.2.2 heartbeat consumer ---------------------------------------------------------

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_ConsumerStartsWithTheFirstHeartbeat) {
  ASSERT_TRUE(master.set_heartbeat_consumer(5, 100ms));
  EXPECT_EQ(master.next_deadline(), TimePoint::max());
  advance(10s);
  EXPECT_TRUE(events.empty());
}

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_ConsumerTimesOutExactlyAfterConsumerTime) {
  master.set_heartbeat_consumer(5, 100ms);
  rx("705#05");
  take_events();
  advance(99ms);
  EXPECT_TRUE(events.empty());
  EXPECT_FALSE(master.node(5)->lost);
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
  EXPECT_EQ(stamps.back(), can::Frame::Clock::time_point{});
  EXPECT_TRUE(master.node(5)->lost);
  advance(10s);
  EXPECT_TRUE(events.empty());  // reported once
}

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_EachHeartbeatRestartsTheConsumerTime) {
  master.set_heartbeat_consumer(5, 100ms);
  rx("705#7F");
  for (int i = 0; i < 5; ++i) {
    advance(99ms);
    rx("705#7F");
  }
  take_events();
  advance(99ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost pre-operational/-"}));
}

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_HeardAgainAfterLostIsRecovered) {
  master.set_heartbeat_consumer(5, 100ms);
  rx("705#7F");
  advance(100ms);
  take_events();
  rx("705#05");
  EXPECT_EQ(take_events(), (Strings{"hb 5 operational", "state 5 recovered pre-operational/operational"}));
  EXPECT_FALSE(master.node(5)->lost);
  advance(100ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
}

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_BootUpCountsAsFirstHeartbeatAndClearsLost) {
  master.set_heartbeat_consumer(5, 100ms);
  rx("705#00");
  advance(100ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 boot-up -/initialising", "state 5 lost initialising/-"}));
  rx("705#00");
  EXPECT_EQ(take_events(), (Strings{"state 5 boot-up initialising/initialising"}));
  EXPECT_FALSE(master.node(5)->lost);
}

TEST_F(MasterTest, Heartbeat_7_2_8_3_2_SeveralConsumersFrom1016h) {
  od::ObjectDictionary od = od::make_gateway_dictionary(0x7F, {});
  ASSERT_FALSE(od.set(0x1016, 1, Value::of_unsigned(DataType::Unsigned32, 0x00050064)));  // node 5, 100 ms
  ASSERT_FALSE(od.set(0x1016, 2, Value::of_unsigned(DataType::Unsigned32, 0x000A00C8)));  // node 10, 200 ms
  ASSERT_FALSE(od.set(0x1016, 3, Value::of_unsigned(DataType::Unsigned32, 0x000B0000)));  // time 0: unused
  ASSERT_FALSE(od.set(0x1016, 4, Value::of_unsigned(DataType::Unsigned32, 0x00000064)));  // node 0: unused
  master.configure_consumers(od);
  rx("705#05");
  rx("70A#05");
  rx("70B#05");
  take_events();
  advance(100ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
  advance(99ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 10 lost operational/-"}));
  advance(10s);
  EXPECT_TRUE(events.empty());  // node 11 is not monitored

  // Reconfiguring drops consumers no longer listed.
  ASSERT_FALSE(od.set(0x1016, 1, Value::of_unsigned(DataType::Unsigned32, 0)));
  master.configure_consumers(od);
  rx("705#05");
  rx("70A#05");
  take_events();
  advance(200ms);
  EXPECT_EQ(take_events(), (Strings{"state 10 lost operational/-"}));
}

// ---- 7.2.8.3.2.1 node guarding master ----------------------------------------------------------

TEST_F(MasterTest, NodeGuarding_7_2_8_3_2_1_RequestEveryGuardTime) {
  ASSERT_TRUE(master.set_node_guarding(5, 100ms, 3, clock.now()));
  advance(0ms);
  EXPECT_EQ(log.take(), (Strings{"705#R1"}));
  advance(99ms);
  EXPECT_TRUE(log.frames.empty());
  advance(1ms);
  EXPECT_EQ(log.take(), (Strings{"705#R1"}));
  rx("705#7F");
  advance(100ms);
  EXPECT_EQ(log.take(), (Strings{"705#R1"}));
}

TEST_F(MasterTest, NodeGuarding_7_2_8_3_2_1_ToggleMustAlternate) {
  master.set_node_guarding(5, 100ms, 3, clock.now());
  advance(0ms);
  EXPECT_TRUE(rx("705#7F"));  // toggle 0
  EXPECT_EQ(take_events(), (Strings{"state 5 guarding -/pre-operational"}));
  advance(100ms);
  EXPECT_TRUE(rx("705#85"));  // toggle 1, operational
  EXPECT_EQ(take_events(), (Strings{"state 5 guarding pre-operational/operational"}));
  advance(100ms);
  EXPECT_TRUE(rx("705#84"));  // toggle 1 again: ignored
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(master.node(5)->toggle_errors, 1U);
  EXPECT_EQ(master.node(5)->state, NmtState::Operational);
  EXPECT_TRUE(rx("705#04"));  // toggle 0: accepted
  EXPECT_EQ(take_events(), (Strings{"state 5 guarding operational/stopped"}));
}

TEST_F(MasterTest, NodeGuarding_7_2_8_3_2_1_RepeatedToggleDoesNotKeepTheNodeAlive) {
  master.set_node_guarding(5, 100ms, 2, clock.now());
  advance(0ms);
  rx("705#7F");
  take_events();
  for (int i = 0; i < 2; ++i) {
    advance(100ms);
    rx("705#7F");  // toggle 0 every time: all ignored
  }
  EXPECT_EQ(take_events(), (Strings{"state 5 lost pre-operational/-"}));
  EXPECT_EQ(master.node(5)->toggle_errors, 2U);
}

TEST_F(MasterTest, NodeGuarding_7_2_8_3_2_1_NoResponseWithinLifeTimeIsLost) {
  master.set_node_guarding(5, 100ms, 3, clock.now());
  advance(0ms);
  rx("705#7F");
  take_events();
  advance(299ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost pre-operational/-"}));
  EXPECT_EQ(log.take(), (Strings{"705#R1", "705#R1", "705#R1", "705#R1"}));  // requests continue
  advance(100ms);
  rx("705#FF");
  EXPECT_EQ(take_events(), (Strings{"state 5 recovered pre-operational/pre-operational"}));
}

TEST_F(MasterTest, NodeGuarding_7_2_8_3_2_1_NeverAnsweringNodeIsLost) {
  master.set_node_guarding(5, 50ms, 2, clock.now());
  advance(99ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost -/-"}));
}

TEST_F(MasterTest, NodeGuarding_7_2_8_3_2_1_BootUpDuringGuardingRestartsTheToggle) {
  master.set_node_guarding(5, 100ms, 3, clock.now());
  advance(0ms);
  rx("705#7F");  // toggle 0
  advance(100ms);
  EXPECT_TRUE(rx("705#00"));  // the node rebooted while a request was outstanding
  EXPECT_EQ(master.node(5)->boot_ups, 1U);
  EXPECT_EQ(master.node(5)->toggle_errors, 0U);
  take_events();
  rx("705#7F");  // toggle 0 again after reset communication: accepted
  EXPECT_EQ(master.node(5)->toggle_errors, 0U);
  EXPECT_EQ(master.node(5)->last_seen, clock.now());
}

TEST_F(MasterTest, NodeGuarding_7_2_8_3_2_1_ZeroGuardTimeOrFactorDisables) {
  master.set_node_guarding(5, 100ms, 3, clock.now());
  master.set_node_guarding(5, 100ms, 0, clock.now());
  master.set_node_guarding(6, 0ms, 3, clock.now());
  EXPECT_EQ(master.next_deadline(), TimePoint::max());
  EXPECT_FALSE(master.set_node_guarding(0, 100ms, 3, clock.now()));
}

// ---- watching without a configured consumer time ---------------------------------------------
// api-contract "Node monitoring without configuration": P from the node's
// 1017h (7.5.2.20) in its EDS/DCF, else learnt from its heartbeats
// (7.2.8.3.2.2); lost when no heartbeat came for 3 x P.

std::string source_path(const char* rel) { return std::string(CANOPEN_SOURCE_DIR) + "/" + rel; }

TEST_F(MasterTest, AutoWatch_7_2_8_3_2_2_PeriodFromTheEds1017h_LostAtThreeTimesPNotBefore) {
  const auto io = eds::load_device_description(source_path("deploy/eds/cia401-io-module.eds"), 10);
  ASSERT_EQ(producer_heartbeat_time(io.od), 1000ms) << "the EDS's DefaultValue";
  ASSERT_TRUE(master.set_auto_watch(10, true, producer_heartbeat_time(io.od)));
  rx("70A#05");  // with P known, one heartbeat starts the watch
  take_events();
  EXPECT_EQ(master.auto_watch_period(10), 1000ms);
  advance(2999ms);
  EXPECT_TRUE(events.empty()) << "not before 3 x P";
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 10 lost operational/-"}));
  EXPECT_TRUE(master.node(10)->lost);
  rx("70A#05");
  EXPECT_EQ(take_events(), (Strings{"hb 10 operational", "state 10 recovered operational/operational"}));
  advance(3000ms);
  EXPECT_EQ(take_events(), (Strings{"state 10 lost operational/-"})) << "the given P holds after recovery";

  // A description whose 1017h is 0 gives no period: it is learnt instead.
  const auto drive = eds::load_device_description(source_path("deploy/eds/cia402-drive.eds"), 5);
  EXPECT_EQ(producer_heartbeat_time(drive.od), 0ms);
}

TEST_F(MasterTest, AutoWatch_7_2_8_3_2_2_PeriodLearntFromTwoHeartbeats_LostAtThreeTimesPNotBefore) {
  rx("706#7F");  // node 6 is heard once: no period, never lost
  rx("705#05");
  advance(200ms);
  rx("705#05");  // P = 200 ms
  take_events();
  EXPECT_EQ(master.auto_watch_period(5), 200ms);
  EXPECT_EQ(master.auto_watch_period(6), 0ms);
  advance(599ms);
  EXPECT_TRUE(events.empty()) << "not before 3 x P";
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
  advance(10s);
  EXPECT_TRUE(events.empty()) << "lost once; node 6 is not watched without a period";
  // Heard again: recovered, and two heartbeats give P again.
  rx("705#7F");
  advance(200ms);
  rx("705#7F");
  EXPECT_EQ(master.auto_watch_period(5), 200ms);
  // A boot-up counts as a heartbeat for the deadline.
  advance(500ms);
  rx("705#00");
  take_events();
  advance(599ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost initialising/-"}));
}

TEST_F(MasterTest, AutoWatch_7_2_8_3_2_2_LearntPeriodFollowsANodeThatSlowsDownOrSpeedsUp) {
  auto beat = [&] { rx("705#05"); };
  beat();
  advance(100ms);
  beat();  // P = 100 ms
  advance(250ms);
  beat();  // slower, but inside 3 x P: P grows to 250 ms at once
  EXPECT_EQ(master.auto_watch_period(5), 250ms);
  take_events();
  advance(749ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
  // The node was given 1017h = 1000 ms: lost at 3 x 250 ms once, then the
  // two heartbeats after the recovery give the new P.
  beat();
  advance(1000ms);
  beat();
  EXPECT_EQ(master.auto_watch_period(5), 1000ms);
  advance(1000ms);
  beat();
  take_events();
  // Faster again: the longer intervals leave the window of 8.
  for (int i = 0; i < 7; ++i) {
    advance(100ms);
    beat();
  }
  EXPECT_EQ(master.auto_watch_period(5), 1000ms);
  advance(100ms);
  beat();
  EXPECT_EQ(master.auto_watch_period(5), 100ms);
  EXPECT_EQ(take_events().size(), 8U) << "heartbeats only, never lost";
  advance(300ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
}

// Issue 28 item 2: the gateway wrote 1017h = 500 ms to a node whose EDS
// says 100 ms; the watch takes the written period at once instead of
// reporting the node lost and recovered at every heartbeat.
TEST_F(MasterTest, AutoWatch_7_5_2_19_AProducerTimeWrittenByThisSideIsWatchedAtOnce) {
  ASSERT_TRUE(master.set_auto_watch(5, true, 100ms));
  rx("705#05");
  ASSERT_TRUE(master.set_producer_time(5, 500ms, clock.now()));
  EXPECT_EQ(master.auto_watch_period(5), 500ms);
  EXPECT_EQ(master.next_deadline(), clock.now() + 1500ms) << "3 x the new period from the write";
  take_events();
  for (int i = 0; i < 10; ++i) {
    advance(500ms);
    rx("705#05");
  }
  EXPECT_EQ(take_events().size(), 10U) << "heartbeats only, never lost";
  advance(1499ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"})) << "still watched: lost at 3 x 500 ms";
  // 1017h = 0: the node sends no heartbeat any more, so none is expected.
  rx("705#05");
  ASSERT_TRUE(master.set_producer_time(5, 0ms, clock.now()));
  take_events();
  advance(60s);
  EXPECT_TRUE(events.empty());
  EXPECT_FALSE(master.set_producer_time(0, 100ms, clock.now()));
  // Not watched automatically (heartbeat-consumer-ms 0): stays so.
  ASSERT_TRUE(master.set_auto_watch(6, false));
  ASSERT_TRUE(master.set_producer_time(6, 100ms, clock.now()));
  EXPECT_EQ(master.auto_watch_period(6), 0ms);
}

// CiA 301 7.5.2.19 (consumer time above producer time): the EDS says 100 ms
// but another tool gave the node 500 ms. Lost at 3 x 100 ms before each of
// its heartbeats at first; after two such gaps the watch follows the
// producer. A single long gap (the node away once) does not stretch P: see
// PeriodFromTheEds1017h above.
TEST_F(MasterTest, AutoWatch_7_5_2_19_AGivenPeriodFollowsAProducerThatIsSlowerThanIt) {
  ASSERT_TRUE(master.set_auto_watch(5, true, 100ms));
  rx("705#05");
  take_events();
  for (int i = 0; i < 20; ++i) {
    advance(500ms);
    rx("705#05");
  }
  const auto seen = take_events();
  EXPECT_EQ(std::count(seen.begin(), seen.end(), "state 5 lost operational/-"), 2) << testing::PrintToString(seen);
  EXPECT_EQ(master.auto_watch_period(5), 500ms);
  EXPECT_EQ(seen.back(), "hb 5 operational") << "the last ten heartbeats: no loss";
  // Back to 100 ms: the given period is a floor; the long intervals leave the window.
  for (int i = 0; i < 8; ++i) {
    advance(100ms);
    rx("705#05");
  }
  EXPECT_EQ(master.auto_watch_period(5), 100ms);
}

TEST_F(MasterTest, AutoWatch_7_2_8_3_2_2_OffForANodeConfiguredWithZero) {
  ASSERT_TRUE(master.set_auto_watch(5, false));
  for (int i = 0; i < 3; ++i) {
    rx("705#05");
    advance(100ms);
  }
  EXPECT_EQ(master.auto_watch_period(5), 0ms);
  EXPECT_EQ(master.next_deadline(), TimePoint::max());
  take_events();
  advance(10s);
  EXPECT_TRUE(events.empty());
  EXPECT_FALSE(master.set_auto_watch(0, false));
  EXPECT_FALSE(master.set_auto_watch(128, true));
}

TEST_F(MasterTest, AutoWatch_7_2_8_3_2_2_AConfiguredConsumerTimeWins) {
  ASSERT_TRUE(master.set_heartbeat_consumer(5, 1000ms));
  rx("705#05");
  advance(100ms);
  rx("705#05");  // a learnt P of 100 ms would make it lost at 300 ms
  take_events();
  advance(999ms);
  EXPECT_TRUE(events.empty());
  advance(1ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
  // Without the consumer the learnt period watches the node again.
  ASSERT_TRUE(master.set_heartbeat_consumer(5, 0ms));
  rx("705#05");
  advance(100ms);
  rx("705#05");
  take_events();
  advance(300ms);
  EXPECT_EQ(take_events(), (Strings{"state 5 lost operational/-"}));
}

}  // namespace
}  // namespace canopen::nmt
