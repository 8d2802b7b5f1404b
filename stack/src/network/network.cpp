#include "canopen/network.hpp"

#include <algorithm>

namespace canopen {

Network::Network(const od::ObjectDictionary& own, FrameSink sink, EventHandler on_event, sdo::ClientConfig sdo_config,
                 WallClock wall)
    : own_(own),
      on_event_(std::move(on_event)),
      wall_(std::move(wall)),
      nmt_(sink,
           [this](const EventBody& body, can::Frame::Clock::time_point ts) {
             // Timer-caused events (lost) come without a frame: stamp them now.
             emit(body, ts == can::Frame::Clock::time_point{} ? wall_() : ts);
           }),
      sdo_(sdo_config, sink),
      pdo_(sink, [this](PdoEvent ev) { emit(std::move(ev), frame_time_); }),
      emcy_(emcy::EmcyConsumerConfig::from_dictionary(own), [this](const EmcyEvent& ev) { emit(ev, frame_time_); }),
      sync_(own, [this](const SyncEvent& ev) { emit(ev, frame_time_); }),
      time_(own, [this](const TimeEvent& ev) { emit(ev, frame_time_); }) {
  pdo_.set_sync_window([this](TimePoint now) { return sync_.in_sync_window(now); });
  configure_heartbeat_consumers();
}

std::vector<std::string> Network::add_node(std::uint8_t node, const od::ObjectDictionary& description) {
  return pdo_.add_node(node, description);
}

void Network::configure_heartbeat_consumers() { nmt_.configure_consumers(own_); }

void Network::emit(EventBody body, can::Frame::Clock::time_point timestamp) {
  if (on_event_) on_event_(Event{++seq_, timestamp, std::move(body)});
}

bool Network::on_frame(const can::Frame& frame, TimePoint now) {
  frame_time_ = frame.timestamp == can::Frame::Clock::time_point{} ? wall_() : frame.timestamp;
  // Every service sees the frame; each ignores what is not its own. SDO
  // responses first: they are the ones callers wait on.
  bool used = sdo_.on_frame(frame, now);
  used = sync_.on_frame(frame, now) || used;  // SYNC before PDOs: it opens the window
  used = nmt_.on_frame(frame, now) || used;
  used = emcy_.on_frame(frame, now) || used;
  used = time_.on_frame(frame, now) || used;
  used = pdo_.on_frame(frame, now) || used;
  return used;
}

void Network::on_time(TimePoint now) {
  if (nmt_.next_deadline() <= now) nmt_.on_time(now);
  if (sdo_.next_deadline() <= now) sdo_.on_time(now);
}

TimePoint Network::next_deadline() const { return std::min(nmt_.next_deadline(), sdo_.next_deadline()); }

void Network::report(const can::BusEvent& ev) { emit(ev, wall_()); }

}  // namespace canopen
