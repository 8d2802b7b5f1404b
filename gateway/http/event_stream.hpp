// The per-client parts of the WebSocket event stream that need no socket:
// the subscription filter and the bounded send queue with its drop policy.
// Sans-I/O (time is passed in), so the policy is unit-tested on its own.
//
// Thread safety: none; used on the io_context thread.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <string_view>
#include <vector>

#include "event_message.hpp"

namespace gateway::http {

// Subscription filter, sent by the client as one JSON text message:
//
//   {"networks": [1, 2], "nodes": [5, 10], "kinds": ["tpdo", "emcy"]}
//
// - every key is optional; a missing key or an empty array means "all";
// - networks: integers 0..4294967295 (0 = gateway-level events, "status");
// - nodes: integers 0..127 (0 = events not about one node: bus, sync, time,
//   unclaimed pdo);
// - kinds: names of EventKind ("status" "bus" "state" "heartbeat" "emcy"
//   "tpdo" "pdo" "sync" "time" "boot" "transfer");
// - an event passes when it passes every dimension;
// - unknown keys, wrong types, values out of range or unknown kinds refuse
//   the whole message (the previous filter stays);
// - a new message replaces the previous filter entirely; {} = everything.
// Before any filter message the client receives everything.
class EventFilter {
 public:
  // Parses `text`; on error returns false and sets `error` (one line).
  bool parse(std::string_view text, std::string& error);
  bool matches(const EncodedEvent& ev) const;
  // Canonical JSON of the filter, e.g. {"networks":[1],"nodes":[],"kinds":["tpdo"]}.
  std::string to_json() const;

 private:
  std::vector<std::uint32_t> networks_;
  std::vector<std::uint8_t> nodes_;
  std::uint32_t kinds_ = 0;  // bit per EventKind; 0 = all
};

// Bounded per-client send queue.
//
// Policy when a message arrives and the queue is full (max_messages or
// max_bytes reached; the message being written is not counted):
//  1. "thinning": the oldest queued message of a thinnable kind (tpdo,
//     heartbeat — periodic data whose next sample supersedes it) is dropped
//     and counted, and the new message is queued;
//  2. if nothing queued is thinnable and the new message is, the new one is
//     dropped and counted;
//  3. otherwise (a non-thinnable message such as emcy or state would be lost)
//     the client is to be closed;
//  4. the client is also to be closed when the queue has stayed full (a drop
//     was needed each time) for longer than stall_timeout; "full" ends when
//     the queue drains to half of max_messages and half of max_bytes.
// Control messages (filter acks and errors) are never thinned.
class SendQueue {
 public:
  struct Limits {
    std::size_t max_messages = 1024;
    std::size_t max_bytes = 8u << 20;
    std::chrono::steady_clock::duration stall_timeout = std::chrono::seconds(10);
  };

  struct Item {
    EncodedEventPtr event;  // null for a control message
    std::string control;    // JSON text of a control message
    bool binary = false;    // send as a binary frame (event->ws_binary)
    // The event's envelope (kind, topic, message); events encoded without
    // one (tests) fall back to the bare message.
    std::string_view payload() const {
      if (!event) return control;
      if (binary) return event->ws_binary.empty() ? event->binary : event->ws_binary;
      return event->ws_json.empty() ? event->json : event->ws_json;
    }
  };

  enum class Result { Queued, Thinned, Close };

  explicit SendQueue(Limits limits) : limits_(limits) {}

  // Result::Thinned: one or more messages were dropped (dropped() grew),
  // possibly the new one itself.
  // Result::Close: the client must be closed; nothing was queued.
  Result push(Item item, std::chrono::steady_clock::time_point now);

  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  std::size_t bytes() const { return bytes_; }
  // Takes the oldest message (to be written). Precondition: !empty().
  Item pop();
  void clear();
  std::uint64_t dropped() const { return dropped_; }

  static bool thinnable(const Item& item);

 private:
  bool full(std::size_t extra_bytes) const;
  void note_drained();

  Limits limits_;
  std::deque<Item> items_;
  std::size_t bytes_ = 0;
  std::size_t thinnable_count_ = 0;
  std::uint64_t dropped_ = 0;
  bool stalled_ = false;
  std::chrono::steady_clock::time_point stalled_since_{};
};

}  // namespace gateway::http
