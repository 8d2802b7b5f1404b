// The two-tier queue behind the publisher (issue 12, item 1): `outage`
// messages cost no storage writes while the broker is connected, go to disk
// while it is not, and nothing is lost or reordered on the way.
#include "mqtt/outbound_queue.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mqtt_support.hpp"  // TempDir

using gateway::mqtt::OutboundQueue;
using gateway::mqtt::OutboundQueueOptions;
using gateway::mqtt::StorageMode;
using mqtt_test::TempDir;

namespace {

OutboundQueueOptions opts(const TempDir& d) {
  OutboundQueueOptions o;
  o.disk.dir = d.path() / "q";
  o.disk.buffered_writes = true;  // as the publisher uses it
  return o;
}

std::uint64_t push(OutboundQueue& q, const std::string& topic, int i, StorageMode mode, std::uint8_t qos = 0) {
  return q.push(topic, std::to_string(i), qos, false, mode);
}

// Hands out everything (topic:payload), acking each unless told not to.
std::vector<std::string> drain(OutboundQueue& q, bool ack = true) {
  std::vector<std::string> out;
  OutboundQueue::Item it;
  while (q.next(it)) {
    out.push_back(it.msg.topic + ":" + it.msg.payload);
    if (ack) q.ack(it.seq);
  }
  return out;
}

std::vector<std::string> seq(const std::string& topic, int from, int to) {
  std::vector<std::string> out;
  for (int i = from; i < to; ++i) out.push_back(topic + ":" + std::to_string(i));
  return out;
}

}  // namespace

// Online, `outage` messages never touch storage: not written, not synced.
TEST(OutboundQueue, OutageMessagesCostNoStorageWhileOnline) {
  TempDir d;
  OutboundQueue q(opts(d));
  q.set_online(true);
  for (int i = 0; i < 1000; ++i) ASSERT_NE(push(q, "tpdo", i, StorageMode::Outage), 0u);
  EXPECT_EQ(q.counters().memory_depth, 1000u);
  EXPECT_EQ(q.disk().depth(), 0u);
  EXPECT_EQ(drain(q), seq("tpdo", 0, 1000));
  q.disk().sync();
  EXPECT_EQ(q.depth(), 0u);
  EXPECT_EQ(q.disk().counters().storage_bytes, 0u);
  EXPECT_EQ(q.disk().counters().syncs, 0u);
}

// Offline they go to disk (and survive a restart), without an fdatasync of
// their own; `disk` messages are synced.
TEST(OutboundQueue, OutageMessagesGoToDiskWhileOfflineUnsynced) {
  TempDir d;
  {
    OutboundQueue q(opts(d));
    for (int i = 0; i < 100; ++i) push(q, "tpdo", i, StorageMode::Outage);
    EXPECT_EQ(q.disk().depth(), 100u);
    EXPECT_EQ(q.counters().to_disk, 100u);
    q.disk().sync();
    EXPECT_GT(q.disk().counters().storage_bytes, 0u);
    EXPECT_EQ(q.disk().counters().syncs, 0u);
    push(q, "state", 0, StorageMode::Disk, 1);
    q.disk().sync();
    EXPECT_EQ(q.disk().counters().syncs, 1u);
  }
  OutboundQueue q(opts(d));
  q.set_online(true);
  auto want = seq("tpdo", 0, 100);
  want.push_back("state:0");
  EXPECT_EQ(drain(q), want);
}

// The connection drops: what is in memory spills to disk (what was in
// flight included, after the rewind), in order, behind nothing newer; what
// comes while offline goes behind it; after the reconnect all arrive once.
TEST(OutboundQueue, SpillOnDisconnectKeepsOrderAndLosesNothing) {
  TempDir d;
  OutboundQueue q(opts(d));
  q.set_online(true);
  for (int i = 0; i < 10; ++i) push(q, "tpdo", i, StorageMode::Outage);
  OutboundQueue::Item it;
  for (int i = 0; i < 3; ++i) {  // 0..2 delivered
    ASSERT_TRUE(q.next(it));
    q.ack(it.seq);
  }
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(q.next(it));  // 3, 4 in flight when it drops
  q.rewind();
  q.set_online(false);
  EXPECT_EQ(q.counters().memory_depth, 0u);
  EXPECT_EQ(q.counters().spilled, 7u);
  EXPECT_EQ(q.disk().depth(), 7u);
  for (int i = 10; i < 20; ++i) push(q, "tpdo", i, StorageMode::Outage);
  q.set_online(true);
  for (int i = 20; i < 25; ++i) push(q, "tpdo", i, StorageMode::Outage);  // memory again
  EXPECT_EQ(q.counters().memory_depth, 5u);
  EXPECT_EQ(drain(q), seq("tpdo", 3, 25));
  EXPECT_EQ(q.depth(), 0u);
}

// Issue 27 item 4 (contract "Brokers", QoS 0 and storage): with the broker
// connected but slower than the buses, QoS 0 `outage` messages never touch
// storage: the oldest unsent ones make room for the newest (counted), the
// ones handed out stay; order is kept; only once offline do they spill.
TEST(OutboundQueue, FullMemoryTierWhileConnectedDropsTheOldestQos0NeverStoresThem) {
  TempDir d;
  auto o = opts(d);
  o.memory_max_messages = 10;
  OutboundQueue q(o);
  q.set_online(true);
  for (int i = 0; i < 10; ++i) push(q, "tpdo", i, StorageMode::Outage);
  OutboundQueue::Item it;
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(q.next(it));  // 0, 1 handed out (in the socket)
  for (int i = 10; i < 1000; ++i) EXPECT_NE(push(q, "tpdo", i, StorageMode::Outage), 0u) << i;
  EXPECT_EQ(q.disk().depth(), 0u);
  EXPECT_EQ(q.disk().counters().storage_bytes, 0u) << "not a byte written";
  EXPECT_EQ(q.counters().spilled + q.counters().to_disk, 0u);
  EXPECT_EQ(q.counters().dropped_backpressure, 990u);
  EXPECT_EQ(q.dropped(), 990u);
  // What is left: the two handed out (acked as written), then the newest.
  EXPECT_EQ(drain(q, false), seq("tpdo", 992, 1000));
  // A QoS 1 kind beside it still spills when the tier is full.
  push(q, "emcy", 0, StorageMode::Outage, 1);
  EXPECT_GE(q.disk().depth() + q.counters().memory_depth, 1u);
  // Offline: what is in memory spills, as before.
  q.rewind();
  q.set_online(false);
  EXPECT_EQ(q.counters().memory_depth, 0u);
  EXPECT_GT(q.counters().spilled, 0u);
}

// The memory tier fills while online (the broker does not keep up): its
// QoS 1 `outage` messages move to disk, those in flight too, without being
// sent twice: their acks (by the ids handed out) ack the disk copies.
TEST(OutboundQueue, FullMemoryTierSpillsQos1WithoutDuplicates) {
  TempDir d;
  auto o = opts(d);
  o.memory_max_messages = 10;
  OutboundQueue q(o);
  q.set_online(true);
  for (int i = 0; i < 10; ++i) push(q, "tpdo", i, StorageMode::Outage, 1);
  std::vector<std::uint64_t> in_flight;
  OutboundQueue::Item it;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(q.next(it));
    in_flight.push_back(it.seq);
  }
  for (int i = 10; i < 15; ++i) push(q, "tpdo", i, StorageMode::Outage, 1);  // full: everything spills
  EXPECT_EQ(q.counters().spilled, 10u);
  EXPECT_EQ(q.counters().memory_depth, 5u);  // 10..14: room again after the spill
  EXPECT_EQ(drain(q, false), seq("tpdo", 4, 15));  // 0..3 are in flight: not again
  for (auto id : in_flight) EXPECT_TRUE(q.ack(id));
  EXPECT_EQ(q.disk().depth(), 6u);  // 4..9, handed out above, not acked
  q.rewind();  // as after a reconnect: what is unacked comes again, in order
  EXPECT_EQ(drain(q), seq("tpdo", 4, 15));
  EXPECT_EQ(q.depth(), 0u);
  EXPECT_EQ(q.dropped(), 0u);
}

// `memory` messages never touch storage, online or not; a full tier drops
// the oldest (counted).
TEST(OutboundQueue, MemoryModeNeverTouchesStorageAndDropsOldest) {
  TempDir d;
  auto o = opts(d);
  o.memory_max_messages = 100;
  OutboundQueue q(o);
  for (int i = 0; i < 150; ++i) push(q, "hb", i, StorageMode::Memory);  // offline
  q.set_online(false);
  EXPECT_EQ(q.counters().dropped_memory, 50u);
  EXPECT_EQ(q.disk().depth(), 0u);
  q.set_online(true);
  EXPECT_EQ(drain(q), seq("hb", 50, 150));
  q.disk().sync();
  EXPECT_EQ(q.disk().counters().storage_bytes, 0u);
  // Larger than the whole tier: dropped.
  o.memory_max_bytes = 64;
  OutboundQueue small(o);
  EXPECT_EQ(small.push("hb", std::string(100, 'x'), 0, false, StorageMode::Memory), 0u);
  EXPECT_EQ(small.counters().dropped_memory, 1u);
}

// next() keeps publish order across the tiers.
TEST(OutboundQueue, PublishOrderAcrossTiers) {
  TempDir d;
  OutboundQueue q(opts(d));
  q.set_online(true);
  std::vector<std::string> want;
  for (int i = 0; i < 30; ++i) {
    const auto mode = i % 3 == 0 ? StorageMode::Disk : i % 3 == 1 ? StorageMode::Outage : StorageMode::Memory;
    const std::string topic = std::string(gateway::mqtt::to_string(mode));
    push(q, topic, i, mode, mode == StorageMode::Disk ? 1 : 0);
    want.push_back(topic + ":" + std::to_string(i));
  }
  EXPECT_EQ(drain(q, false), want);
  q.rewind();
  EXPECT_EQ(drain(q), want);  // and again after a rewind
}
