#include "canopen/pdo/transmitter.hpp"

#include <algorithm>
#include <chrono>

#include "canopen/sdo/abort.hpp"

namespace canopen::pdo {

Result<std::size_t> PdoTransmitter::add_from(std::uint8_t node, Direction dir, std::uint16_t number,
                                             const od::ObjectDictionary& dict, TimePoint now, std::size_t max_bytes) {
  const Report<PdoTransmitter> deadline_report(*this);  // the driver follows
  auto cfg = read_pdo(dict, dir, number, max_bytes);
  if (!cfg) return cfg.error();
  auto r = add(node, std::move(*cfg), now);
  if (!r) return r;
  Tx& tx = *find(node, number);
  std::size_t offset = 0;
  for (const auto& e : tx.cfg.entries) {
    if (!e.dummy)
      if (auto v = dict.get(e.index, e.sub)) (void)pack_value(*v, tx.payload, offset, e.bits);  // else stays 0
    offset += e.bits;
  }
  tx.sampled = tx.payload;
  return r;
}

Result<std::size_t> PdoTransmitter::add(std::uint8_t node, PdoConfig cfg, TimePoint now) {
  const Report<PdoTransmitter> deadline_report(*this);  // the driver follows
  if (!cfg.comm.cob_id.valid())
    return Error{make_error_code(SdoAbort::NoSuchObject), "PDO is not valid (COB-ID bit 31 set)"};
  if (cfg.kind != MappingKind::Normal)
    return Error{make_error_code(SdoAbort::NoSuchObject), "MPDOs are not produced here"};
  Tx tx;
  tx.payload.assign(cfg.byte_length(), 0);
  tx.sampled = tx.payload;
  if (cfg.comm.event_driven() && cfg.comm.event_timer != 0)
    tx.timer_due = now + std::chrono::milliseconds(cfg.comm.event_timer);
  tx.cfg = std::move(cfg);
  const std::size_t len = tx.payload.size();
  pdos_[Key{node, tx.cfg.number}] = std::move(tx);
  return len;
}

void PdoTransmitter::remove(std::uint8_t node, std::uint16_t number) { pdos_.erase(Key{node, number}); }

Result<std::size_t> PdoTransmitter::reconfigure(std::uint8_t node, PdoConfig cfg, TimePoint now,
                                                const od::ObjectDictionary* initial) {
  const Report<PdoTransmitter> deadline_report(*this);  // the driver follows
  const std::uint16_t number = cfg.number;
  std::optional<Tx> before;
  if (Tx* old = find(node, number)) before = std::move(*old);
  auto r = add(node, std::move(cfg), now);
  if (!r) {
    remove(node, number);
    return r;
  }
  Tx& tx = *find(node, number);
  std::size_t offset = 0;
  for (const auto& e : tx.cfg.entries) {
    if (!e.dummy) {
      std::optional<std::size_t> was;
      if (before) {
        std::size_t at = 0;
        for (const auto& o : before->cfg.entries) {
          if (!o.dummy && o.index == e.index && o.sub == e.sub && o.bits == e.bits) was = at;
          if (was) break;
          at += o.bits;
        }
      }
      if (was) {
        for (unsigned b = 0; b < e.bits; b += 64) {
          const unsigned n = std::min(64U, e.bits - b);
          insert_bits(tx.payload, offset + b, n, extract_bits(before->payload, *was + b, n));
        }
      } else if (initial != nullptr) {
        if (auto v = initial->get(e.index, e.sub)) (void)pack_value(*v, tx.payload, offset, e.bits);
      }
    }
    offset += e.bits;
  }
  tx.sampled = tx.payload;
  return r;
}

const PdoConfig* PdoTransmitter::config(std::uint8_t node, std::uint16_t number) const {
  auto it = pdos_.find(Key{node, number});
  return it == pdos_.end() ? nullptr : &it->second.cfg;
}

PdoTransmitter::Tx* PdoTransmitter::find(std::uint8_t node, std::uint16_t number) {
  auto it = pdos_.find(Key{node, number});
  return it == pdos_.end() ? nullptr : &it->second;
}

const Bytes* PdoTransmitter::payload(std::uint8_t node, std::uint16_t number) const {
  auto it = pdos_.find(Key{node, number});
  return it == pdos_.end() ? nullptr : &it->second.payload;
}

std::error_code PdoTransmitter::set_value(std::uint8_t node, std::uint16_t number, std::uint16_t index,
                                          std::uint8_t sub, const Value& v, TimePoint now) {
  const Report<PdoTransmitter> deadline_report(*this);  // the driver follows
  const MappedValue mv{index, sub, {}, v};
  return set_values(node, number, std::span<const MappedValue>(&mv, 1), now);
}

std::error_code PdoTransmitter::set_values(std::uint8_t node, std::uint16_t number,
                                           std::span<const MappedValue> values, TimePoint now) {
  const Report<PdoTransmitter> deadline_report(*this);  // the driver follows
  Tx* tx = find(node, number);
  if (!tx) return make_error_code(SdoAbort::NoSuchObject);
  Bytes next = tx->payload;  // all or nothing
  for (const auto& mv : values) {
    auto offset = bit_offset_of(tx->cfg, mv.index, mv.sub);
    if (!offset) return make_error_code(SdoAbort::NotMappable);
    const auto e = std::find_if(tx->cfg.entries.begin(), tx->cfg.entries.end(),
                                [&](const MappingEntry& m) { return !m.dummy && m.index == mv.index && m.sub == mv.sub; });
    if (mv.value.type != e->type) return make_error_code(SdoAbort::LengthMismatch);
    if (auto ec = pack_value(mv.value, next, *offset, e->bits)) return ec;
  }
  tx->payload = std::move(next);
  event(*tx, now);
  return {};
}

std::error_code PdoTransmitter::set_raw(std::uint8_t node, std::uint16_t number, std::span<const std::uint8_t> bytes,
                                        TimePoint now) {
  const Report<PdoTransmitter> deadline_report(*this);  // the driver follows
  Tx* tx = find(node, number);
  if (!tx) return make_error_code(SdoAbort::NoSuchObject);
  if (bytes.size() != tx->payload.size()) return make_error_code(SdoAbort::LengthMismatch);
  tx->payload.assign(bytes.begin(), bytes.end());
  event(*tx, now);
  return {};
}

void PdoTransmitter::event(Tx& tx, TimePoint now) {
  const CommParams& c = tx.cfg.comm;
  if (c.transmission_type == 0) {
    tx.changed = true;
  } else if (c.event_driven()) {
    if (tx.inhibit_until && now < *tx.inhibit_until) tx.held = true;  // sent when the inhibit time ends
    else send(tx, tx.payload, now);
  }
  // Cyclic and RTR-only types send the latest payload at their trigger.
}

void PdoTransmitter::send(Tx& tx, const Bytes& data, TimePoint now) {
  const CobId& id = tx.cfg.comm.cob_id;
  can::Frame f = id.extended() ? can::Frame::extended_id(id.can_id(), {}) : can::Frame::standard(id.can_id(), {});
  std::copy(data.begin(), data.end(), f.data.begin());
  std::size_t len = data.size();
  if (len > can::kMaxClassicLength) {
    f.set(can::FrameFlag::Fd);
    len = can::fd_round_up_length(len);  // padding bytes stay zero
  }
  f.len = static_cast<std::uint8_t>(len);
  const CommParams& c = tx.cfg.comm;
  tx.held = false;
  tx.changed = false;
  if (c.event_driven()) {
    tx.inhibit_until = now + std::chrono::microseconds(100 * std::int64_t{c.inhibit_time});
    if (c.event_timer != 0) tx.timer_due = now + std::chrono::milliseconds(c.event_timer);
  }
  sink_(f);
}

void PdoTransmitter::on_sync(std::optional<std::uint8_t> counter, TimePoint now) {
  const Report<PdoTransmitter> deadline_report(*this);  // the driver follows
  for (auto& [key, tx] : pdos_) {
    const CommParams& c = tx.cfg.comm;
    if (c.transmission_type == 0) {
      if (tx.changed) send(tx, tx.payload, now);
    } else if (c.cyclic()) {
      if (c.sync_start != 0 && counter && !tx.started) {
        if (*counter != c.sync_start) continue;  // 7.5.2.36: wait for the start value
        tx.started = true;
        tx.sync_count = 0;
        send(tx, tx.payload, now);
        continue;
      }
      if (++tx.sync_count >= c.transmission_type) {
        tx.sync_count = 0;
        send(tx, tx.payload, now);
      }
    } else if (c.transmission_type == 252) {
      tx.sampled = tx.payload;
    }
  }
}

bool PdoTransmitter::on_frame(const can::Frame& f, TimePoint now) {
  if (!f.remote()) return false;
  for (auto& [key, tx] : pdos_) {
    const CobId& id = tx.cfg.comm.cob_id;
    if (id.can_id() != f.id || id.extended() != f.extended() || !id.rtr_allowed()) continue;
    send(tx, tx.cfg.comm.transmission_type == 252 ? tx.sampled : tx.payload, now);
    return true;
  }
  return false;
}

TimePoint PdoTransmitter::next_deadline() const {
  TimePoint t = TimePoint::max();
  for (const auto& [key, tx] : pdos_) {
    if (tx.held && tx.inhibit_until) t = std::min(t, *tx.inhibit_until);
    if (tx.timer_due) t = std::min(t, *tx.timer_due);
  }
  return t;
}

void PdoTransmitter::on_time(TimePoint now) {
  for (auto& [key, tx] : pdos_) {
    const bool inhibited = tx.inhibit_until && now < *tx.inhibit_until;
    if (tx.held && !inhibited) {
      send(tx, tx.payload, now);
    } else if (tx.timer_due && now >= *tx.timer_due) {
      if (inhibited) {
        tx.held = true;
        tx.timer_due.reset();  // re-armed by the send at the end of the inhibit time
      } else {
        send(tx, tx.payload, now);
      }
    }
  }
}

}  // namespace canopen::pdo
