#include "canopen/pdo/mapping.hpp"

#include <string>

#include "canopen/sdo/abort.hpp"

namespace canopen::pdo {

namespace {

std::string hex(std::uint32_t v, int digits) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  std::string s(static_cast<std::size_t>(digits), '0');
  for (int i = digits - 1; i >= 0; --i, v >>= 4) s[static_cast<std::size_t>(i)] = kDigits[v & 0xFU];
  return s;
}

std::string pdo_label(Direction d, std::uint16_t number) {
  return (d == Direction::Transmit ? "TPDO" : "RPDO") + std::to_string(number);
}

Error fail(SdoAbort code, std::string detail) { return Error{make_error_code(code), std::move(detail)}; }

}  // namespace

std::uint16_t comm_index(Direction d, std::uint16_t number) {
  return static_cast<std::uint16_t>((d == Direction::Transmit ? 0x1800 : 0x1400) + number - 1);
}
std::uint16_t mapping_index(Direction d, std::uint16_t number) {
  return static_cast<std::uint16_t>((d == Direction::Transmit ? 0x1A00 : 0x1600) + number - 1);
}

MappingEntry MappingEntry::from_raw(std::uint32_t raw) {
  MappingEntry e;
  e.index = static_cast<std::uint16_t>(raw >> 16);
  e.sub = static_cast<std::uint8_t>(raw >> 8);
  e.bits = static_cast<std::uint8_t>(raw);
  return e;
}

unsigned PdoConfig::total_bits() const {
  if (kind != MappingKind::Normal) return 64;  // MPDOs are always 8 bytes
  unsigned n = 0;
  for (const auto& e : entries) n += e.bits;
  return n;
}

Result<CommParams> read_comm_params(const od::ObjectDictionary& od, Direction d, std::uint16_t number) {
  if (number < 1 || number > kMaxPdoNumber) return fail(SdoAbort::NoSuchObject, "PDO number out of range");
  const std::uint16_t idx = comm_index(d, number);
  auto cob = od.get_unsigned(idx, 1);
  if (!cob) return fail(SdoAbort::NoSuchObject, pdo_label(d, number) + ": no COB-ID at " + hex(idx, 4) + "h sub 1");
  CommParams p;
  p.cob_id.raw = static_cast<std::uint32_t>(*cob);
  if (auto v = od.get_unsigned(idx, 2)) p.transmission_type = static_cast<std::uint8_t>(*v);
  if (auto v = od.get_unsigned(idx, 3)) p.inhibit_time = static_cast<std::uint16_t>(*v);
  if (auto v = od.get_unsigned(idx, 5)) p.event_timer = static_cast<std::uint16_t>(*v);
  if (auto v = od.get_unsigned(idx, 6)) p.sync_start = static_cast<std::uint8_t>(*v);
  return p;
}

Result<PdoParameters> read_parameters(const od::ObjectDictionary& od, Direction d, std::uint16_t number) {
  auto comm = read_comm_params(od, d, number);
  if (!comm) return comm.error();
  PdoParameters p;
  p.comm = *comm;
  const std::uint16_t midx = mapping_index(d, number);
  auto count = od.get_unsigned(midx, 0);
  if (!count) return fail(SdoAbort::NoSuchObject, pdo_label(d, number) + ": no mapping at " + hex(midx, 4) + "h");
  p.count = static_cast<std::uint8_t>(*count);
  if (const od::Object* m = od.find(midx)) {
    for (const auto& [sub, e] : m->subs) {
      if (sub == 0 || sub > kMaxMappedEntries) continue;
      if (auto raw = od.get_unsigned(midx, sub)) p.entries[sub] = static_cast<std::uint32_t>(*raw);
    }
  }
  return p;
}

Result<PdoConfig> resolve_pdo(Direction d, std::uint16_t number, const PdoParameters& parameters,
                              const od::ObjectDictionary& od, std::size_t max_bytes) {
  PdoConfig cfg;
  cfg.direction = d;
  cfg.number = number;
  cfg.comm = parameters.comm;
  const std::string label = pdo_label(d, number);
  const unsigned count = parameters.count;
  if (count == 0xFE) cfg.kind = MappingKind::SamMpdo;
  if (count == 0xFF) cfg.kind = MappingKind::DamMpdo;
  if (cfg.kind != MappingKind::Normal) return cfg;
  if (count > kMaxMappedEntries)
    return fail(SdoAbort::PdoLengthExceeded, label + ": " + std::to_string(count) + " mapped objects");
  std::size_t bits = 0;
  for (unsigned i = 1; i <= count; ++i) {
    const auto raw = parameters.entries.find(static_cast<std::uint8_t>(i));
    const std::string where = label + " entry " + std::to_string(i);
    if (raw == parameters.entries.end()) return fail(SdoAbort::NoSuchSubIndex, where + ": missing");
    MappingEntry e = MappingEntry::from_raw(raw->second);
    if (e.bits == 0) return fail(SdoAbort::PdoLengthExceeded, where + ": length 0");
    if (e.index >= 0x0001 && e.index <= 0x0007 && e.sub == 0) {
      e.dummy = true;
      e.type = *data_type_from_index(e.index);
    } else {
      const od::SubEntry* s = od.find(e.index, e.sub);
      if (!s) return fail(SdoAbort::NoSuchObject, where + ": " + hex(e.index, 4) + "h sub " + std::to_string(e.sub) +
                                                      " does not exist");
      e.type = s->type;
      e.name = s->name;
      if (e.name.empty()) e.name = od.find(e.index)->name;
    }
    const unsigned want = pdo_bit_size(e.type);
    const bool ok = want != 0 ? e.bits == want : e.bits % 8 == 0;
    if (!ok)
      return fail(SdoAbort::LengthMismatch, where + ": " + std::to_string(e.bits) + " bits for " +
                                                std::string(standard_name(e.type)));
    bits += e.bits;
    cfg.entries.push_back(std::move(e));
  }
  if (bits > max_bytes * 8)
    return fail(SdoAbort::PdoLengthExceeded, label + ": " + std::to_string(bits) + " bits exceed " +
                                                 std::to_string(max_bytes) + " bytes");
  return cfg;
}

Result<PdoConfig> read_pdo(const od::ObjectDictionary& od, Direction d, std::uint16_t number, std::size_t max_bytes) {
  auto p = read_parameters(od, d, number);
  if (!p) return p.error();
  return resolve_pdo(d, number, *p, od, max_bytes);
}

std::vector<PdoConfig> read_all(const od::ObjectDictionary& od, Direction d, std::vector<std::string>* errors,
                                std::size_t max_bytes) {
  std::vector<PdoConfig> out;
  for (std::uint16_t n = 1; n <= kMaxPdoNumber; ++n) {
    if (!od.find(comm_index(d, n))) continue;
    auto r = read_pdo(od, d, n, max_bytes);
    if (r) out.push_back(std::move(*r));
    else if (errors) errors->push_back(r.error().detail);
  }
  return out;
}

std::uint64_t extract_bits(std::span<const std::uint8_t> bytes, std::size_t offset, unsigned bits) {
  std::uint64_t v = 0;
  for (unsigned i = 0; i < bits; ++i) {
    const std::size_t b = offset + i;
    if ((bytes[b / 8] >> (b % 8)) & 1U) v |= std::uint64_t{1} << i;
  }
  return v;
}

void insert_bits(std::span<std::uint8_t> bytes, std::size_t offset, unsigned bits, std::uint64_t v) {
  for (unsigned i = 0; i < bits; ++i) {
    const std::size_t b = offset + i;
    const auto mask = static_cast<std::uint8_t>(1U << (b % 8));
    if ((v >> i) & 1U) bytes[b / 8] = static_cast<std::uint8_t>(bytes[b / 8] | mask);
    else bytes[b / 8] = static_cast<std::uint8_t>(bytes[b / 8] & ~mask);
  }
}

Result<Value> unpack_value(DataType type, std::span<const std::uint8_t> bytes, std::size_t offset, unsigned bits) {
  if (offset + bits > bytes.size() * 8) return fail(SdoAbort::LengthTooLow, "payload too short");
  if (type == DataType::Boolean) {
    if (bits != 1) return fail(SdoAbort::LengthMismatch, "BOOLEAN needs 1 bit");
    return Value::of_bool(extract_bits(bytes, offset, 1) != 0);
  }
  const unsigned want = pdo_bit_size(type);
  if (want != 0 ? bits != want : bits % 8 != 0)
    return fail(SdoAbort::LengthMismatch, std::to_string(bits) + " bits for " + std::string(standard_name(type)));
  Bytes raw(bits / 8);
  for (std::size_t i = 0; i < raw.size(); ++i)
    raw[i] = static_cast<std::uint8_t>(extract_bits(bytes, offset + 8 * i, 8));
  return decode(type, raw);
}

std::error_code pack_value(const Value& v, std::span<std::uint8_t> bytes, std::size_t offset, unsigned bits) {
  if (!holds_its_type(v)) return make_error_code(SdoAbort::LengthMismatch);
  if (offset + bits > bytes.size() * 8) return make_error_code(SdoAbort::PdoLengthExceeded);
  if (v.type == DataType::Boolean) {
    if (bits != 1) return make_error_code(SdoAbort::LengthMismatch);
    insert_bits(bytes, offset, 1, std::get<bool>(v.data) ? 1U : 0U);
    return {};
  }
  const unsigned want = pdo_bit_size(v.type);
  if (want != 0 ? bits != want : bits % 8 != 0) return make_error_code(SdoAbort::LengthMismatch);
  Bytes raw = encode(v);
  if (raw.size() > bits / 8) return make_error_code(SdoAbort::LengthTooHigh);
  raw.resize(bits / 8, 0);  // shorter strings are padded with NUL
  for (std::size_t i = 0; i < raw.size(); ++i) insert_bits(bytes, offset + 8 * i, 8, raw[i]);
  return {};
}

Result<std::vector<MappedValue>> unpack(const PdoConfig& pdo, std::span<const std::uint8_t> payload) {
  std::vector<MappedValue> out;
  std::size_t offset = 0;
  for (const auto& e : pdo.entries) {
    if (!e.dummy) {
      auto v = unpack_value(e.type, payload, offset, e.bits);
      if (!v) return v.error();
      out.push_back(MappedValue{e.index, e.sub, e.name, std::move(*v)});
    }
    offset += e.bits;
  }
  return out;
}

std::optional<std::size_t> bit_offset_of(const PdoConfig& pdo, std::uint16_t index, std::uint8_t sub) {
  std::size_t offset = 0;
  for (const auto& e : pdo.entries) {
    if (!e.dummy && e.index == index && e.sub == sub) return offset;
    offset += e.bits;
  }
  return std::nullopt;
}

}  // namespace canopen::pdo
