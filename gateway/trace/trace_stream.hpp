// The per-client parts of the trace WebSocket (GET /api/v1/networks/{net}/trace)
// that need no socket: the JSON message of a frame, the id-range filter
// and the bounded queue that tells a slow client how many frames it lost.
// Sans-I/O, unit-tested on their own.
//
// Thread safety: none; used on the io_context thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "trace/capture.hpp"
#include "trace/frame_decode.hpp"

namespace gateway::trace {

using Message = std::shared_ptr<const std::string>;

// {"t":"2026-11-24T17:46:31.123456Z","id":389,"ext":false,"rtr":false,
//  "fd":false,"dir":"rx","data":"0102","decoded":"TPDO1 5",
//  "service":"tpdo","node":5}
// t: RFC 3339 UTC with microseconds; data: lower-case hex of the payload
// (empty for a remote frame); service and node from classify() (node
// absent when the frame is about no single node).
std::string frame_json(const Traced& t, std::string_view decoded, Service service);

// The client's filter message: {"ids": [[from, to], ...]}: frames whose
// identifier lies in one of the inclusive ranges (0..1FFFFFFFh, from <= to,
// at most 64 ranges); {} or {"ids": []} = every frame (also before any
// filter message). Anything else refuses the message and keeps the filter.
class IdFilter {
 public:
  static constexpr std::size_t kMaxRanges = 64;
  bool parse(std::string_view text, std::string& error);
  bool matches(std::uint32_t id) const;
  std::string to_json() const;  // {"ids":[[384,511]]}

 private:
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges_;
};

// Bounded queue of one client. A frame that does not fit (max_messages or
// max_bytes reached) is dropped and counted. The client is told
// {"lost": N}, N the frames dropped since the last such message, where the
// gap is: before the next frame that fits, or when it has caught up (the
// queue ran empty: take_lost()). Control messages (filter replies) are
// always queued.
class TraceQueue {
 public:
  struct Limits {
    std::size_t max_messages = 4096;
    std::size_t max_bytes = 2u << 20;
  };
  explicit TraceQueue(Limits limits) : limits_(limits) {}

  // False when the frame was dropped.
  bool push_frame(Message m);
  void push_control(std::string text);
  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  // The oldest message. Precondition: !empty().
  Message pop();
  // With the queue empty: {"lost": N} for frames lost since the last
  // report, once; null when none were.
  Message take_lost();
  std::uint64_t lost() const { return lost_total_; }

 private:
  bool fits(std::size_t count, std::size_t bytes) const {
    return items_.size() + count <= limits_.max_messages && bytes_ + bytes <= limits_.max_bytes;
  }
  Limits limits_;
  std::deque<Message> items_;
  std::size_t bytes_ = 0;
  std::uint64_t lost_pending_ = 0, lost_total_ = 0;
};

}  // namespace gateway::trace
