#include "trace/network_trace.hpp"

namespace gateway::trace {

NetworkTrace::NetworkTrace(TraceSettings settings, SteadyTime now)
    : settings_(std::move(settings)), ring_(settings_.capture), load_(settings_.bitrate, now) {
  decode_.own_node_id = settings_.own_node_id;
}

void NetworkTrace::received(std::span<const canopen::can::Frame> frames, SteadyTime now, WallTime wall) {
  for (const auto& f : frames) {
    Traced t{f, Direction::Rx};
    if (t.frame.timestamp == WallTime{}) t.frame.timestamp = wall;
    tap(t, now);
  }
}

void NetworkTrace::sent(const canopen::can::Frame& f, SteadyTime now, WallTime wall) {
  Traced t{f, Direction::Tx};
  t.frame.timestamp = wall;
  tap(t, now);
}

void NetworkTrace::tap(const Traced& t, SteadyTime now) {
  ++frames_;
  ring_.add(t);
  load_.add(t.frame, now);
  if (!clients_.empty()) {
    Message msg;
    for (auto& [id, c] : clients_) {
      if (!c.wants(t.frame.id)) continue;
      if (!msg) msg = std::make_shared<const std::string>(frame_json(t, decode(t.frame, decode_), classify(t.frame)));
      c.deliver(msg);
    }
  }
  for (auto& [id, r] : recorders_) r(t);
  track_sdo_block(t.frame, decode_.block);
}

std::uint64_t NetworkTrace::add_client(Client c) {
  clients_.emplace(next_id_, std::move(c));
  return next_id_++;
}

std::uint64_t NetworkTrace::add_recorder(std::function<void(const Traced&)> r) {
  recorders_.emplace(next_id_, std::move(r));
  return next_id_++;
}

void NetworkTrace::remove(std::uint64_t id) {
  clients_.erase(id);
  recorders_.erase(id);
}

}  // namespace gateway::trace
