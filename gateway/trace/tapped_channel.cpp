#include "trace/tapped_channel.hpp"

#include <algorithm>
#include <chrono>

namespace gateway::trace {

TappedChannel::TappedChannel(canopen::can::Channel& inner, NetworkTrace& trace) : inner_(inner), trace_(trace) {
  inner_.on_frames([this](std::span<const canopen::can::Frame> frames) {
    // The wall clock only stamps frames without the kernel's time (SocketCAN
    // gives each one): a clock read is a system call on some kernels.
    const bool stamped = std::all_of(frames.begin(), frames.end(),
                                     [](const canopen::can::Frame& f) { return f.timestamp != WallTime{}; });
    trace_.received(frames, std::chrono::steady_clock::now(), stamped ? WallTime{} : std::chrono::system_clock::now());
    deliver(frames);
  });
  inner_.on_bus_event([this](const canopen::can::BusEvent& ev) { report(ev); });
}

TappedChannel::~TappedChannel() {
  inner_.on_frames(nullptr);
  inner_.on_bus_event(nullptr);
}

canopen::can::SendStatus TappedChannel::send(const canopen::can::Frame& frame) {
  const auto status = inner_.send(frame);
  if (status == canopen::can::SendStatus::Accepted)
    trace_.sent(frame, std::chrono::steady_clock::now(), std::chrono::system_clock::now());
  return status;
}

}  // namespace gateway::trace
