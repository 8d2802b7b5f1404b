// A can::Channel in front of another that shows every frame passing it to
// a NetworkTrace: each received batch before the services see it (so the
// trace keeps bus order: a request before the answer the services send to
// it) and each frame the channel accepted for sending, stamped with the
// time it was handed over. Everything else is the inner channel's.
//
// Thread safety: as can::Channel (one thread). The inner channel and the
// trace MUST outlive this; it takes the inner channel's handlers.
#pragma once

#include "canopen/can/channel.hpp"
#include "trace/network_trace.hpp"

namespace gateway::trace {

class TappedChannel final : public canopen::can::Channel {
 public:
  TappedChannel(canopen::can::Channel& inner, NetworkTrace& trace);
  ~TappedChannel() override;

  std::string_view name() const override { return inner_.name(); }
  canopen::can::SendStatus send(const canopen::can::Frame& frame) override;
  canopen::can::BusState state() const override { return inner_.state(); }
  canopen::can::ChannelStats stats() const override { return inner_.stats(); }

 private:
  canopen::can::Channel& inner_;
  NetworkTrace& trace_;
};

}  // namespace gateway::trace
