#include "mqtt/outbound_queue.hpp"

#include <algorithm>

namespace gateway::mqtt {

std::string_view to_string(StorageMode m) {
  switch (m) {
    case StorageMode::Disk: return "disk";
    case StorageMode::Outage: return "outage";
    case StorageMode::Memory: return "memory";
  }
  return "disk";
}

OutboundQueue::OutboundQueue(OutboundQueueOptions opts) : opts_(std::move(opts)), disk_(opts_.disk) {
  if (opts_.memory_max_messages == 0) opts_.memory_max_messages = 1;
}

OutboundQueue::MemEntry* OutboundQueue::mem_entry(std::uint64_t id) {
  if (id < mem_base_ || id - mem_base_ >= mem_.size()) return nullptr;
  return &mem_[static_cast<std::size_t>(id - mem_base_)];
}

void OutboundQueue::retire(MemEntry& e) {
  e.live = false;
  --mem_live_;
  mem_bytes_ -= cost(e);
  if (e.mode == StorageMode::Outage) --mem_outage_;
}

void OutboundQueue::pop_done() {
  while (!mem_.empty() && !mem_.front().live) {
    mem_.pop_front();
    ++mem_base_;
  }
  if (mem_cursor_ < mem_base_) mem_cursor_ = mem_base_;
  counters_.memory_depth = mem_live_;
  counters_.memory_bytes = mem_bytes_;
}

void OutboundQueue::spill(bool qos1_only) {
  if (mem_outage_ == 0) return;
  for (std::size_t i = 0; i < mem_.size() && mem_outage_ > 0; ++i) {
    MemEntry& e = mem_[i];
    if (!e.live || e.mode != StorageMode::Outage || (qos1_only && e.msg.qos == 0)) continue;
    const std::uint64_t id = mem_base_ + i;
    const std::uint64_t seq = disk_.push(e.msg.topic, e.msg.payload, e.msg.qos, e.msg.retained, false);
    if (seq == 0) {
      ++counters_.dropped_spill;
    } else {
      ++counters_.spilled;
      if (id < mem_cursor_) {
        // Handed out and not acked: its ack acks the disk copy.
        moved_[id] = seq;
        moved_in_flight_.insert(seq);
      }
    }
    retire(e);
  }
  pop_done();
}

// Room in the memory tier for a message of `bytes` (see the header).
bool OutboundQueue::make_room(std::uint64_t bytes, StorageMode mode, std::uint8_t qos) {
  if (bytes > opts_.memory_max_bytes) return false;
  auto full = [&] { return mem_live_ + 1 > opts_.memory_max_messages || mem_bytes_ + bytes > opts_.memory_max_bytes; };
  if (!full()) return true;
  if (mode == StorageMode::Outage && qos == 0 && online_) {
    // Backpressure while connected: never storage for QoS 0; the oldest
    // unsent QoS 0 Outage messages go (those handed out are as good as
    // written). Per topic the newest stays, and order is kept.
    for (std::uint64_t id = std::max(mem_cursor_, mem_base_); full() && id - mem_base_ < mem_.size(); ++id) {
      MemEntry& e = mem_[static_cast<std::size_t>(id - mem_base_)];
      if (!e.live || e.mode != StorageMode::Outage || e.msg.qos != 0) continue;
      retire(e);
      ++counters_.dropped_backpressure;
    }
    if (full()) spill(true);  // QoS 1 ones may make the room
    pop_done();
    return !full();
  }
  spill(online_);  // online: only QoS 1 ones may touch storage
  if (mode != StorageMode::Memory) return !full();
  for (std::size_t i = 0; full() && i < mem_.size(); ++i) {
    if (!mem_[i].live) continue;
    retire(mem_[i]);
    ++counters_.dropped_memory;
  }
  pop_done();
  return !full();
}

std::uint64_t OutboundQueue::push(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained,
                                  StorageMode mode) {
  if (mode == StorageMode::Disk) return disk_.push(topic, payload, qos, retained, true);
  const std::uint64_t bytes = topic.size() + payload.size();
  if ((mode == StorageMode::Outage && !online_) || !make_room(bytes, mode, qos)) {
    if (mode == StorageMode::Memory) {
      ++counters_.dropped_memory;  // larger than the whole tier
      return 0;
    }
    if (qos == 0 && online_) {
      ++counters_.dropped_backpressure;  // no room without storage
      return 0;
    }
    ++counters_.to_disk;
    return disk_.push(topic, payload, qos, retained, false);
  }
  const std::uint64_t id = mem_base_ + mem_.size();
  mem_.push_back(MemEntry{disk_.next_seq(), QueuedMessage{std::string(topic), std::string(payload), qos, retained},
                          mode, true});
  ++mem_live_;
  mem_bytes_ += bytes;
  if (mode == StorageMode::Outage) ++mem_outage_;
  counters_.memory_depth = mem_live_;
  counters_.memory_bytes = mem_bytes_;
  return id;
}

void OutboundQueue::set_online(bool online) {
  if (online_ && !online) spill();
  online_ = online;
}

bool OutboundQueue::next(Item& out) {
  for (;;) {
    const MemEntry* m = nullptr;
    for (; mem_cursor_ - mem_base_ < mem_.size(); ++mem_cursor_) {
      const MemEntry& e = mem_[static_cast<std::size_t>(mem_cursor_ - mem_base_)];
      if (e.live) {
        m = &e;
        break;
      }
    }
    const std::uint64_t d = disk_.peek();
    if (m != nullptr && (d == 0 || d >= m->disk_mark)) {
      out.seq = mem_cursor_++;
      out.msg = m->msg;
      return true;
    }
    if (d == 0) return false;
    if (!moved_in_flight_.empty() && moved_in_flight_.count(d) > 0) {
      (void)disk_.next(skip_);  // a spilled copy of a message in flight
      continue;
    }
    return disk_.next(out);
  }
}

bool OutboundQueue::ack(std::uint64_t id) {
  if ((id & kMemoryBit) == 0) return disk_.ack(id);
  if (auto it = moved_.find(id); it != moved_.end()) {
    const std::uint64_t seq = it->second;
    moved_in_flight_.erase(seq);
    moved_.erase(it);
    return disk_.ack(seq);
  }
  MemEntry* e = mem_entry(id);
  if (e == nullptr || !e->live) return false;
  retire(*e);
  pop_done();
  return true;
}

void OutboundQueue::rewind() {
  disk_.rewind();
  mem_cursor_ = mem_base_;
  moved_.clear();
  moved_in_flight_.clear();
}

void OutboundQueue::rewind_to(std::uint64_t id) {
  if ((id & kMemoryBit) == 0) {
    disk_.rewind_to(id);
  } else {
    mem_cursor_ = std::clamp(id, mem_base_, mem_cursor_);
  }
}

bool OutboundQueue::has_unsent() const {
  if (disk_.has_unsent()) return true;
  for (std::uint64_t id = std::max(mem_cursor_, mem_base_); id - mem_base_ < mem_.size(); ++id)
    if (mem_[static_cast<std::size_t>(id - mem_base_)].live) return true;
  return false;
}

}  // namespace gateway::mqtt
