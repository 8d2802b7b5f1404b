// The interface every CAN network endpoint offers to the stack: the
// in-memory bus for tests and the SocketCAN adapter in production.
//
// Thread safety: a Channel is used from one thread (the io_context's, or the
// test's). Handlers are called on that thread, never from inside send().
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string_view>
#include <utility>

#include "canopen/can/bus_state.hpp"
#include "canopen/can/frame.hpp"

namespace canopen::can {

enum class SendStatus : std::uint8_t {
  Accepted,   // written, or queued and will be written in order
  QueueFull,  // transmit queue at its bound; the frame was dropped and counted
  Invalid,    // the frame is malformed or not supported here (e.g. FD on classic CAN)
};

struct ChannelStats {
  std::uint64_t rx_frames = 0;
  std::uint64_t tx_frames = 0;     // frames handed to the bus/kernel
  std::uint64_t rx_dropped = 0;    // receive overflow (socket queue or controller)
  std::uint64_t tx_dropped = 0;    // rejected because the queue was full, or failed to write
  std::uint64_t tx_retries = 0;    // writes repeated after ENOBUFS/EAGAIN
  std::uint64_t error_frames = 0;  // error frames seen
  std::uint64_t reopens = 0;       // socket reopened after the interface came back
  std::size_t tx_queue_depth = 0;
  std::size_t tx_queue_high_water = 0;
};

class Channel {
 public:
  // Called with every batch of received frames, in bus order. The span is
  // only valid during the call.
  using FrameHandler = std::function<void(std::span<const Frame>)>;
  using BusEventHandler = std::function<void(const BusEvent&)>;

  Channel() = default;
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;
  virtual ~Channel() = default;

  virtual std::string_view name() const = 0;
  // Never blocks. Frames accepted are transmitted in submission order.
  virtual SendStatus send(const Frame& frame) = 0;
  virtual BusState state() const = 0;
  virtual ChannelStats stats() const = 0;

  void on_frames(FrameHandler h) { frame_handler_ = std::move(h); }
  void on_bus_event(BusEventHandler h) { bus_handler_ = std::move(h); }

 protected:
  void deliver(std::span<const Frame> frames) {
    if (frame_handler_ && !frames.empty()) frame_handler_(frames);
  }
  void report(const BusEvent& ev) {
    if (bus_handler_) bus_handler_(ev);
  }

 private:
  FrameHandler frame_handler_;
  BusEventHandler bus_handler_;
};

}  // namespace canopen::can
