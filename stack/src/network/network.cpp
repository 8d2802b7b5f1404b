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
             // The boot-up is reported before its configuration starts.
             if (const auto* s = std::get_if<NodeStateEvent>(&body);
                 s != nullptr && boot_ && s->cause == NodeStateEvent::Cause::BootUp)
               boot_->on_boot_up(s->node, now_);
           }),
      sdo_(sdo_config, sink),
      pdo_(sink, [this](PdoEvent ev) { emit(std::move(ev), frame_time_); }),
      rpdo_(sink),
      emcy_(emcy::EmcyConsumerConfig::from_dictionary(own), [this](const EmcyEvent& ev) { emit(ev, frame_time_); }),
      sync_(own,
            [this](const SyncEvent& ev) {
              emit(ev, frame_time_);
              rpdo_.on_sync(ev.counter, now_);  // synchronous RPDO data goes out on this SYNC
            }),
      time_(own, [this](const TimeEvent& ev) { emit(ev, frame_time_); }) {
  pdo_.set_sync_window([this](TimePoint now) { return sync_.in_sync_window(now); });
  configure_heartbeat_consumers();
}

std::vector<std::string> Network::add_node(std::uint8_t node, const od::ObjectDictionary& description) {
  auto problems = pdo_.add_node(node, description);
  for (const auto& cfg : pdo::read_all(description, pdo::Direction::Receive, &problems)) {
    if (!cfg.comm.cob_id.valid() || cfg.kind != pdo::MappingKind::Normal) continue;
    if (auto r = rpdo_.add_rpdo(node, cfg.number, description, now_); !r)
      problems.push_back("RPDO" + std::to_string(cfg.number) + ": " + r.error().code.message() + " " + r.error().detail);
  }
  return problems;
}

bool Network::configure_boot(std::uint8_t node, nmt::NodeBootConfig config) {
  if (!boot_) {
    boot_ = std::make_unique<nmt::BootConfigurator>(
        sdo_, [this](NmtCommand cmd, std::uint8_t n) { nmt_.send_command(cmd, n); },
        [this](const BootConfigEvent& ev) { emit(ev, wall_()); }, [this] { return now_; });
  }
  return boot_->configure(node, std::move(config));
}

void Network::configure_heartbeat_consumers() { nmt_.configure_consumers(own_); }

void Network::emit(EventBody body, can::Frame::Clock::time_point timestamp) {
  if (on_event_) on_event_(Event{++seq_, timestamp, std::move(body)});
}

bool Network::on_frame(const can::Frame& frame, TimePoint now) {
  now_ = now;
  frame_time_ = frame.timestamp == can::Frame::Clock::time_point{} ? wall_() : frame.timestamp;
  // Every service sees the frame; each ignores what is not its own. SDO
  // responses first: they are the ones callers wait on.
  bool used = sdo_.on_frame(frame, now);
  used = sync_.on_frame(frame, now) || used;  // SYNC before PDOs: it opens the window
  used = nmt_.on_frame(frame, now) || used;
  used = emcy_.on_frame(frame, now) || used;
  used = time_.on_frame(frame, now) || used;
  used = pdo_.on_frame(frame, now) || used;
  used = rpdo_.on_frame(frame, now) || used;  // RTRs for RPDO data the gateway produces
  return used;
}

void Network::on_time(TimePoint now) {
  now_ = now;
  if (nmt_.next_deadline() <= now) nmt_.on_time(now);
  if (sdo_.next_deadline() <= now) sdo_.on_time(now);
  if (rpdo_.next_deadline() <= now) rpdo_.on_time(now);
}

TimePoint Network::next_deadline() const {
  return std::min({nmt_.next_deadline(), sdo_.next_deadline(), rpdo_.next_deadline()});
}

void Network::report(const can::BusEvent& ev) { emit(ev, wall_()); }

}  // namespace canopen
