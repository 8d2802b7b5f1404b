#include "sparkplug/payload.hpp"

#include <bit>
#include <cstring>
#include <type_traits>

#include "sparkplug_b.pb.h"

namespace gateway::sparkplug {

namespace pb = org::eclipse::tahu::protobuf;

// The hand-written writer and the generated parser must agree on the values.
static_assert(static_cast<int>(DataType::Int8) == pb::Int8 && static_cast<int>(DataType::UInt64) == pb::UInt64 &&
              static_cast<int>(DataType::Boolean) == pb::Boolean && static_cast<int>(DataType::DateTime) == pb::DateTime &&
              static_cast<int>(DataType::Bytes) == pb::Bytes && static_cast<int>(DataType::PropertySetList) == pb::PropertySetList);

DataType datatype_of(canopen::DataType t) {
  using C = canopen::DataType;
  switch (t) {
    case C::Boolean: return DataType::Boolean;
    case C::Integer8: return DataType::Int8;
    case C::Integer16: return DataType::Int16;
    case C::Integer24:
    case C::Integer32: return DataType::Int32;
    case C::Integer40:
    case C::Integer48:
    case C::Integer56:
    case C::Integer64: return DataType::Int64;
    case C::Unsigned8: return DataType::UInt8;
    case C::Unsigned16: return DataType::UInt16;
    case C::Unsigned24:
    case C::Unsigned32: return DataType::UInt32;
    case C::Unsigned40:
    case C::Unsigned48:
    case C::Unsigned56:
    case C::Unsigned64: return DataType::UInt64;
    case C::Real32: return DataType::Float;
    case C::Real64: return DataType::Double;
    case C::VisibleString:
    case C::UnicodeString: return DataType::String;
    case C::OctetString:
    case C::Domain: return DataType::Bytes;
    case C::TimeOfDay: return DataType::DateTime;
    case C::TimeDifference: return DataType::Int64;
  }
  return DataType::Unknown;
}

namespace {

// Field numbers (spec ch6; proto/sparkplug_b.proto).
enum : std::uint32_t {
  kPayloadTimestamp = 1, kPayloadMetrics = 2, kPayloadSeq = 3,
  kName = 1, kAlias = 2, kTimestamp = 3, kDatatype = 4, kIsNull = 7, kProperties = 9,
  kIntValue = 10, kLongValue = 11, kFloatValue = 12, kDoubleValue = 13, kBooleanValue = 14, kStringValue = 15,
  kBytesValue = 16,
  kSetKeys = 1, kSetValues = 2,
  kPropType = 1, kPropIntValue = 3,
};
enum : std::uint32_t { kVarint = 0, kFixed64 = 1, kLen = 2, kFixed32 = 5 };

// Counts what Writer would append: the same code computes a nested
// message's length prefix and then writes it, without a temporary buffer.
struct Counter {
  std::size_t n = 0;
  void byte(std::uint8_t) { ++n; }
  void bytes(const void*, std::size_t len) { n += len; }
};
// Writes into room the caller made (resize by Counter's count first), so
// no byte goes through std::string's capacity checks.
struct Writer {
  char* p;
  void byte(std::uint8_t b) { *p++ = static_cast<char>(b); }
  void bytes(const void* src, std::size_t len) {
    if (len) std::memcpy(p, src, len);
    p += len;
  }
};

// Appends what `write(sink)` writes to `out`: counted first, then written in place.
template <class F>
void append(std::string& out, F&& write) {
  Counter c;
  write(c);
  const std::size_t at = out.size();
  out.resize(at + c.n);
  Writer w{out.data() + at};
  write(w);
}

template <class S>
void varint(S& s, std::uint64_t v) {
  while (v >= 0x80) {
    s.byte(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  s.byte(static_cast<std::uint8_t>(v));
}
template <class S>
void tag(S& s, std::uint32_t field, std::uint32_t wire) {
  varint(s, (std::uint64_t{field} << 3) | wire);
}
template <class S>
void field_varint(S& s, std::uint32_t field, std::uint64_t v) {
  tag(s, field, kVarint);
  varint(s, v);
}
template <class S>
void field_bytes(S& s, std::uint32_t field, const void* p, std::size_t len) {
  tag(s, field, kLen);
  varint(s, len);
  s.bytes(p, len);
}
template <class S, class T>
void field_fixed(S& s, std::uint32_t field, T v) {  // float, double: little-endian IEEE 754
  static_assert(std::endian::native == std::endian::little, "the writer copies fixed-width values as they are");
  tag(s, field, sizeof v == 4 ? kFixed32 : kFixed64);
  s.bytes(&v, sizeof v);
}

// As Tahu Java and Ignition read them (contract, issue 27 items 5 and 6):
// UInt32 goes in long_value (tahu issues 131 and 397: a UInt32 in
// int_value reads as null there), the narrower types in int_value.
bool in_int_value(DataType t) {
  return t == DataType::Int8 || t == DataType::Int16 || t == DataType::Int32 || t == DataType::UInt8 ||
         t == DataType::UInt16;
}
// Signed values sign-extended to 32 bits, as Tahu's own encoders write
// them (-1234 as Int16 is 0xFFFFFB2E; its own width, 0xFB2E, reads as 64302
// in Tahu JS: spec issue 453, tahu issue 71); unsigned ones as they are.
std::uint32_t int_value_of(DataType t, std::uint64_t bits) {
  switch (t) {
    case DataType::UInt8: return static_cast<std::uint32_t>(bits & 0xFFu);
    case DataType::UInt16: return static_cast<std::uint32_t>(bits & 0xFFFFu);
    default: return static_cast<std::uint32_t>(bits);  // the int64's low 32 bits: sign-extended
  }
}

template <class S>
void value_fields(S& s, const Metric& m) {
  std::visit(
      [&](const auto& v) {
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, std::monostate>) {
          // is_null, written before the properties (field order)
        } else if constexpr (std::is_same_v<V, bool>) {
          field_varint(s, kBooleanValue, v ? 1 : 0);
        } else if constexpr (std::is_same_v<V, std::int64_t> || std::is_same_v<V, std::uint64_t>) {
          const auto bits = static_cast<std::uint64_t>(v);
          if (in_int_value(m.datatype))
            field_varint(s, kIntValue, int_value_of(m.datatype, bits));
          else
            field_varint(s, kLongValue, bits);
        } else if constexpr (std::is_same_v<V, float>) {
          field_fixed(s, kFloatValue, v);
        } else if constexpr (std::is_same_v<V, double>) {
          field_fixed(s, kDoubleValue, v);
        } else if constexpr (std::is_same_v<V, std::string>) {
          field_bytes(s, kStringValue, v.data(), v.size());
        } else {
          field_bytes(s, kBytesValue, v.data(), v.size());
        }
      },
      m.value);
}

template <class S>
void property_value(S& s, DataType type, std::uint32_t v) {
  field_varint(s, kPropType, static_cast<std::uint32_t>(type));
  field_varint(s, kPropIntValue, v);
}

template <class S>
void property_set(S& s, const ObjectRef& o) {
  static constexpr std::string_view kIndex = "index", kSubIndex = "subIndex";
  field_bytes(s, kSetKeys, kIndex.data(), kIndex.size());
  field_bytes(s, kSetKeys, kSubIndex.data(), kSubIndex.size());
  for (const auto& [type, v] : {std::pair{DataType::UInt16, std::uint32_t{o.index}},
                                std::pair{DataType::UInt8, std::uint32_t{o.sub_index}}}) {
    Counter c;
    property_value(c, type, v);
    tag(s, kSetValues, kLen);
    varint(s, c.n);
    property_value(s, type, v);
  }
}

// Fields in field-number order, as protobuf's own serializer writes them.
template <class S>
void metric_body(S& s, const Metric& m, Form form) {
  const bool birth = form == Form::Birth;
  if (birth || !m.alias) field_bytes(s, kName, m.name.data(), m.name.size());
  if (m.alias) field_varint(s, kAlias, *m.alias);
  field_varint(s, kTimestamp, m.timestamp);
  if (birth) field_varint(s, kDatatype, static_cast<std::uint32_t>(m.datatype));
  if (std::holds_alternative<std::monostate>(m.value)) field_varint(s, kIsNull, 1);
  if (birth && m.object) {
    Counter c;
    property_set(c, *m.object);
    tag(s, kProperties, kLen);
    varint(s, c.n);
    property_set(s, *m.object);
  }
  value_fields(s, m);
}

}  // namespace

void append_header(std::string& out, std::uint64_t timestamp) {
  append(out, [&](auto& s) { field_varint(s, kPayloadTimestamp, timestamp); });
}

void append_metric(std::string& out, const Metric& m, Form form) {
  Counter body;  // the body once for its length prefix, not again for the room
  metric_body(body, m, form);
  Counter prefix;
  tag(prefix, kPayloadMetrics, kLen);
  varint(prefix, body.n);
  const std::size_t at = out.size();
  out.resize(at + prefix.n + body.n);
  Writer w{out.data() + at};
  tag(w, kPayloadMetrics, kLen);
  varint(w, body.n);
  metric_body(w, m, form);
}

void append_seq(std::string& out, std::uint64_t seq) {
  append(out, [&](auto& s) { field_varint(s, kPayloadSeq, seq); });
}

std::optional<Command> decode_command(std::string_view payload) {
  pb::Payload p;
  if (!p.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) return std::nullopt;
  Command cmd;
  if (p.has_timestamp()) cmd.timestamp = p.timestamp();
  cmd.metrics.reserve(static_cast<std::size_t>(p.metrics_size()));
  for (const auto& m : p.metrics()) {
    CommandMetric c;
    c.name = m.name();
    if (m.has_alias()) c.alias = m.alias();
    if (m.has_datatype()) c.datatype = static_cast<DataType>(m.datatype());
    switch (m.value_case()) {
      case pb::Payload_Metric::kIntValue: c.value = std::uint64_t{m.int_value()}; break;
      case pb::Payload_Metric::kLongValue: c.value = std::uint64_t{m.long_value()}; break;
      case pb::Payload_Metric::kFloatValue: c.value = m.float_value(); break;
      case pb::Payload_Metric::kDoubleValue: c.value = m.double_value(); break;
      case pb::Payload_Metric::kBooleanValue: c.value = m.boolean_value(); break;
      case pb::Payload_Metric::kStringValue: c.value = m.string_value(); break;
      case pb::Payload_Metric::kBytesValue: c.value = canopen::Bytes(m.bytes_value().begin(), m.bytes_value().end()); break;
      default: break;  // null, or a DataSet/Template the gateway has no metric for
    }
    cmd.metrics.push_back(std::move(c));
  }
  return cmd;
}

namespace {
// A signed value of `bits` width from int_value: hosts write a negative one
// either in its own width (Tahu Python: -1 as Int8 is 255) or sign-extended
// to 32 bits (Tahu Java: 4294967295); both are accepted, nothing else.
std::optional<Value> signed_from_wire(std::uint64_t u, unsigned bits) {
  const std::uint64_t width_mask = (std::uint64_t{1} << bits) - 1;
  const std::uint64_t sign = std::uint64_t{1} << (bits - 1);
  if (u > 0xFFFFFFFFu) return std::nullopt;
  if (u > width_mask && (u | (width_mask >> 1)) != 0xFFFFFFFFu) return std::nullopt;
  std::uint64_t v = u & width_mask;
  const auto value = (v & sign) ? static_cast<std::int64_t>(v) - static_cast<std::int64_t>(width_mask + 1)
                                : static_cast<std::int64_t>(v);
  return Value{value};
}
}  // namespace

std::optional<Value> typed_value(const Value& wire, DataType t) {
  const auto* u = std::get_if<std::uint64_t>(&wire);
  switch (t) {
    case DataType::Int8:
      if (u) return signed_from_wire(*u, 8);
      break;
    case DataType::Int16:
      if (u) return signed_from_wire(*u, 16);
      break;
    case DataType::Int32:
      if (u) return signed_from_wire(*u, 32);
      break;
    case DataType::Int64:
      if (u) return Value{static_cast<std::int64_t>(*u)};
      break;
    case DataType::UInt8:
      if (u && *u <= 0xFFu) return wire;
      break;
    case DataType::UInt16:
      if (u && *u <= 0xFFFFu) return wire;
      break;
    case DataType::UInt32:
      if (u && *u <= 0xFFFFFFFFu) return wire;
      break;
    case DataType::UInt64:
    case DataType::DateTime:
      if (u) return wire;
      break;
    case DataType::Float:
      if (std::holds_alternative<float>(wire)) return wire;
      break;
    case DataType::Double:
      if (std::holds_alternative<double>(wire)) return wire;
      break;
    case DataType::Boolean:
      if (std::holds_alternative<bool>(wire)) return wire;
      break;
    case DataType::String:
    case DataType::Text:
    case DataType::UUID:
      if (std::holds_alternative<std::string>(wire)) return wire;
      break;
    case DataType::Bytes:
    case DataType::File:
      if (std::holds_alternative<canopen::Bytes>(wire)) return wire;
      break;
    default: break;
  }
  return std::nullopt;
}

}  // namespace gateway::sparkplug
