// An in-memory CAN bus for unit tests: endpoints attach to it, and every
// frame one endpoint sends is delivered to every other endpoint (as on a
// real bus; the sender does not receive its own frame, like SocketCAN with
// CAN_RAW_RECV_OWN_MSGS off).
//
// Delivery is explicit: send() only queues, deliver() hands frames out. This
// keeps protocol code free of re-entrancy (a reply is never received inside
// the send() that caused it) and lets a test step the bus frame by frame.
//
// Faults can be injected for robustness tests: random loss, duplication and
// reordering from a seeded generator (repeatable), or a per-frame verdict.
//
// Not thread-safe. The bus must outlive its endpoints.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "canopen/can/channel.hpp"

namespace canopen::can {

class MemoryBus;

class MemoryEndpoint final : public Channel {
 public:
  ~MemoryEndpoint() override;

  std::string_view name() const override { return name_; }
  SendStatus send(const Frame& frame) override;
  BusState state() const override { return tracker_.state(); }
  ChannelStats stats() const override { return stats_; }

  // Simulates a link change: a down endpoint neither sends nor receives.
  void set_link_up(bool up);

 private:
  friend class MemoryBus;
  MemoryEndpoint(MemoryBus& bus, std::string name) : bus_(&bus), name_(std::move(name)) {}
  void receive(const Frame& f);

  MemoryBus* bus_;
  std::string name_;
  BusStateTracker tracker_;
  ChannelStats stats_;
};

// What the fault hook decides for one frame.
enum class FrameVerdict : std::uint8_t { Deliver, Drop, Duplicate };

struct BusFaults {
  double loss = 0.0;       // probability a frame is lost for everyone
  double duplicate = 0.0;  // probability a frame is delivered twice
  double reorder = 0.0;    // probability a frame overtakes the one queued before it
  std::uint64_t seed = 1;
  // Called for each sent frame with its 0-based index on the bus; overrides
  // the probabilities when set.
  std::function<FrameVerdict(const Frame&, std::uint64_t index)> verdict;
};

class MemoryBus {
 public:
  explicit MemoryBus(BusFaults faults = {});
  MemoryBus(const MemoryBus&) = delete;
  MemoryBus& operator=(const MemoryBus&) = delete;

  std::unique_ptr<MemoryEndpoint> attach(std::string name);

  // Delivers one queued frame to every other attached, up endpoint.
  // Returns false when nothing was queued.
  bool deliver_one();
  // Delivers until the queue is empty, including frames sent by handlers
  // meanwhile; stops after max_frames to guard against endless ping-pong.
  // Returns the number of frames delivered.
  std::size_t deliver(std::size_t max_frames = 1'000'000);

  std::size_t pending() const { return queue_.size(); }
  std::uint64_t frames_sent() const { return sent_; }
  std::uint64_t frames_lost() const { return lost_; }

  void set_faults(BusFaults faults);
  // Source of receive timestamps; frames keep the sender's timestamp otherwise.
  void set_time_source(std::function<Frame::Clock::time_point()> now) { now_ = std::move(now); }

 private:
  friend class MemoryEndpoint;
  struct Queued {
    Frame frame;
    const MemoryEndpoint* sender;
  };
  void submit(const MemoryEndpoint& from, const Frame& f);
  void detach(const MemoryEndpoint& ep);
  bool chance(double p);

  BusFaults faults_;
  std::mt19937_64 rng_;
  std::vector<MemoryEndpoint*> endpoints_;
  std::deque<Queued> queue_;
  std::function<Frame::Clock::time_point()> now_;
  std::uint64_t sent_ = 0;
  std::uint64_t lost_ = 0;
  unsigned delivering_ = 0;  // nesting depth of deliver_one()
};

}  // namespace canopen::can
