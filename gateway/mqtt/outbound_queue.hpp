// The publisher's outgoing messages in two tiers: a bounded memory tier and
// the DiskQueue, chosen per message by its StorageMode (per event kind in
// the configuration), so that messages that need not survive a crash cost
// no storage writes while the broker takes them (flash wear, issue 12).
//
//   Disk    written to the DiskQueue (durable: fdatasync'ed by sync()).
//           Survives kill -9 and, up to the sync interval, a power loss.
//   Outage  in memory while online(); written to the DiskQueue (not
//           durable: never fdatasync'ed on its own) while offline. When
//           the memory tier is full while online (the broker or the link
//           is slower than the buses), QoS 0 ones never go to storage (the
//           flash wear of issue 27 item 4): the oldest unsent QoS 0 Outage
//           messages are dropped for the new one (dropped_backpressure; a
//           dashboard wants the latest TPDO, not a backlog); QoS 1 ones
//           spill to the DiskQueue as before. Going
//           offline (set_online(false)) moves every Outage message still in
//           memory to the DiskQueue, in order ("spill"), so a broker outage
//           and a restart lose nothing within the DiskQueue's bounds.
//   Memory  in memory only, online or not; never on storage. Lost on a
//           restart; when the tier is full the oldest are dropped.
//
// Order: next() hands out messages in the order they were pushed across
// both tiers (each memory message remembers the DiskQueue's next sequence
// number at its push, and waits for the disk messages older than it). A
// spill re-appends messages at the end of the DiskQueue; all Outage
// messages in memory spill together and every later Outage message goes
// behind them, so per topic (one topic is one event kind, so one mode) the
// order always holds. Messages handed out and not yet acked when they spill
// stay "in flight": their ack (by the id handed out) acks the disk copy,
// and the disk copy is handed out again only after a rewind().
//
// Memory tier full (memory_max_messages or memory_max_bytes over messages
// not yet acked): a new QoS 0 Outage message, while online, first drops
// the oldest unsent QoS 0 Outage messages, and is dropped itself if that
// makes no room; otherwise all QoS 1 Outage messages in memory spill to the
// DiskQueue (every Outage one when offline); a new Outage QoS 1 message
// that still does not fit goes to the DiskQueue; a
// new Memory message makes room by dropping the oldest Memory messages
// (counted in dropped_memory), or is dropped itself if it alone is larger
// than the tier.
//
// Ids: what next() hands out and ack() takes; DiskQueue sequence numbers,
// or kMemoryBit | n for the memory tier.
//
// No sockets, threads or clocks (the DiskQueue does file I/O). Thread
// safety: none; one owner thread.
#pragma once

#include <cstdint>
#include <deque>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include "mqtt/disk_queue.hpp"
#include "mqtt/mqtt_config.hpp"  // StorageMode

namespace gateway::mqtt {

std::string_view to_string(StorageMode m);

struct OutboundQueueOptions {
  DiskQueueOptions disk;
  std::uint64_t memory_max_bytes = 16ull << 20;   // topic + payload bytes not yet acked
  std::uint64_t memory_max_messages = 100'000;    // messages not yet acked
};

class OutboundQueue {
 public:
  static constexpr std::uint64_t kMemoryBit = std::uint64_t{1} << 62;

  struct Counters {
    std::uint64_t memory_depth = 0;    // memory messages not yet acked
    std::uint64_t memory_bytes = 0;    // their topic + payload bytes
    std::uint64_t spilled = 0;         // Outage messages moved from memory to the DiskQueue
    std::uint64_t to_disk = 0;         // Outage messages written to the DiskQueue at push (offline or tier full)
    std::uint64_t dropped_memory = 0;  // Memory messages dropped: the tier was full
    std::uint64_t dropped_spill = 0;   // Outage messages the DiskQueue refused (full disk)
    std::uint64_t dropped_backpressure = 0;  // QoS 0 Outage messages dropped online: the tier was full
  };
  using Item = DiskQueue::Item;  // Item::seq is the id

  // Opens the DiskQueue (throws as its constructor). Starts offline.
  explicit OutboundQueue(OutboundQueueOptions opts);

  // Queues per `mode`; returns the id, or 0 when dropped (see the counters
  // of both tiers for why).
  std::uint64_t push(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained,
                     StorageMode mode);
  // Online: Outage messages may stay in memory. Going offline spills them;
  // call rewind() first (in-flight messages of a lost connection are
  // unsent again).
  void set_online(bool online);
  bool online() const { return online_; }

  bool next(Item& out);
  bool ack(std::uint64_t id);
  void rewind();
  void rewind_to(std::uint64_t id);

  std::uint64_t depth() const { return disk_.depth() + mem_live_; }
  bool has_unsent() const;

  DiskQueue& disk() { return disk_; }
  const DiskQueue& disk() const { return disk_; }
  const Counters& counters() const { return counters_; }
  // Drops across both tiers (DiskQueue drops included).
  std::uint64_t dropped() const {
    return disk_.counters().dropped() + counters_.dropped_memory + counters_.dropped_spill +
           counters_.dropped_backpressure;
  }

 private:
  struct MemEntry {
    std::uint64_t disk_mark;  // DiskQueue::next_seq() at push: older disk messages go first
    QueuedMessage msg;
    StorageMode mode;
    bool live;
  };
  static std::uint64_t cost(const MemEntry& e) { return e.msg.topic.size() + e.msg.payload.size(); }
  MemEntry* mem_entry(std::uint64_t id);
  bool make_room(std::uint64_t bytes, StorageMode mode, std::uint8_t qos);
  // Every Outage message in memory to the DiskQueue (only the QoS 1 ones
  // with qos1_only), oldest first.
  void spill(bool qos1_only = false);
  void retire(MemEntry& e);
  void pop_done();

  OutboundQueueOptions opts_;
  DiskQueue disk_;
  bool online_ = false;
  std::deque<MemEntry> mem_;       // mem_[i] has id mem_base_ + i
  std::uint64_t mem_base_ = kMemoryBit | 1;
  std::uint64_t mem_cursor_ = kMemoryBit | 1;  // next id to hand out
  std::uint64_t mem_live_ = 0, mem_bytes_ = 0, mem_outage_ = 0;
  // Spilled while handed out: memory id -> disk seq, and those disk seqs
  // (skipped by next() until a rewind()).
  std::unordered_map<std::uint64_t, std::uint64_t> moved_;
  std::unordered_set<std::uint64_t> moved_in_flight_;
  Item skip_;
  Counters counters_;
};

}  // namespace gateway::mqtt
