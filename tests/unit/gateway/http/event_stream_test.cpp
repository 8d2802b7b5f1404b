#include "http/event_stream.hpp"

#include <gtest/gtest.h>

#include <memory>

using gateway::EncodedEvent;
using gateway::EncodedEventPtr;
using gateway::EventKind;
using gateway::http::EventFilter;
using gateway::http::SendQueue;
using namespace std::chrono_literals;

namespace {

EncodedEventPtr event(EventKind k, std::uint32_t net, std::uint8_t node, std::uint64_t seq = 0,
                      std::size_t size = 10) {
  auto e = std::make_shared<EncodedEvent>();
  e->kind = k;
  e->network = net;
  e->node = node;
  e->seq = seq;
  e->json = std::string(size, 'j');
  e->binary = std::string(size / 2, 'b');
  return e;
}

SendQueue::Item item(EventKind k, std::uint64_t seq, std::size_t size = 10) {
  return SendQueue::Item{event(k, 1, 5, seq, size), {}, false};
}

}  // namespace

TEST(EventFilter, EmptyMatchesEverything) {
  EventFilter f;
  EXPECT_TRUE(f.matches(*event(EventKind::Status, 0, 0)));
  std::string err;
  ASSERT_TRUE(f.parse("{}", err)) << err;
  EXPECT_TRUE(f.matches(*event(EventKind::Tpdo, 3, 9)));
  ASSERT_TRUE(f.parse(R"({"networks":[],"nodes":[],"kinds":[]})", err)) << err;
  EXPECT_TRUE(f.matches(*event(EventKind::Emcy, 2, 1)));
}

TEST(EventFilter, AllDimensionsMustMatch) {
  EventFilter f;
  std::string err;
  ASSERT_TRUE(f.parse(R"({"networks":[1],"nodes":[5,10],"kinds":["tpdo","emcy"]})", err)) << err;
  EXPECT_TRUE(f.matches(*event(EventKind::Tpdo, 1, 5)));
  EXPECT_TRUE(f.matches(*event(EventKind::Emcy, 1, 10)));
  EXPECT_FALSE(f.matches(*event(EventKind::Heartbeat, 1, 5)));
  EXPECT_FALSE(f.matches(*event(EventKind::Tpdo, 2, 5)));
  EXPECT_FALSE(f.matches(*event(EventKind::Tpdo, 1, 6)));
  EXPECT_FALSE(f.matches(*event(EventKind::Bus, 1, 0)));  // node 0 not listed
  EXPECT_EQ(f.to_json(), R"({"networks":[1],"nodes":[5,10],"kinds":["emcy","tpdo"]})");
}

TEST(EventFilter, RefusesBadMessagesAndKeepsOldFilter) {
  EventFilter f;
  std::string err;
  ASSERT_TRUE(f.parse(R"({"kinds":["emcy"]})", err));
  for (const char* bad : {"not json", "[1]", R"({"nodes":[128]})", R"({"nodes":[-1]})", R"({"nodes":"5"})",
                          R"({"kinds":["nope"]})", R"({"kinds":[1]})", R"({"network":[1]})",
                          R"({"networks":[1.5]})"}) {
    err.clear();
    EXPECT_FALSE(f.parse(bad, err)) << bad;
    EXPECT_FALSE(err.empty()) << bad;
  }
  EXPECT_TRUE(f.matches(*event(EventKind::Emcy, 1, 1)));
  EXPECT_FALSE(f.matches(*event(EventKind::Tpdo, 1, 1)));
}

TEST(SendQueue, ThinsOldestTpdoAndHeartbeatFirst) {
  SendQueue q({4, 1 << 20, 10s});
  const auto t0 = std::chrono::steady_clock::time_point{} + 1h;
  EXPECT_EQ(q.push(item(EventKind::Emcy, 1), t0), SendQueue::Result::Queued);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 2), t0), SendQueue::Result::Queued);
  EXPECT_EQ(q.push(item(EventKind::Heartbeat, 3), t0), SendQueue::Result::Queued);
  EXPECT_EQ(q.push(item(EventKind::State, 4), t0), SendQueue::Result::Queued);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 5), t0), SendQueue::Result::Thinned);  // drops 2
  EXPECT_EQ(q.push(item(EventKind::Emcy, 6), t0), SendQueue::Result::Thinned);  // drops 3
  EXPECT_EQ(q.dropped(), 2u);
  std::vector<std::uint64_t> seqs;
  while (!q.empty()) seqs.push_back(q.pop().event->seq);
  EXPECT_EQ(seqs, (std::vector<std::uint64_t>{1, 4, 5, 6}));
}

TEST(SendQueue, ClosesWhenAnImportantMessageWouldBeLost) {
  SendQueue q({2, 1 << 20, 10s});
  const auto t0 = std::chrono::steady_clock::time_point{} + 1h;
  q.push(item(EventKind::Emcy, 1), t0);
  q.push(item(EventKind::State, 2), t0);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 3), t0), SendQueue::Result::Thinned);  // the new tpdo is dropped
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(q.push(item(EventKind::Emcy, 4), t0), SendQueue::Result::Close);
}

TEST(SendQueue, ClosesWhenFullLongerThanStallTimeout) {
  SendQueue q({2, 1 << 20, 1s});
  auto t = std::chrono::steady_clock::time_point{} + 1h;
  q.push(item(EventKind::Tpdo, 1), t);
  q.push(item(EventKind::Tpdo, 2), t);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 3), t), SendQueue::Result::Thinned);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 4), t + 900ms), SendQueue::Result::Thinned);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 5), t + 1100ms), SendQueue::Result::Close);
}

TEST(SendQueue, DrainingEndsTheStall) {
  SendQueue q({2, 1 << 20, 1s});
  auto t = std::chrono::steady_clock::time_point{} + 1h;
  q.push(item(EventKind::Tpdo, 1), t);
  q.push(item(EventKind::Tpdo, 2), t);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 3), t), SendQueue::Result::Thinned);
  q.pop();  // down to half: not full any more
  q.push(item(EventKind::Tpdo, 4), t + 2s);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 5), t + 2s), SendQueue::Result::Thinned);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 6), t + 2500ms), SendQueue::Result::Thinned);
}

TEST(SendQueue, ByteLimit) {
  SendQueue q({100, 100, 10s});
  auto t = std::chrono::steady_clock::time_point{} + 1h;
  q.push(item(EventKind::Tpdo, 1, 40), t);
  q.push(item(EventKind::Tpdo, 2, 40), t);
  EXPECT_EQ(q.bytes(), 80u);
  EXPECT_EQ(q.push(item(EventKind::Tpdo, 3, 40), t), SendQueue::Result::Thinned);
  EXPECT_EQ(q.bytes(), 80u);
  EXPECT_EQ(q.pop().event->seq, 2u);
  // A control message is never thinned.
  SendQueue::Item ctl{nullptr, std::string(10, 'c'), false};
  EXPECT_FALSE(SendQueue::thinnable(ctl));
}
