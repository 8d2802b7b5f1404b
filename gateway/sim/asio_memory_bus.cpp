#include "sim/asio_memory_bus.hpp"

#include <boost/asio/post.hpp>

namespace canopen::sim {

AsioMemoryChannel::AsioMemoryChannel(AsioMemoryBus& owner, std::unique_ptr<can::MemoryEndpoint> ep)
    : owner_(owner), ep_(std::move(ep)) {
  ep_->on_frames([this](std::span<const can::Frame> frames) { deliver(frames); });
  // Link changes (set_link_up) are bus events, as on a SocketCAN channel.
  ep_->on_bus_event([this](const can::BusEvent& ev) { report(ev); });
}

AsioMemoryChannel::~AsioMemoryChannel() {
  ep_->on_frames(nullptr);
  ep_->on_bus_event(nullptr);
}

can::SendStatus AsioMemoryChannel::send(const can::Frame& frame) {
  const auto status = ep_->send(frame);
  if (status == can::SendStatus::Accepted) owner_.schedule();
  return status;
}

AsioMemoryBus::AsioMemoryBus(boost::asio::io_context& io, can::BusFaults faults) : io_(io), bus_(std::move(faults)) {
  // Receive timestamps as SocketCAN would give them.
  bus_.set_time_source([] { return can::Frame::Clock::now(); });
}

AsioMemoryBus::~AsioMemoryBus() { *alive_ = false; }

std::unique_ptr<AsioMemoryChannel> AsioMemoryBus::attach(std::string name) {
  return std::unique_ptr<AsioMemoryChannel>(new AsioMemoryChannel(*this, bus_.attach(std::move(name))));
}

void AsioMemoryBus::schedule() {
  if (posted_) return;
  posted_ = true;
  boost::asio::post(io_, [this, alive = std::weak_ptr<bool>(alive_)] {
    if (alive.expired()) return;
    posted_ = false;
    bus_.deliver();
  });
}

}  // namespace canopen::sim
