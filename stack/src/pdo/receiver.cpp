#include "canopen/pdo/receiver.hpp"

#include <algorithm>
#include <string>
#include <utility>

namespace canopen::pdo {

ScannerEntry ScannerEntry::from_raw(std::uint32_t raw) {
  ScannerEntry e;
  e.sub = static_cast<std::uint8_t>(raw);
  e.index = static_cast<std::uint16_t>(raw >> 8);
  e.block = static_cast<std::uint8_t>(raw >> 24);
  return e;
}

bool ScannerEntry::covers(std::uint16_t i, std::uint8_t s) const {
  const unsigned n = block == 0 ? 1U : block;  // block 0 read as a single sub-index
  return i == index && s >= sub && unsigned{s} < unsigned{sub} + n;
}

DispatcherEntry DispatcherEntry::from_raw(std::uint64_t raw) {
  DispatcherEntry e;
  e.local_sub = static_cast<std::uint8_t>(raw);
  e.local_index = static_cast<std::uint16_t>(raw >> 8);
  e.producer_sub = static_cast<std::uint8_t>(raw >> 24);
  e.producer_index = static_cast<std::uint16_t>(raw >> 32);
  e.producer = static_cast<std::uint8_t>(raw >> 48);
  e.block = static_cast<std::uint8_t>(raw >> 56);
  return e;
}

std::vector<ScannerEntry> read_scanner_list(const od::ObjectDictionary& od) {
  std::vector<ScannerEntry> out;
  for (unsigned idx = 0x1FA0; idx <= 0x1FCF; ++idx) {
    const auto index = static_cast<std::uint16_t>(idx);
    auto count = od.get_unsigned(index, 0);
    if (!count) continue;
    for (unsigned s = 1; s <= *count && s <= 0xFE; ++s) {
      auto raw = od.get_unsigned(index, static_cast<std::uint8_t>(s));
      if (raw && *raw != 0) out.push_back(ScannerEntry::from_raw(static_cast<std::uint32_t>(*raw)));
    }
  }
  return out;
}

std::vector<DispatcherEntry> read_dispatcher_list(const od::ObjectDictionary& od) {
  std::vector<DispatcherEntry> out;
  for (unsigned idx = 0x1FD0; idx <= 0x1FFF; ++idx) {
    const auto index = static_cast<std::uint16_t>(idx);
    auto count = od.get_unsigned(index, 0);
    if (!count) continue;
    for (unsigned s = 1; s <= *count && s <= 0xFE; ++s) {
      auto raw = od.get_unsigned(index, static_cast<std::uint8_t>(s));
      if (raw && *raw != 0) out.push_back(DispatcherEntry::from_raw(*raw));
    }
  }
  return out;
}

PdoReceiver::PdoReceiver(FrameSink sink, EventSink on_event, std::size_t max_bytes)
    : sink_(std::move(sink)), on_event_(std::move(on_event)), max_bytes_(max_bytes) {}

std::vector<std::string> PdoReceiver::add_node(std::uint8_t node, od::ObjectDictionary dict) {
  std::vector<std::string> problems;
  Node n;
  n.tpdos = read_all(dict, Direction::Transmit, &problems, max_bytes_);
  n.scanner = read_scanner_list(dict);
  n.dict = std::move(dict);
  nodes_[node] = std::move(n);
  rebuild_claims();
  auto conflicts = claim_conflicts(node);
  problems.insert(problems.end(), conflicts.begin(), conflicts.end());
  return problems;
}

std::vector<std::string> PdoReceiver::claim_conflicts(std::uint8_t node) const {
  std::vector<std::string> problems;
  for (const auto& p : nodes_.at(node).tpdos) {
    if (!p.comm.cob_id.valid()) continue;
    auto it = claims_.find(key(p.comm.cob_id));
    if (it != claims_.end() && it->second.node != node)
      problems.push_back("TPDO" + std::to_string(p.number) + ": COB-ID " + std::to_string(p.comm.cob_id.can_id()) +
                         " already used by node " + std::to_string(it->second.node));
  }
  return problems;
}

std::vector<std::string> PdoReceiver::set_tpdo(std::uint8_t node, PdoConfig cfg, std::string unusable) {
  Node& n = nodes_[node];
  const std::uint16_t number = cfg.number;
  auto pos = std::find_if(n.tpdos.begin(), n.tpdos.end(), [&](const PdoConfig& p) { return p.number >= number; });
  if (pos != n.tpdos.end() && pos->number == number) *pos = std::move(cfg);
  else n.tpdos.insert(pos, std::move(cfg));
  if (unusable.empty()) n.unusable.erase(number);
  else n.unusable[number] = std::move(unusable);
  rebuild_claims();  // claims index into tpdos
  return claim_conflicts(node);
}

void PdoReceiver::remove_node(std::uint8_t node) {
  nodes_.erase(node);
  rebuild_claims();
}

void PdoReceiver::set_dispatcher_list(const od::ObjectDictionary& local) { dispatcher_ = read_dispatcher_list(local); }

void PdoReceiver::rebuild_claims() {
  claims_.clear();
  for (const auto& [id, n] : nodes_)  // lowest node-ID wins a shared COB-ID
    for (std::size_t i = 0; i < n.tpdos.size(); ++i)
      if (n.tpdos[i].comm.cob_id.valid()) claims_.emplace(key(n.tpdos[i].comm.cob_id), Claim{id, i});
}

const PdoConfig* PdoReceiver::tpdo(std::uint8_t node, std::uint16_t number) const {
  auto it = nodes_.find(node);
  if (it == nodes_.end()) return nullptr;
  for (const auto& p : it->second.tpdos)
    if (p.number == number) return &p;
  return nullptr;
}

bool PdoReceiver::on_frame(const can::Frame& f, TimePoint now) {
  if (f.remote()) return false;
  CobId c;
  c.raw = f.id | (f.extended() ? 0x20000000U : 0U);
  auto it = claims_.find(key(c));
  PdoEvent ev;
  ev.cob_id = f.id;
  auto payload = f.payload();
  ev.raw.assign(payload.begin(), payload.end());
  if (it == claims_.end()) {
    const std::uint32_t function = f.id >> 7;
    if (f.extended() || function < 3 || function > 10 || (f.id & 0x7FU) == 0) return false;
    on_event_(std::move(ev));
    return true;
  }
  const Node& n = nodes_.at(it->second.node);
  const PdoConfig& cfg = n.tpdos[it->second.pdo];
  ev.node = it->second.node;
  ev.number = cfg.number;
  if (cfg.comm.synchronous() && in_window_ && !in_window_(now)) {
    ++dropped_late_;  // 7.2.2.2: synchronous PDOs belong to the window after SYNC
    return true;
  }
  if (auto bad = n.unusable.find(cfg.number); bad != n.unusable.end()) {
    ev.error = "TPDO" + std::to_string(cfg.number) + " mapping cannot be decoded: " + bad->second;
  } else if (cfg.kind != MappingKind::Normal) {
    decode_mpdo(it->second.node, cfg, f, ev);
  } else {
    const std::size_t want = cfg.byte_length();
    if (payload.size() < want) {
      ev.error = "length " + std::to_string(payload.size()) + " is shorter than the mapping (" + std::to_string(want) +
                 " bytes)";
    } else {
      auto values = unpack(cfg, payload);
      if (values) ev.values = std::move(*values);
      else ev.error = values.error().detail;
      if (values && payload.size() > want)
        ev.error = "length " + std::to_string(payload.size()) + " is longer than the mapping (" +
                   std::to_string(want) + " bytes); extra bytes ignored";
    }
  }
  on_event_(std::move(ev));
  return true;
}

void PdoReceiver::decode_mpdo(std::uint8_t owner, const PdoConfig& cfg, const can::Frame& f, PdoEvent& ev) const {
  auto p = f.payload();
  if (p.size() != 8) {
    ev.error = "MPDO of length " + std::to_string(p.size()) + " (must be 8)";
    return;
  }
  MpdoInfo info;
  info.destination_mode = (p[0] & 0x80U) != 0;
  info.address = static_cast<std::uint8_t>(p[0] & 0x7FU);
  info.index = static_cast<std::uint16_t>(p[1] | p[2] << 8);
  info.sub = p[3];
  ev.mpdo = info;
  if (info.destination_mode != (cfg.kind == MappingKind::DamMpdo)) {
    ev.error = info.destination_mode ? "DAM-MPDO on a PDO configured for SAM" : "SAM-MPDO on a PDO configured for DAM";
    return;
  }
  const auto data = p.subspan(4, 4);
  const Node* dict_node = nullptr;
  if (!info.destination_mode) {
    if (info.address == 0) {
      ev.error = "SAM-MPDO with producer node-ID 0";
      return;
    }
    auto pn = nodes_.find(info.address);
    dict_node = pn != nodes_.end() ? &pn->second : &nodes_.at(owner);
    if (!dict_node->scanner.empty() &&
        std::none_of(dict_node->scanner.begin(), dict_node->scanner.end(),
                     [&](const ScannerEntry& s) { return s.covers(info.index, info.sub); })) {
      ev.error = "object not in the producer's scanner list";
      return;
    }
    for (const auto& d : dispatcher_) {
      const unsigned block = d.block == 0 ? 1U : d.block;
      if (d.producer == info.address && d.producer_index == info.index && info.sub >= d.producer_sub &&
          unsigned{info.sub} < unsigned{d.producer_sub} + block) {
        ev.mpdo->local_index = d.local_index;
        ev.mpdo->local_sub = static_cast<std::uint8_t>(d.local_sub + (info.sub - d.producer_sub));
        break;
      }
    }
  } else {
    auto dn = nodes_.find(info.address);
    dict_node = dn != nodes_.end() ? &dn->second : &nodes_.at(owner);
  }
  const od::SubEntry* entry = dict_node->dict.find(info.index, info.sub);
  if (!entry) {
    if (!info.destination_mode) {
      ev.error = "producer has no object at this index/sub-index";
      return;
    }
    ev.values.push_back(MappedValue{info.index, info.sub, {}, Value::of_bytes(DataType::Domain, Bytes(data.begin(), data.end()))});
    return;
  }
  const unsigned bits = pdo_bit_size(entry->type);
  Result<Value> v = bits != 0 && bits <= 32 ? unpack_value(entry->type, data, 0, bits)
                                            : Result<Value>(make_error_code(SdoAbort::LengthTooHigh),
                                                            std::string(standard_name(entry->type)) +
                                                                " does not fit an MPDO");
  if (!v) {
    ev.error = v.error().detail;
    return;
  }
  std::string name = entry->name.empty() ? dict_node->dict.find(info.index)->name : entry->name;
  ev.values.push_back(MappedValue{info.index, info.sub, std::move(name), std::move(*v)});
}

bool PdoReceiver::request(std::uint8_t node, std::uint16_t number, TimePoint) {
  const PdoConfig* p = tpdo(node, number);
  if (!p || !p->comm.cob_id.valid() || !p->comm.cob_id.rtr_allowed()) return false;
  const std::size_t len = std::min<std::size_t>(p->byte_length(), can::kMaxClassicLength);
  sink_(can::Frame::rtr(p->comm.cob_id.can_id(), static_cast<std::uint8_t>(len), p->comm.cob_id.extended()));
  return true;
}

}  // namespace canopen::pdo
