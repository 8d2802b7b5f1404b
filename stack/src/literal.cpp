// Literals typed as CANopen values (see literal.hpp and json_value.hpp for the rules).
#include "canopen/literal.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <string>
#include <string_view>

#include "canopen/sdo/abort.hpp"

namespace canopen {

std::string format_number(double d) {
  std::array<char, 32> buf{};
  auto r = std::to_chars(buf.data(), buf.data() + buf.size(), d);
  return std::string(buf.data(), r.ptr);
}

namespace {

using K = Literal::Kind;

constexpr std::int64_t kMsPerDay = 86'400'000;
constexpr std::int64_t kMaxTimeDifferenceMs = 0xFFFF * kMsPerDay + kMsPerDay - 1;

Error error(SdoAbort code, std::string detail) { return Error{make_error_code(code), std::move(detail)}; }

std::string label(DataType t) { return std::string(cia309_name(t)); }

std::string_view kind_name(Literal::Kind k) {
  switch (k) {
    case K::null: return "null";
    case K::boolean: return "a boolean";
    case K::int64:
    case K::uint64:
    case K::real: return "a number";
    case K::string: return "a string";
    case K::array: return "an array";
    case K::object: return "an object";
  }
  return "an unknown JSON value";
}

std::string expected_for(DataType t) {
  if (t == DataType::Boolean) return "true, false, 0 or 1";
  if (t == DataType::TimeDifference) return "a number of milliseconds or a \"days ms\" string";
  if (t == DataType::TimeOfDay) return "an RFC 3339 string";
  if (t == DataType::OctetString || t == DataType::Domain) return "a hex string";
  if (t == DataType::VisibleString || t == DataType::UnicodeString) return "a string";
  if (is_real(t)) return "a number or a numeric string";
  return "an integer or a numeric string";
}

Error wrong_kind(DataType t, const Literal& j) {
  return error(SdoAbort::InvalidValue,
               "expected " + expected_for(t) + " for " + label(t) + ", got " + std::string(kind_name(j.kind)));
}

// Numbers in JSON strings: decimal or 0x hex. Leading zeros are decimal
// ("010" is 10), unlike EDS text where they mean octal.
std::string normalize_json_integer_text(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  std::string sign;
  std::string_view body = s;
  if (!body.empty() && (body.front() == '+' || body.front() == '-')) {
    sign = std::string(1, body.front());
    body.remove_prefix(1);
  }
  if (body.size() >= 2 && body[0] == '0' && (body[1] == 'x' || body[1] == 'X')) return std::string(s);
  while (body.size() > 1 && body.front() == '0') body.remove_prefix(1);
  return sign + std::string(body);
}

Result<Value> integer_from_double(DataType t, double d) {
  const std::string text = format_number(d);
  if (!std::isfinite(d) || d != std::trunc(d)) {
    return error(SdoAbort::InvalidValue, text + " is not an integer (" + label(t) + ")");
  }
  // Outside 64 bits: out of range for every type.
  if (d >= 18446744073709551616.0) {
    const std::string max = is_unsigned_integer(t) ? std::to_string(unsigned_max(t)) : std::to_string(signed_max(t));
    return error(SdoAbort::ValueTooHigh, text + " is above " + max + " (" + label(t) + ")");
  }
  if (d < -9223372036854775808.0) {
    const std::string min = is_unsigned_integer(t) ? "0" : std::to_string(signed_min(t));
    return error(SdoAbort::ValueTooLow, text + " is below " + min + " (" + label(t) + ")");
  }
  // Exact conversion, then the same range checks as text.
  if (d < 0) return parse_value(t, std::to_string(static_cast<std::int64_t>(d)));
  return parse_value(t, std::to_string(static_cast<std::uint64_t>(d)));
}

Result<Value> integer_from_json(DataType t, const Literal& j) {
  switch (j.kind) {
    case K::int64: return parse_value(t, std::to_string(j.int64));
    case K::uint64: return parse_value(t, std::to_string(j.uint64));
    case K::real: return integer_from_double(t, j.real);
    case K::string: {
      return parse_value(t, normalize_json_integer_text(j.text));
    }
    default: return wrong_kind(t, j);
  }
}

Result<Value> real_from_json(DataType t, const Literal& j) {
  double d = 0;
  switch (j.kind) {
    case K::int64: d = static_cast<double>(j.int64); break;
    case K::uint64: d = static_cast<double>(j.uint64); break;
    case K::real: d = j.real; break;
    case K::string: {
      const std::string_view text(j.text);
      if (text.find_first_of("xX") == std::string_view::npos) return parse_value(t, text);
      // "0x10": a hex integer, taken as its numeric value.
      auto n = parse_value(DataType::Integer64, text);
      if (!n.ok()) {
        auto u = parse_value(DataType::Unsigned64, text);
        if (!u.ok())
          return error(SdoAbort::InvalidValue, "\"" + std::string(text) + "\" is not a number (" + label(t) + ")");
        d = static_cast<double>(std::get<std::uint64_t>(u->data));
      } else {
        d = static_cast<double>(std::get<std::int64_t>(n->data));
      }
      break;
    }
    default: return wrong_kind(t, j);
  }
  if (t == DataType::Real64) return Value::of_real64(d);
  // Same text path as parse_value, so r32 range errors read the same.
  return parse_value(t, format_number(d));
}

Result<Value> bool_from_json(const Literal& j) {
  switch (j.kind) {
    case K::boolean: return Value::of_bool(j.boolean);
    case K::int64:
    case K::uint64:
    case K::real: {
      const double d = j.kind == K::real  ? j.real
                       : j.kind == K::int64 ? static_cast<double>(j.int64)
                                      : static_cast<double>(j.uint64);
      if (d == 0) return Value::of_bool(false);
      if (d == 1) return Value::of_bool(true);
      return error(SdoAbort::InvalidValue, format_number(d) + " is not a boolean (b: true, false, 0, 1)");
    }
    case K::string: {
      return parse_value(DataType::Boolean, j.text);
    }
    default: return wrong_kind(DataType::Boolean, j);
  }
}

Result<Value> time_difference_from_ms(std::int64_t ms, const std::string& text) {
  if (ms < 0) return error(SdoAbort::ValueTooLow, text + " is below 0 (td)");
  if (ms > kMaxTimeDifferenceMs) {
    return error(SdoAbort::ValueTooHigh, text + " is above " + std::to_string(kMaxTimeDifferenceMs) + " (td)");
  }
  return Value{DataType::TimeDifference,
               TimeOfDay{static_cast<std::uint32_t>(ms % kMsPerDay), static_cast<std::uint16_t>(ms / kMsPerDay)}};
}

Result<Value> time_difference_from_json(const Literal& j) {
  constexpr DataType t = DataType::TimeDifference;
  switch (j.kind) {
    case K::int64: return time_difference_from_ms(j.int64, std::to_string(j.int64));
    case K::uint64: {
      const auto u = j.uint64;
      const auto ms = u > static_cast<std::uint64_t>(kMaxTimeDifferenceMs) ? kMaxTimeDifferenceMs + 1
                                                                           : static_cast<std::int64_t>(u);
      return time_difference_from_ms(ms, std::to_string(u));
    }
    case K::real: {
      const double d = j.real;
      const std::string text = format_number(d);
      if (!std::isfinite(d) || d != std::trunc(d))
        return error(SdoAbort::InvalidValue, text + " is not an integer (td)");
      if (d < 0) return error(SdoAbort::ValueTooLow, text + " is below 0 (td)");
      if (d > static_cast<double>(kMaxTimeDifferenceMs)) {
        return error(SdoAbort::ValueTooHigh, text + " is above " + std::to_string(kMaxTimeDifferenceMs) + " (td)");
      }
      return time_difference_from_ms(static_cast<std::int64_t>(d), text);
    }
    case K::string: {
      const std::string_view text(j.text);
      // A plain number of milliseconds as a string, or "days ms".
      if (auto n = parse_value(DataType::Integer64, normalize_json_integer_text(text)); n.ok()) {
        return time_difference_from_ms(std::get<std::int64_t>(n->data), std::string(text));
      }
      return parse_value(t, text);
    }
    default: return wrong_kind(t, j);
  }
}

}  // namespace

Result<Value> value_from_literal(DataType type, const Literal& j) {
  if (type == DataType::Boolean) return bool_from_json(j);
  if (is_signed_integer(type) || is_unsigned_integer(type)) return integer_from_json(type, j);
  if (is_real(type)) return real_from_json(type, j);
  if (type == DataType::TimeDifference) return time_difference_from_json(j);
  if (cia309_name(type).empty()) {
    return error(SdoAbort::InvalidValue, "unknown data type " + std::to_string(static_cast<unsigned>(type)));
  }
  // vs, us, os, d, t: strings only.
  if (j.kind != K::string) return wrong_kind(type, j);
  return parse_value(type, j.text);
}

}  // namespace canopen
