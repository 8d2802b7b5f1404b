#include "canopen/network.hpp"

#include <algorithm>

#include "canopen/sdo/abort.hpp"

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
             const auto* s = std::get_if<NodeStateEvent>(&body);
             if (s == nullptr || !boot_) return;
             if (s->cause == NodeStateEvent::Cause::BootUp) {
               // What a rebooted node answers belongs to its new life.
               pdo_reader_.cancel(s->node, now_);
               boot_checks_only_.erase(s->node);
               boot_->on_boot_up(s->node, now_);
             } else if (found_without_boot_up(*s) && !pdo_reader_.busy(s->node) &&
                        boot_->on_found(s->node, *s->state, now_)) {
               if (*s->state == NmtState::Operational) {
                 boot_checks_only_.insert(s->node);
               } else {
                 boot_checks_only_.erase(s->node);
               }
             }
           }),
      sdo_(sdo_config, sink),
      pdo_(sink, [this](PdoEvent ev) { emit(std::move(ev), frame_time_); }),
      rpdo_(sink),
      lss_(lss::MasterConfig{}, sink),
      emcy_(emcy::EmcyConsumerConfig::from_dictionary(own), [this](const EmcyEvent& ev) { emit(ev, frame_time_); }),
      sync_(own,
            [this](const SyncEvent& ev) {
              emit(ev, frame_time_);
              rpdo_.on_sync(ev.counter, now_);  // synchronous RPDO data goes out on this SYNC
            }),
      time_(own, [this](const TimeEvent& ev) { emit(ev, frame_time_); }),
      pdo_reader_(sdo_, [this] { return now_; }),
      dcf_reader_(sdo_, [this](const TransferEvent& ev) { emit(ev, wall_()); }, [this] { return now_; }),
      dcf_applier_(
          sdo_, [this](NmtCommand cmd, std::uint8_t n) { nmt_.send_command(cmd, n); },
          [this](const TransferEvent& ev) { emit(ev, wall_()); }, [this] { return now_; }),
      program_(sdo_, [this](const TransferEvent& ev) { emit(ev, wall_()); }, [this] { return now_; }) {
  pdo_.set_sync_window([this](TimePoint now) { return sync_.in_sync_window(now); });
  sdo_.set_download_observer([this](std::uint8_t node, const sdo::Multiplexer& mux, const Bytes& data) {
    if (auto key = pdo_table_.apply_download(node, mux.index, mux.sub, data)) refresh_pdo(node, *key);
    // 1017h written by this network (REST, MQTT, DCF apply, boot-up
    // configuration): the watch expects the new period at once.
    if (mux.index == 0x1017 && mux.sub == 0 && data.size() >= 2)
      nmt_.set_producer_time(node, std::chrono::milliseconds(data[0] | data[1] << 8), now_);
  });
  // Calls from outside through nmt(), sdo() and rpdo() move their
  // deadlines: the network's driver hears of it from here.
  const auto forward = [this](TimePoint next) { report_deadline(next); };
  nmt_.on_deadline_change(forward);
  sdo_.on_deadline_change(forward);
  rpdo_.on_deadline_change(forward);
  lss_.on_deadline_change(forward);
  configure_heartbeat_consumers();
}

std::vector<std::string> Network::add_node(std::uint8_t node, const od::ObjectDictionary& description) {
  // RPDOs of an earlier description that this one lacks must not go on being produced.
  for (std::uint16_t number = 1; number <= pdo::kMaxPdoNumber; ++number) rpdo_.remove(node, number);
  (void)pdo_table_.add_node(node, description);  // its problems are the decoder's below
  auto problems = pdo_.add_node(node, description);
  for (const auto& cfg : pdo::read_all(description, pdo::Direction::Receive, &problems)) {
    if (!cfg.comm.cob_id.valid() || cfg.kind != pdo::MappingKind::Normal) continue;
    if (auto r = rpdo_.add_rpdo(node, cfg.number, description, now_); !r)
      problems.push_back("RPDO" + std::to_string(cfg.number) + ": " + r.error().code.message() + " " + r.error().detail);
  }
  return problems;
}

void Network::remove_node(std::uint8_t node) {
  pdo_reader_.cancel(node, now_);
  for (std::uint16_t number = 1; number <= pdo::kMaxPdoNumber; ++number) rpdo_.remove(node, number);
  pdo_.remove_node(node);
  pdo_table_.remove_node(node);
  if (boot_) boot_->remove(node);
  boot_reads_.erase(node);
  boot_checks_only_.erase(node);
}

bool Network::configure_boot(std::uint8_t node, master::NodeBootConfig config, bool read_pdo_config) {
  if (!boot_) {
    boot_ = std::make_unique<master::BootConfigurator>(
        sdo_, [this](NmtCommand cmd, std::uint8_t n) { nmt_.send_command(cmd, n); },
        [this](const BootConfigEvent& ev) { on_boot_event(ev); }, [this] { return now_; });
  }
  if (node < 1 || node > 127) return false;
  if (read_pdo_config) {
    // The configurator stops before the start; the read finishes the boot.
    boot_reads_[node] = config.start;
    config.start = false;
  } else {
    boot_reads_.erase(node);
  }
  return boot_->configure(node, std::move(config));
}

bool Network::found_without_boot_up(const NodeStateEvent& s) {
  using Cause = NodeStateEvent::Cause;
  if (!s.state) return false;
  // First heard, and not by its boot-up: it was powered before the gateway listened.
  if ((s.cause == Cause::Heartbeat || s.cause == Cause::NodeGuarding) && !s.previous) return true;
  // Back after a loss in another state: it was reset (or power-cycled) while
  // its boot-up went unheard.
  return s.cause == Cause::Recovered && s.previous != s.state;
}

void Network::on_boot_event(const BootConfigEvent& ev) {
  const bool check_only = boot_checks_only_.count(ev.node) != 0;
  if (check_only && (ev.step == BootConfigEvent::Step::Done || ev.step == BootConfigEvent::Step::Failed))
    boot_checks_only_.erase(ev.node);
  const auto it = boot_reads_.find(ev.node);
  if (it == boot_reads_.end() || ev.step != BootConfigEvent::Step::Done) {
    emit(ev, wall_());
    return;
  }
  const std::uint8_t node = ev.node;
  // An operational node found without a boot-up is read, not restarted.
  const bool start = it->second && !check_only;
  // What the configurator would have done at its end, after the read.
  auto conclude = [this, node, start, found_detail = ev.detail](std::error_code failed, const std::string& detail) {
    BootConfigEvent e;
    e.node = node;
    if (failed) {
      e.step = BootConfigEvent::Step::Failed;
      e.error = failed;
      e.detail = "reading the PDO configuration: " + detail;
      emit(e, wall_());
      return;
    }
    if (start) {
      nmt_.send_command(NmtCommand::Start, node);
      e.step = BootConfigEvent::Step::Start;
      emit(e, wall_());
    }
    e.step = BootConfigEvent::Step::Done;
    e.detail = found_detail.empty() ? detail : found_detail + "; " + detail;
    emit(e, wall_());
  };
  if (pdo_table_.description(node) == nullptr) {
    conclude({}, "no EDS/DCF: PDO configuration not read");
    return;
  }
  auto ec = read_pdo_config(
      node,
      [conclude](const pdo::PdoReadReport& r) {
        if (r.cancelled) return;  // the node booted again: that boot-up's sequence runs
        conclude(r.stopped, r.summary());
      },
      now_);
  if (ec) conclude(ec, ec.message());
}

std::error_code Network::read_pdo_config(std::uint8_t node, pdo::PdoConfigReader::Done done, TimePoint now) {
  const od::ObjectDictionary* description = pdo_table_.description(node);
  if (description == nullptr) return make_error_code(SdoAbort::NoSuchObject);
  std::vector<pdo::PdoReadPlan> plan;
  for (const pdo::RemotePdo* p : pdo_table_.pdos(node)) {
    pdo::PdoReadPlan step{p->key, {}};
    for (const std::uint8_t sub : {std::uint8_t{3}, std::uint8_t{5}, std::uint8_t{6}})
      if (description->find(pdo::comm_index(p->key.direction, p->key.number), sub) != nullptr)
        step.optional_comm_subs.push_back(sub);
    plan.push_back(std::move(step));
  }
  return pdo_reader_.read(
      node, std::move(plan),
      [this, node, done = std::move(done)](const pdo::PdoReadReport& r) {
        if (!r.cancelled) {
          for (const auto& o : r.pdos) {
            if (o.parameters) {
              if (pdo_table_.apply_read(node, o.key, *o.parameters)) refresh_pdo(node, o.key);
            } else {
              pdo_table_.set_read_error(node, o.key, o.detail);
            }
          }
        }
        if (done) done(r);
      },
      now);
}

std::error_code Network::check_transfer(std::uint8_t node) const {
  if (node < 1 || node > 127) return make_error_code(master::TransferError::BadNode);
  if (transfer_busy(node)) return make_error_code(master::TransferError::Busy);
  return {};
}

bool Network::transfer_busy(std::uint8_t node) const {
  return dcf_reader_.busy(node) || dcf_applier_.busy(node) || program_.busy(node);
}

std::error_code Network::read_dcf(std::uint8_t node, const eds::DeviceDescription& description,
                                  master::DcfReader::Done done, TimePoint now) {
  if (auto ec = check_transfer(node)) return ec;
  return dcf_reader_.start(node, description, std::move(done), now);
}

std::error_code Network::apply_dcf(std::uint8_t node, const eds::DeviceDescription& dcf,
                                   master::DcfApplyOptions options, master::DcfApplier::Done done, TimePoint now) {
  if (auto ec = check_transfer(node)) return ec;
  return dcf_applier_.start(node, dcf, options, std::move(done), now);
}

std::error_code Network::download_program(std::uint8_t node, master::ProgramDownloadOptions options, Bytes image,
                                          master::ProgramDownloader::Done done, TimePoint now) {
  if (auto ec = check_transfer(node)) return ec;
  return program_.start(node, options, std::move(image), std::move(done), now);
}

bool Network::cancel_transfer(std::uint8_t node, TimePoint now) {
  return dcf_reader_.cancel(node, now) || dcf_applier_.cancel(node, now) || program_.cancel(node, now);
}

void Network::refresh_pdo(std::uint8_t node, pdo::PdoKey key) {
  auto cfg = pdo_table_.resolve(node, key);
  const pdo::RemotePdo* raw = pdo_table_.find(node, key);
  if (raw == nullptr) return;
  if (key.direction == pdo::Direction::Transmit) {
    if (cfg) {
      (void)pdo_.set_tpdo(node, std::move(*cfg));
    } else {
      pdo::PdoConfig off;  // COB-ID and transmission type only: frames are reported, not decoded
      off.direction = key.direction;
      off.number = key.number;
      off.comm = raw->parameters.comm;
      (void)pdo_.set_tpdo(node, std::move(off), cfg.error().detail);
    }
    return;
  }
  // An RPDO that is disabled, an MPDO or not resolvable is not produced.
  if (!cfg || !cfg->comm.cob_id.valid() || cfg->kind != pdo::MappingKind::Normal) {
    rpdo_.remove(node, key.number);
    return;
  }
  (void)rpdo_.reconfigure(node, std::move(*cfg), now_, pdo_table_.description(node));
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
  used = lss_.on_frame(frame, now) || used;   // LSS slaves' answers (7E4h)
  return used;
}

void Network::on_time(TimePoint now) {
  now_ = now;
  if (nmt_.next_deadline() <= now) nmt_.on_time(now);
  if (sdo_.next_deadline() <= now) sdo_.on_time(now);
  if (rpdo_.next_deadline() <= now) rpdo_.on_time(now);
  if (lss_.next_deadline() <= now) lss_.on_time(now);
}

TimePoint Network::next_deadline() const {
  return std::min({nmt_.next_deadline(), sdo_.next_deadline(), rpdo_.next_deadline(), lss_.next_deadline()});
}

void Network::report(const can::BusEvent& ev) { emit(ev, wall_()); }

}  // namespace canopen
