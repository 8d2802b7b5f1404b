// The frame tap of one network: every frame received and sent on it, with
// its time and direction, goes to the capture ring, the bus-load meter and
// whoever subscribed (trace WebSocket clients, a capture of the next
// seconds). NetworkUnit calls received()/sent() on the bus path, so they
// are cheap: with no subscriber a frame costs a ring record, the load
// meter's addition and the SDO block tracker's few tests; decoding and
// JSON happen only for frames a subscriber wants, once per frame whatever
// the number of subscribers. Nothing here blocks or waits for a
// subscriber: a subscriber queues and drops on its own (TraceQueue).
//
// Thread safety: none; io_context thread only. Subscribers MUST NOT
// subscribe or unsubscribe from inside a callback.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <span>
#include <string>

#include "trace/bus_load.hpp"
#include "trace/capture.hpp"
#include "trace/frame_decode.hpp"
#include "trace/trace_stream.hpp"

namespace gateway::trace {

struct TraceSettings {
  std::string interface;         // the name in candump lines and the pcapng IDB
  std::uint8_t own_node_id = 0;  // the gateway's node-ID on the network (SDO rx/tx names)
  std::uint32_t bitrate = 0;     // bit/s, 0 = unknown
  CaptureLimits capture;
};

class NetworkTrace {
 public:
  using SteadyTime = std::chrono::steady_clock::time_point;
  NetworkTrace(TraceSettings settings, SteadyTime now);

  // A received batch, in bus order. Frames without a kernel time (the
  // epoch: the in-process bus) get `wall`.
  void received(std::span<const canopen::can::Frame> frames, SteadyTime now, WallTime wall);
  // A frame the gateway handed to the channel, at `wall`.
  void sent(const canopen::can::Frame& f, SteadyTime now, WallTime wall);

  // A trace client: `wants(id)` asked for every frame; `deliver` gets the
  // frame's JSON message (frame_json) of the frames it wants.
  struct Client {
    std::function<bool(std::uint32_t id)> wants;
    std::function<void(const Message&)> deliver;
  };
  std::uint64_t add_client(Client c);
  // A recorder gets every frame (capture of the next seconds).
  std::uint64_t add_recorder(std::function<void(const Traced&)> r);
  void remove(std::uint64_t id);
  std::size_t clients() const { return clients_.size(); }
  std::size_t recorders() const { return recorders_.size(); }

  const CaptureRing& ring() const { return ring_; }
  const BusLoad& load() const { return load_; }
  const TraceSettings& settings() const { return settings_; }
  std::uint64_t frames() const { return frames_; }

 private:
  void tap(const Traced& t, SteadyTime now);

  TraceSettings settings_;
  CaptureRing ring_;
  BusLoad load_;
  DecodeContext decode_;
  std::map<std::uint64_t, Client> clients_;
  std::map<std::uint64_t, std::function<void(const Traced&)>> recorders_;
  std::uint64_t next_id_ = 1;
  std::uint64_t frames_ = 0;
};

}  // namespace gateway::trace
