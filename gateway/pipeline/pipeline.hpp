// The event pipeline: stack events of every network -> encoded once ->
// state cache, bounded history ring, and every consumer (MQTT, WebSocket
// hub, ...). Consumers get the same immutable EncodedEventPtr, so N
// consumers cost one encoding, and a consumer that wants to keep an event
// (a queue for a slow client, the MQTT disk buffer) holds the pointer.
//
// Consumers MUST NOT block: they queue and return (the loop carries the bus).
// Thread safety: none; io_context thread only.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "canopen/events.hpp"
#include "event_message.hpp"
#include "pipeline/state_cache.hpp"

namespace gateway {

class EventPipeline {
 public:
  // Returns nullptr for an event that has no outgoing message.
  using Encoder = std::function<EncodedEventPtr(std::uint32_t network, const canopen::Event&)>;
  using Consumer = std::function<void(const EncodedEventPtr&)>;

  EventPipeline(Encoder encoder, StateCache& cache, std::size_t history_capacity = 4096);

  void add_consumer(Consumer c) { consumers_.push_back(std::move(c)); }

  // A stack event of network `network` (1-based).
  void on_event(std::uint32_t network, const canopen::Event& ev);
  // An already encoded gateway-level message (e.g. the gateway status).
  void publish(const EncodedEventPtr& ev);

  // The newest events, oldest first, at most `max`, optionally of one
  // network; a client that connects late starts from here.
  std::vector<EncodedEventPtr> recent(std::size_t max, std::optional<std::uint32_t> network = {}) const;

  std::uint64_t published(EventKind k) const { return published_[static_cast<std::size_t>(k)]; }
  std::uint64_t total() const { return total_; }

 private:
  void fan_out(const EncodedEventPtr& ev);

  Encoder encoder_;
  StateCache& cache_;
  std::vector<Consumer> consumers_;
  std::vector<EncodedEventPtr> ring_;
  std::size_t ring_next_ = 0;
  std::uint64_t total_ = 0;
  std::array<std::uint64_t, static_cast<std::size_t>(kLastEventKind) + 1> published_{};
};

}  // namespace gateway
