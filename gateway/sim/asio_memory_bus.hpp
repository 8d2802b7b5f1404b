// can::MemoryBus inside an io_context: frames one channel sends reach the
// others asynchronously (posted), never inside send(), as on a real socket.
// Lets the gateway's Network and simulated nodes share an in-process bus
// (canopen-gateway --demo) and tests run the Asio adapters without SocketCAN.
//
// Thread safety: io_context thread only. The AsioMemoryBus must outlive
// every channel it attached; run the io_context for frames to move.
#pragma once

#include <boost/asio/io_context.hpp>

#include <memory>
#include <string>

#include "canopen/can/channel.hpp"
#include "canopen/can/memory_bus.hpp"

namespace canopen::sim {

class AsioMemoryBus;

// One endpoint of an AsioMemoryBus, usable wherever a can::Channel is.
class AsioMemoryChannel final : public can::Channel {
 public:
  ~AsioMemoryChannel() override;
  std::string_view name() const override { return ep_->name(); }
  can::SendStatus send(const can::Frame& frame) override;
  can::BusState state() const override { return ep_->state(); }
  can::ChannelStats stats() const override { return ep_->stats(); }
  // Simulates unplugging: a down channel neither sends nor receives.
  void set_link_up(bool up) { ep_->set_link_up(up); }

 private:
  friend class AsioMemoryBus;
  AsioMemoryChannel(AsioMemoryBus& owner, std::unique_ptr<can::MemoryEndpoint> ep);
  AsioMemoryBus& owner_;
  std::unique_ptr<can::MemoryEndpoint> ep_;
};

class AsioMemoryBus {
 public:
  explicit AsioMemoryBus(boost::asio::io_context& io, can::BusFaults faults = {});
  ~AsioMemoryBus();
  AsioMemoryBus(const AsioMemoryBus&) = delete;
  AsioMemoryBus& operator=(const AsioMemoryBus&) = delete;

  std::unique_ptr<AsioMemoryChannel> attach(std::string name);
  can::MemoryBus& bus() { return bus_; }

 private:
  friend class AsioMemoryChannel;
  void schedule();  // one posted delivery for everything sent until it runs

  boost::asio::io_context& io_;
  can::MemoryBus bus_;
  bool posted_ = false;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace canopen::sim
