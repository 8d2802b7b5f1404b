// Event pipeline (gateway/pipeline/): each event is encoded once and the
// same message reaches every consumer; the state cache follows the stream;
// the history ring keeps the newest events in order.
#include "pipeline/pipeline.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace gateway {
namespace {

canopen::Event event(std::uint64_t seq, canopen::EventBody body) {
  canopen::Event ev;
  ev.seq = seq;
  ev.timestamp = canopen::can::Frame::Clock::time_point(std::chrono::seconds(seq));
  ev.body = std::move(body);
  return ev;
}

struct Fixture {
  Fixture() {
    cache.add_network(1, "vcan0", false);
    cache.add_network(2, "vcan1", false);
  }
  EventPipeline::Encoder encoder() {
    return [this](std::uint32_t net, const canopen::Event& ev) -> EncodedEventPtr {
      ++encodings;
      auto e = std::make_shared<EncodedEvent>();
      e->network = net;
      e->seq = ev.seq;
      e->kind = std::holds_alternative<canopen::PdoEvent>(ev.body) ? EventKind::Tpdo : EventKind::State;
      if (std::holds_alternative<canopen::SyncEvent>(ev.body)) return nullptr;  // "no message"
      e->json = std::to_string(ev.seq);
      return e;
    };
  }
  StateCache cache;
  int encodings = 0;
};

TEST(EventPipeline, EncodesOnceAndEveryConsumerGetsTheSameMessage) {
  Fixture f;
  EventPipeline p(f.encoder(), f.cache);
  std::vector<EncodedEventPtr> a, b, c;
  p.add_consumer([&](const EncodedEventPtr& e) { a.push_back(e); });
  p.add_consumer([&](const EncodedEventPtr& e) { b.push_back(e); });
  p.add_consumer([&](const EncodedEventPtr& e) { c.push_back(e); });
  for (std::uint64_t i = 1; i <= 100; ++i) p.on_event(1, event(i, canopen::HeartbeatEvent{5, canopen::NmtState::Operational}));
  EXPECT_EQ(f.encodings, 100);
  ASSERT_EQ(a.size(), 100U);
  ASSERT_EQ(b.size(), 100U);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].get(), b[i].get());  // one object, not copies
    EXPECT_EQ(a[i].get(), c[i].get());
    EXPECT_EQ(a[i]->seq, i + 1);
  }
  EXPECT_EQ(p.total(), 100U);
  EXPECT_EQ(p.published(EventKind::State), 100U);
}

TEST(EventPipeline, EventsWithoutMessageStillUpdateTheCache) {
  Fixture f;
  EventPipeline p(f.encoder(), f.cache);
  int delivered = 0;
  p.add_consumer([&](const EncodedEventPtr&) { ++delivered; });
  p.on_event(1, event(1, canopen::SyncEvent{std::uint8_t{3}}));
  EXPECT_EQ(delivered, 0);
  EXPECT_EQ(f.cache.network(1)->sync_count, 1U);
  EXPECT_EQ(f.cache.network(1)->last_sync_counter, 3);
}

TEST(EventPipeline, HistoryKeepsTheNewestInOrderPerNetwork) {
  Fixture f;
  EventPipeline p(f.encoder(), f.cache, 10);
  for (std::uint64_t i = 1; i <= 25; ++i) p.on_event(i % 2 == 0 ? 2 : 1, event(i, canopen::HeartbeatEvent{5, {}}));
  auto all = p.recent(100);
  ASSERT_EQ(all.size(), 10U);  // bounded
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_EQ(all[i]->seq, 16 + i);
  auto last3 = p.recent(3);
  ASSERT_EQ(last3.size(), 3U);
  EXPECT_EQ(last3.front()->seq, 23U);
  EXPECT_EQ(last3.back()->seq, 25U);
  auto net2 = p.recent(100, 2);
  ASSERT_EQ(net2.size(), 5U);
  for (const auto& e : net2) EXPECT_EQ(e->network, 2U);
  EXPECT_TRUE(EventPipeline(f.encoder(), f.cache).recent(5).empty());
}

TEST(StateCache, FollowsNodeStatesHeartbeatsAndLoss) {
  StateCache cache;
  cache.add_network(1, "vcan0", false);
  cache.add_configured_node(1, 5, "drive");
  using C = canopen::NodeStateEvent::Cause;
  cache.apply(1, event(1, canopen::NodeStateEvent{5, canopen::NmtState::PreOperational, {}, C::BootUp}));
  cache.apply(1, event(2, canopen::HeartbeatEvent{5, canopen::NmtState::Operational}));
  const NodeInfo* n = cache.node(1, 5);
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(n->name, "drive");
  EXPECT_TRUE(n->configured);
  EXPECT_EQ(n->boot_count, 1U);
  EXPECT_EQ(n->state, canopen::NmtState::Operational);
  EXPECT_EQ(n->last_heartbeat, canopen::can::Frame::Clock::time_point(std::chrono::seconds(2)));
  cache.apply(1, event(3, canopen::NodeStateEvent{5, std::nullopt, canopen::NmtState::Operational, C::Lost}));
  EXPECT_TRUE(n->lost);
  EXPECT_FALSE(n->state);
  cache.apply(1, event(4, canopen::NodeStateEvent{5, canopen::NmtState::Operational, {}, C::Recovered}));
  EXPECT_FALSE(n->lost);
  EXPECT_EQ(cache.network(1)->last_seq, 4U);
  // A node only heard, never configured, is known too.
  cache.apply(1, event(5, canopen::HeartbeatEvent{9, canopen::NmtState::Stopped}));
  ASSERT_NE(cache.node(1, 9), nullptr);
  EXPECT_FALSE(cache.node(1, 9)->configured);
  // Unknown networks change nothing.
  cache.apply(7, event(6, canopen::HeartbeatEvent{9, canopen::NmtState::Stopped}));
  EXPECT_EQ(cache.network(7), nullptr);
}

TEST(StateCache, KeepsLatestValuesAndBoundedEmcyHistoryNewestFirst) {
  StateCache cache(3);
  cache.add_network(1, "vcan0", false);
  canopen::PdoEvent pdo;
  pdo.node = 5;
  pdo.number = 1;
  pdo.raw = {1, 0};
  pdo.values = {{0x6041, 0, "Statusword", canopen::Value::of_unsigned(canopen::DataType::Unsigned16, 1)}};
  cache.apply(1, event(1, pdo));
  pdo.values[0].value = canopen::Value::of_unsigned(canopen::DataType::Unsigned16, 7);
  pdo.raw = {7, 0};
  cache.apply(1, event(2, pdo));
  const auto* n = cache.node(1, 5);
  ASSERT_NE(n, nullptr);
  const auto& v = n->values.at({0x6041, 0});
  EXPECT_EQ(v.name, "Statusword");
  EXPECT_EQ(std::get<std::uint64_t>(v.value.data), 7U);
  EXPECT_EQ(v.tpdo, 1);
  EXPECT_EQ(n->tpdo_raw.at(1), (canopen::Bytes{7, 0}));
  for (std::uint16_t code = 1; code <= 5; ++code) {
    canopen::EmcyEvent e;
    e.node = 5;
    e.error_code = code;
    cache.apply(1, event(10 + code, e));
  }
  EXPECT_EQ(n->emcy_count, 5U);
  ASSERT_EQ(n->emcys.size(), 3U);
  EXPECT_EQ(n->emcys.front().emcy.error_code, 5);  // newest first
  EXPECT_EQ(n->emcys.back().emcy.error_code, 3);
  // An EMCY with code 0000h says "error reset or no error" (CiA 301
  // 7.2.7.1): it is an EMCY, but no error.
  canopen::EmcyEvent reset;
  reset.node = 5;
  cache.apply(1, event(16, reset));
  EXPECT_EQ(n->emcy_count, 6U);
  EXPECT_EQ(n->emcy_error_count, 5U);
  EXPECT_EQ(n->emcys.front().emcy.error_code, 0);
  // Unclaimed PDOs belong to no node.
  canopen::PdoEvent unclaimed;
  unclaimed.cob_id = 0x1A5;
  cache.apply(1, event(20, unclaimed));
  EXPECT_EQ(cache.node(1, 0), nullptr);
}

// What the dashboard's "error" status rests on: the last EMCY since the
// node's boot-up. A reset (0000h) stays the last EMCY, with the error
// register it reports (other errors may remain); a boot-up forgets it.
TEST(StateCache, LastEmcySinceBootUp) {
  StateCache cache;
  cache.add_network(1, "vcan0", false);
  using C = canopen::NodeStateEvent::Cause;
  cache.apply(1, event(1, canopen::NodeStateEvent{5, canopen::NmtState::PreOperational, {}, C::BootUp}));
  const NodeInfo* n = cache.node(1, 5);
  ASSERT_NE(n, nullptr);
  EXPECT_FALSE(n->last_emcy);
  canopen::EmcyEvent voltage;
  voltage.node = 5;
  voltage.error_code = 0x3210;
  voltage.error_register = 0x05;
  cache.apply(1, event(2, voltage));
  ASSERT_TRUE(n->last_emcy);
  EXPECT_EQ(n->last_emcy->emcy.error_code, 0x3210);
  EXPECT_EQ(n->last_emcy->seq, 2U);
  canopen::EmcyEvent reset;
  reset.node = 5;
  cache.apply(1, event(3, reset));
  ASSERT_TRUE(n->last_emcy);
  EXPECT_EQ(n->last_emcy->emcy.error_code, 0);
  EXPECT_EQ(n->last_emcy->emcy.error_register, 0);
  EXPECT_EQ(n->emcy_error_count, 1U);
  cache.apply(1, event(4, voltage));
  cache.apply(1, event(5, canopen::NodeStateEvent{5, canopen::NmtState::PreOperational, {}, C::BootUp}));
  EXPECT_FALSE(n->last_emcy) << "a boot-up starts without the old errors";
  EXPECT_EQ(n->emcys.size(), 3U) << "the history keeps them";
  // A heartbeat or a recovery is no boot-up.
  cache.apply(1, event(6, voltage));
  cache.apply(1, event(7, canopen::NodeStateEvent{5, std::nullopt, canopen::NmtState::Operational, C::Lost}));
  cache.apply(1, event(8, canopen::NodeStateEvent{5, canopen::NmtState::Operational, {}, C::Recovered}));
  cache.apply(1, event(9, canopen::HeartbeatEvent{5, canopen::NmtState::Operational}));
  ASSERT_TRUE(n->last_emcy);
  EXPECT_EQ(n->last_emcy->seq, 6U);
}

TEST(StateCache, BusStateFollowsBusEvents) {
  StateCache cache;
  cache.add_network(1, "vcan0", false);
  canopen::can::BusEvent b;
  b.state = canopen::can::BusState::BusOff;
  cache.apply(1, event(1, b));
  EXPECT_EQ(cache.network(1)->bus, canopen::can::BusState::BusOff);
}

}  // namespace
}  // namespace gateway
