// canopen::Device: the slave-side services of CiA 301 on one dictionary.
#include "canopen/device.hpp"

#include <algorithm>
#include <utility>

#include "canopen/cob_id.hpp"
#include "canopen/nmt/nmt.hpp"

namespace canopen {

namespace {

using nmt::Service;

bool is_pdo_parameter(std::uint16_t index) { return index >= 0x1400 && index <= 0x1BFF; }
bool is_sync_parameter(std::uint16_t index) { return index == 0x1005 || index == 0x1006 || index == 0x1019; }

// Areas of 7.3.2.2.1: reset communication restores the communication area,
// reset application the manufacturer-specific and standardized profile areas.
constexpr std::uint16_t kCommunicationFirst = 0x1000, kCommunicationLast = 0x1FFF;
constexpr std::uint16_t kApplicationFirst = 0x2000, kApplicationLast = 0x9FFF;

// Parameters are what a client may write; 1003h sub 0 (clears the history)
// and 1010h/1011h (store/restore signatures) are commands, not settings;
// 1F50h-1F5Fh (CiA 302-3 program download) are the program and its
// control, which a reset does not undo.
bool is_parameter(std::uint16_t index, const od::SubEntry& e) {
  if (index == 0x1003 || index == 0x1010 || index == 0x1011 || (index >= 0x1F50 && index <= 0x1F5F)) return false;
  return od::writable(e.access);
}

// The index range of a 1010h/1011h sub-index (parameter group).
std::optional<std::pair<std::uint16_t, std::uint16_t>> group_range(std::uint8_t group) {
  switch (group) {
    case 1: return std::pair{kCommunicationFirst, kApplicationLast};
    case 2: return std::pair{kCommunicationFirst, kCommunicationLast};
    case 3: return std::pair{kApplicationFirst, kApplicationLast};
    // Sub 4..7Fh are manufacturer-specific groups (7.5.2.13); 4 is the
    // manufacturer-specific profile area here.
    case 4: return std::pair<std::uint16_t, std::uint16_t>{0x2000, 0x5FFF};
    default: return std::nullopt;
  }
}

sdo::ServerConfig server_config(const DeviceConfig& c) {
  sdo::ServerConfig s = c.sdo;
  s.node_id = c.node_id;
  return s;
}

}  // namespace

Device::Device(od::ObjectDictionary& dictionary, DeviceConfig config, FrameSink sink, DeviceCallbacks callbacks)
    : od_(dictionary),
      cfg_(std::move(config)),
      sink_(std::move(sink)),
      cb_(std::move(callbacks)),
      token_(std::make_shared<Token>(Token{this})),
      slave_(od_, cfg_.node_id, [this](const can::Frame& f) { sink_(f); },
             nmt::SlaveCallbacks{
                 [this] {
                   restore_power_on(kApplicationFirst, kApplicationLast);
                   if (cb_.on_reset_application) cb_.on_reset_application();
                 },
                 [this] {
                   sdo_.abort(make_error_code(SdoAbort::GeneralError));
                   // The slave re-reads 1017h/100Ch/100Dh after this.
                   restore_power_on(kCommunicationFirst, kCommunicationLast);
                   if (cb_.on_reset_communication) cb_.on_reset_communication();
                   // Communication parameters may have been restored: rebuild.
                   pdo_dirty_ = true;
                   sync_dirty_ = true;
                   sync_producer_.reset_counter();
                 },
                 [this](NmtState n, NmtState b) { on_state(n, b); },
                 [this](nmt::LifeGuardingEvent e) {
                   if (cb_.on_life_guarding) cb_.on_life_guarding(e);
                 }}),
      sdo_(od_, server_config(cfg_), [this](const can::Frame& f) { send_if(Service::Sdo, f); }),
      emcy_(od_, [this](const can::Frame& f) { send_if(Service::Emcy, f); }),
      sync_(od_, [this](const SyncEvent& ev) { on_sync_received(ev); }),
      sync_producer_(
          od_,
          [this](const can::Frame& f) {
            if (!slave_.service_active(Service::Sync)) return;
            sink_(f);
            // Our own SYNC does not come back from the bus: consume it here too.
            (void)sync_.on_frame(f, now_);
          },
          TimePoint{}),
      time_consumer_(od_,
                     [this](const TimeEvent& ev) {
                       if (cb_.on_time_of_day) cb_.on_time_of_day(ev);
                     }),
      tpdo_([this](const can::Frame& f) { send_tpdo(f); }) {
  changed_.reserve(16);
  install_observers();
}

Device::~Device() { token_->device = nullptr; }

void Device::install_observers() {
  // One observer per index, installed once: the dictionary has no way to
  // remove observers, so they reach the Device through a token it disarms.
  for (const auto& [index, obj] : od_.objects()) {
    const std::uint16_t i = index;
    od_.observe(i, [tok = token_, i](std::uint8_t sub) {
      if (tok->device != nullptr) tok->device->observed(i, sub);
    });
  }
}

// Reports the next deadline when the outermost public call returns (the
// nested ones, e.g. set() from a callback, leave it to the outer one).
struct Device::Outermost {
  explicit Outermost(Device& d) : device(d) { ++device.depth_; }
  ~Outermost() {
    if (--device.depth_ == 0 && device.deadline_observed()) device.report_deadline(device.next_deadline());
  }
  Outermost(const Outermost&) = delete;
  Outermost& operator=(const Outermost&) = delete;
  Device& device;
};

void Device::observed(std::uint16_t index, std::uint8_t sub) {
  // The application wrote the dictionary directly (not through a Device
  // method): what it changed is run at the next on_time(), at once.
  if (depth_ == 0 && !in_call_) {
    const Outermost call(*this);
    observed_in_call(index, sub);
    return;
  }
  observed_in_call(index, sub);
}

void Device::observed_in_call(std::uint16_t index, std::uint8_t sub) {
  if (is_pdo_parameter(index)) {
    pdo_dirty_ = true;
    return;
  }
  if (is_sync_parameter(index)) sync_dirty_ = true;
  for (const auto& t : tpdos_) {
    for (const auto& m : t.mapped) {
      if (m.first == index && m.second == sub) {
        changed_.emplace_back(index, sub);
        return;
      }
    }
  }
}

void Device::start(TimePoint now) {
  const Outermost call(*this);
  now_ = now;
  in_call_ = true;
  if (!started_) {
    // Power-on: what the application put in the dictionary before start()
    // is the configuration a reset returns to.
    defaults_ = parameters(kCommunicationFirst, kApplicationLast);
    power_on_ = defaults_;
    started_ = true;
  }
  sync_producer_.reconfigure(now);
  // Periodic TIME starts its grid at power-on (the standard sets no rate).
  time_producer_.emplace(od_, [this](const can::Frame& f) { send_if(Service::Time, f); },
                         cfg_.unix_ms ? cfg_.time_period : Duration::zero(), now);
  rebuild_pdos(now);
  slave_.start(now);
  in_call_ = false;
  settle(now);
}

bool Device::on_frame(const can::Frame& frame, TimePoint now) {
  const Outermost call(*this);
  now_ = now;
  in_call_ = true;
  bool mine = false;
  if (auto cmd = nmt::parse_command_frame(frame);
      cmd && (cmd->node == nmt::kAllNodes || cmd->node == cfg_.node_id) && cb_.on_nmt_command) {
    cb_.on_nmt_command(cmd->command);
  }
  if (slave_.on_frame(frame, now)) {
    mine = true;
  } else if (slave_.service_active(Service::Sync) && sync_.on_frame(frame, now)) {
    mine = true;
  } else if (slave_.service_active(Service::Time) && time_consumer_.on_frame(frame, now)) {
    mine = true;
  } else if (slave_.service_active(Service::Sdo) && sdo_.on_frame(frame, now)) {
    mine = true;
  } else if (!frame.remote()) {
    const std::uint32_t id = frame.id;
    const bool ext = frame.extended();
    for (auto& r : rpdos_) {
      if (r.cfg.comm.cob_id.can_id() == id && r.cfg.comm.cob_id.extended() == ext) {
        handle_rpdo(r, frame, now);
        mine = true;
        break;
      }
    }
  } else {
    mine = tpdo_.on_frame(frame, now);  // RTR for one of our TPDOs
  }
  in_call_ = false;
  settle(now);
  return mine;
}

void Device::on_time(TimePoint now) {
  now_ = now;
  in_call_ = true;
  if (slave_.next_deadline() <= now) slave_.on_time(now);
  if (sdo_.next_deadline() <= now) sdo_.on_time(now);
  if (emcy_.next_deadline() <= now) emcy_.on_time(now);
  if (sync_producer_.next_deadline() <= now) sync_producer_.on_time(now);
  if (time_producer_ && cfg_.unix_ms && time_producer_->next_deadline() <= now)
    time_producer_->on_time(now, cfg_.unix_ms());
  if (tpdo_.next_deadline() <= now) tpdo_.on_time(now);
  bool timeouts = false;
  for (auto& r : rpdos_) {
    if (r.deadline <= now) {
      r.deadline = TimePoint::max();
      r.timed_out = true;
      timeouts = true;
      if (cb_.on_rpdo_timeout) cb_.on_rpdo_timeout(r.cfg.number);
    }
  }
  if (timeouts) update_timeout_emcy(now);
  in_call_ = false;
  settle(now);
}

TimePoint Device::next_deadline() const {
  if (pdo_dirty_ || sync_dirty_ || !changed_.empty()) return TimePoint::min();
  TimePoint t = std::min({slave_.next_deadline(), sdo_.next_deadline(), emcy_.next_deadline(),
                          sync_producer_.next_deadline(), tpdo_.next_deadline()});
  if (time_producer_ && cfg_.unix_ms) t = std::min(t, time_producer_->next_deadline());
  for (const auto& r : rpdos_) t = std::min(t, r.deadline);
  return t;
}

std::error_code Device::set(std::uint16_t index, std::uint8_t sub, Value value, TimePoint now) {
  const Outermost call(*this);
  now_ = now;
  auto ec = od_.set(index, sub, std::move(value));
  settle(now);
  return ec;
}

void Device::command(NmtCommand cs, TimePoint now) {
  const Outermost call(*this);
  now_ = now;
  in_call_ = true;
  slave_.command(cs, now);
  in_call_ = false;
  settle(now);
}

bool Device::raise_emcy(std::uint16_t code, std::uint8_t register_bits, TimePoint now,
                        const emcy::ManufacturerField& manufacturer) {
  const Outermost call(*this);
  now_ = now;
  const bool r = emcy_.raise(code, register_bits, now, manufacturer);
  settle(now);
  return r;
}

bool Device::clear_emcy(std::uint16_t code, TimePoint now) {
  const Outermost call(*this);
  now_ = now;
  const bool r = emcy_.clear(code, now);
  settle(now);
  return r;
}

bool Device::send_time(std::int64_t unix_ms) {
  if (!time_producer_ || !slave_.service_active(Service::Time)) return false;
  return time_producer_->send(unix_ms);
}

void Device::reconfigure_pdos(TimePoint now) {
  const Outermost call(*this);
  now_ = now;
  rebuild_pdos(now);
  settle(now);
}

Device::Parameters Device::parameters(std::uint16_t first, std::uint16_t last) const {
  Parameters out;
  const auto& objects = od_.objects();
  for (auto it = objects.lower_bound(first); it != objects.end() && it->first <= last; ++it) {
    for (const auto& [sub, entry] : it->second.subs) {
      if (is_parameter(it->first, entry)) out.emplace(std::pair{it->first, sub}, entry.value);
    }
  }
  return out;
}

void Device::restore_power_on(std::uint16_t first, std::uint16_t last) {
  // ObjectDictionary::set: no write hooks (a valid PDO's COB-ID may change
  // here), observers run (PDO/SYNC rebuild, the application's own).
  for (auto it = power_on_.lower_bound({first, 0}); it != power_on_.end() && it->first.first <= last; ++it) {
    const auto [index, sub] = it->first;
    const od::SubEntry* entry = od_.find(index, sub);
    if (entry != nullptr && entry->value != it->second) (void)od_.set(index, sub, it->second);
  }
}

std::error_code Device::store_parameters(std::uint8_t group) {
  const auto range = group_range(group);
  if (!range) return make_error_code(SdoAbort::NoSuchSubIndex);
  if (!started_) return make_error_code(SdoAbort::CannotStoreDeviceState);
  std::erase_if(power_on_, [&](const auto& kv) { return kv.first.first >= range->first && kv.first.first <= range->second; });
  power_on_.merge(parameters(range->first, range->second));
  return {};
}

std::error_code Device::restore_default_parameters(std::uint8_t group) {
  const auto range = group_range(group);
  if (!range) return make_error_code(SdoAbort::NoSuchSubIndex);
  if (!started_) return make_error_code(SdoAbort::CannotStoreDeviceState);
  auto in_range = [&](const auto& kv) { return kv.first.first >= range->first && kv.first.first <= range->second; };
  std::erase_if(power_on_, in_range);
  for (const auto& kv : defaults_) {
    if (in_range(kv)) power_on_.insert(kv);
  }
  return {};
}

std::vector<std::uint16_t> Device::tpdo_numbers() const {
  std::vector<std::uint16_t> out;
  for (const auto& t : tpdos_) out.push_back(t.number);
  return out;
}

std::vector<std::uint16_t> Device::rpdo_numbers() const {
  std::vector<std::uint16_t> out;
  for (const auto& r : rpdos_) out.push_back(r.cfg.number);
  return out;
}

// Runs what observers recorded during the last call: PDO rebuilds, SYNC
// reconfiguration and TPDO events of changed mapped objects.
void Device::settle(TimePoint now) {
  if (in_call_) return;
  if (pdo_dirty_) rebuild_pdos(now);
  if (sync_dirty_) {
    sync_dirty_ = false;
    sync_producer_.reconfigure(now);
  }
  // set_value() may send, and a send never writes the dictionary, so
  // changed_ does not grow while it is walked; index loop anyway.
  for (std::size_t k = 0; k < changed_.size(); ++k) {
    const auto [index, sub] = changed_[k];
    auto v = od_.get(index, sub);
    if (!v) continue;
    for (const auto& t : tpdos_) {
      for (const auto& m : t.mapped) {
        if (m.first == index && m.second == sub) {
          (void)tpdo_.set_value(cfg_.node_id, t.number, index, sub, *v, now);
          break;
        }
      }
    }
  }
  changed_.clear();
}

void Device::rebuild_pdos(TimePoint now) {
  pdo_dirty_ = false;
  changed_.clear();  // payloads are re-read from the dictionary below
  pdo_errors_.clear();
  for (const auto& t : tpdos_) tpdo_.remove(cfg_.node_id, t.number);
  tpdos_.clear();
  rpdos_.clear();

  for (auto& cfg : pdo::read_all(od_, pdo::Direction::Transmit, &pdo_errors_)) {
    if (!cfg.comm.cob_id.valid()) continue;
    if (cfg.kind != pdo::MappingKind::Normal) {
      pdo_errors_.push_back("TPDO" + std::to_string(cfg.number) + ": MPDO not produced by this device");
      continue;
    }
    auto r = tpdo_.add_from(cfg_.node_id, pdo::Direction::Transmit, cfg.number, od_, now);
    if (!r) {
      pdo_errors_.push_back("TPDO" + std::to_string(cfg.number) + ": " + r.error().detail);
      continue;
    }
    Tpdo t;
    t.number = cfg.number;
    t.can_id = cfg.comm.cob_id.can_id();
    t.extended = cfg.comm.cob_id.extended();
    t.synchronous = cfg.comm.synchronous();
    for (const auto& e : cfg.entries)
      if (!e.dummy) t.mapped.emplace_back(e.index, e.sub);
    tpdos_.push_back(std::move(t));
  }

  for (auto& cfg : pdo::read_all(od_, pdo::Direction::Receive, &pdo_errors_)) {
    if (!cfg.comm.cob_id.valid()) continue;
    if (cfg.kind != pdo::MappingKind::Normal) {
      pdo_errors_.push_back("RPDO" + std::to_string(cfg.number) + ": MPDO not consumed by this device");
      continue;
    }
    Rpdo r;
    std::size_t offset = 0;
    for (const auto& e : cfg.entries) {
      r.offsets.push_back(offset);
      offset += e.bits;
      if (!e.dummy) r.values.push_back(MappedValue{e.index, e.sub, e.name, Value::zero(e.type)});
    }
    if (cfg.comm.event_timer != 0) r.deadline_period = std::chrono::milliseconds(cfg.comm.event_timer);
    r.cfg = std::move(cfg);
    rpdos_.push_back(std::move(r));
  }
  update_length_emcy(now);
  update_timeout_emcy(now);
}

void Device::handle_rpdo(Rpdo& r, const can::Frame& f, TimePoint now) {
  if (!slave_.service_active(Service::Pdo)) return;  // 7.3.2.2.5: PDOs only in operational
  const std::size_t need = r.cfg.byte_length();
  if (r.deadline_period > Duration::zero()) r.deadline = now + r.deadline_period;
  if (r.timed_out) {
    r.timed_out = false;
    update_timeout_emcy(now);
  }
  const bool short_frame = f.len < need;
  const bool long_frame = f.len > need;
  if (short_frame != r.length_error || long_frame) {
    r.length_error = short_frame;
    update_length_emcy(now);
  }
  if (long_frame) (void)emcy_.raise(kEmcyPdoLengthExceeded, emcy::error_register::kCommunication, now);
  else if (!short_frame && emcy_.is_present(kEmcyPdoLengthExceeded)) (void)emcy_.clear(kEmcyPdoLengthExceeded, now);
  if (short_frame) return;  // 7.5.2.36: not processed

  const auto data = std::span<const std::uint8_t>(f.data.data(), need);
  if (r.cfg.comm.synchronous()) {
    // Actuated at the next SYNC, if it came inside the synchronous window.
    if (!sync_.in_sync_window(now)) return;
    std::copy(data.begin(), data.end(), r.pending.begin());
    r.has_pending = true;
    return;
  }
  apply_rpdo(r, data);
}

void Device::apply_rpdo(Rpdo& r, std::span<const std::uint8_t> data) {
  std::size_t slot = 0;
  for (std::size_t k = 0; k < r.cfg.entries.size(); ++k) {
    const auto& e = r.cfg.entries[k];
    if (e.dummy) continue;
    auto v = pdo::unpack_value(e.type, data, r.offsets[k], e.bits);
    if (v) {
      r.values[slot].value = std::move(*v);
      (void)od_.set(e.index, e.sub, r.values[slot].value);
    }
    ++slot;
  }
  if (cb_.on_rpdo) cb_.on_rpdo(r.cfg.number, r.values);
}

void Device::update_length_emcy(TimePoint now) {
  const bool any = std::any_of(rpdos_.begin(), rpdos_.end(), [](const Rpdo& r) { return r.length_error; });
  if (any) (void)emcy_.raise(kEmcyPdoLength, emcy::error_register::kCommunication, now);
  else if (emcy_.is_present(kEmcyPdoLength)) (void)emcy_.clear(kEmcyPdoLength, now);
}

void Device::update_timeout_emcy(TimePoint now) {
  const bool any = std::any_of(rpdos_.begin(), rpdos_.end(), [](const Rpdo& r) { return r.timed_out; });
  if (any) (void)emcy_.raise(kEmcyRpdoTimeout, emcy::error_register::kCommunication, now);
  else if (emcy_.is_present(kEmcyRpdoTimeout)) (void)emcy_.clear(kEmcyRpdoTimeout, now);
}

void Device::on_sync_received(const SyncEvent& ev) {
  if (slave_.service_active(Service::Pdo)) {
    for (auto& r : rpdos_) {
      if (r.has_pending) {
        r.has_pending = false;
        apply_rpdo(r, std::span<const std::uint8_t>(r.pending.data(), r.cfg.byte_length()));
      }
    }
    // Writes by the RPDOs above are sampled by this SYNC's TPDOs.
    const bool was = in_call_;
    in_call_ = false;
    settle(now_);
    in_call_ = was;
    tpdo_.on_sync(ev.counter, now_);
  }
  if (cb_.on_sync) cb_.on_sync(ev);
}

void Device::on_state(NmtState now_state, NmtState before) {
  if (now_state != NmtState::Operational) {
    // Leaving operational: no deadline monitoring, no data waiting for SYNC.
    for (auto& r : rpdos_) {
      r.deadline = TimePoint::max();
      r.has_pending = false;
    }
  }
  if (cb_.on_state_change) cb_.on_state_change(now_state, before);
}

void Device::send_tpdo(const can::Frame& f) {
  if (!slave_.service_active(Service::Pdo)) return;
  for (const auto& t : tpdos_) {
    if (t.can_id == f.id && t.extended == f.extended()) {
      // Synchronous PDOs only inside the synchronous window (7.2.2.2, 1007h).
      if (t.synchronous && !sync_.in_sync_window(now_)) return;
      break;
    }
  }
  sink_(f);
}

void Device::send_if(nmt::Service s, const can::Frame& f) {
  if (slave_.service_active(s)) sink_(f);
}

}  // namespace canopen
