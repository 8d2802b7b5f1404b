// Typed values <-> JSON (see json_value.hpp for the rules).
#include <array>
#include <boost/json/string.hpp>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>

#include "canopen/json_value.hpp"
#include "canopen/sdo/abort.hpp"

namespace canopen {

namespace {

namespace json = boost::json;

constexpr std::int64_t kMsPerDay = 86'400'000;
constexpr std::int64_t kMaxTimeDifferenceMs = 0xFFFF * kMsPerDay + kMsPerDay - 1;

Error error(SdoAbort code, std::string detail) { return Error{make_error_code(code), std::move(detail)}; }

std::string label(DataType t) { return std::string(cia309_name(t)); }

// Integer types whose every value fits a JSON number exactly (<= 53 bits).
bool fits_json_number(DataType t) {
  return (is_signed_integer(t) || is_unsigned_integer(t)) && fixed_size(t).value_or(8) <= 6;
}

std::string_view kind_name(json::kind k) {
  switch (k) {
    case json::kind::null: return "null";
    case json::kind::bool_: return "a boolean";
    case json::kind::int64:
    case json::kind::uint64:
    case json::kind::double_: return "a number";
    case json::kind::string: return "a string";
    case json::kind::array: return "an array";
    case json::kind::object: return "an object";
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

Error wrong_kind(DataType t, const json::value& j) {
  return error(SdoAbort::InvalidValue,
               "expected " + expected_for(t) + " for " + label(t) + ", got " + std::string(kind_name(j.kind())));
}

std::string format_number(double d) {
  std::array<char, 32> buf{};
  auto r = std::to_chars(buf.data(), buf.data() + buf.size(), d);
  return std::string(buf.data(), r.ptr);
}

// JSON from a non-finite real: JSON has no NaN or infinity.
json::value non_finite(double d) {
  if (std::isnan(d)) return json::string("nan");
  return json::string(d < 0 ? "-inf" : "inf");
}

// VISIBLE_STRING bytes as JSON text: UTF-8 as is, anything else as Latin-1,
// so the serialized JSON is always valid.
std::string visible_to_utf8(const std::string& s) { return is_utf8(s) ? s : latin1_to_utf8(s); }

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

Result<Value> integer_from_json(DataType t, const json::value& j) {
  switch (j.kind()) {
    case json::kind::int64: return parse_value(t, std::to_string(j.get_int64()));
    case json::kind::uint64: return parse_value(t, std::to_string(j.get_uint64()));
    case json::kind::double_: return integer_from_double(t, j.get_double());
    case json::kind::string: {
      const json::string& s = j.get_string();
      return parse_value(t, normalize_json_integer_text(std::string_view(s.data(), s.size())));
    }
    default: return wrong_kind(t, j);
  }
}

Result<Value> real_from_json(DataType t, const json::value& j) {
  double d = 0;
  switch (j.kind()) {
    case json::kind::int64: d = static_cast<double>(j.get_int64()); break;
    case json::kind::uint64: d = static_cast<double>(j.get_uint64()); break;
    case json::kind::double_: d = j.get_double(); break;
    case json::kind::string: {
      const json::string& s = j.get_string();
      const std::string_view text(s.data(), s.size());
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

Result<Value> bool_from_json(const json::value& j) {
  switch (j.kind()) {
    case json::kind::bool_: return Value::of_bool(j.get_bool());
    case json::kind::int64:
    case json::kind::uint64:
    case json::kind::double_: {
      const double d = j.is_double()  ? j.get_double()
                       : j.is_int64() ? static_cast<double>(j.get_int64())
                                      : static_cast<double>(j.get_uint64());
      if (d == 0) return Value::of_bool(false);
      if (d == 1) return Value::of_bool(true);
      return error(SdoAbort::InvalidValue, format_number(d) + " is not a boolean (b: true, false, 0, 1)");
    }
    case json::kind::string: {
      const json::string& s = j.get_string();
      return parse_value(DataType::Boolean, std::string_view(s.data(), s.size()));
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

Result<Value> time_difference_from_json(const json::value& j) {
  constexpr DataType t = DataType::TimeDifference;
  switch (j.kind()) {
    case json::kind::int64: return time_difference_from_ms(j.get_int64(), std::to_string(j.get_int64()));
    case json::kind::uint64: {
      const auto u = j.get_uint64();
      const auto ms = u > static_cast<std::uint64_t>(kMaxTimeDifferenceMs) ? kMaxTimeDifferenceMs + 1
                                                                           : static_cast<std::int64_t>(u);
      return time_difference_from_ms(ms, std::to_string(u));
    }
    case json::kind::double_: {
      const double d = j.get_double();
      const std::string text = format_number(d);
      if (!std::isfinite(d) || d != std::trunc(d))
        return error(SdoAbort::InvalidValue, text + " is not an integer (td)");
      if (d < 0) return error(SdoAbort::ValueTooLow, text + " is below 0 (td)");
      if (d > static_cast<double>(kMaxTimeDifferenceMs)) {
        return error(SdoAbort::ValueTooHigh, text + " is above " + std::to_string(kMaxTimeDifferenceMs) + " (td)");
      }
      return time_difference_from_ms(static_cast<std::int64_t>(d), text);
    }
    case json::kind::string: {
      const json::string& s = j.get_string();
      const std::string_view text(s.data(), s.size());
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

json::value value_to_json(const Value& v) {
  const DataType t = v.type;
  if (t == DataType::Boolean) return json::value(std::get<bool>(v.data));
  if (is_signed_integer(t)) {
    const auto i = std::get<std::int64_t>(v.data);
    if (fits_json_number(t)) return json::value(i);
    return json::string(std::to_string(i));
  }
  if (is_unsigned_integer(t)) {
    const auto u = std::get<std::uint64_t>(v.data);
    // int64 for every <= 48-bit value so consumers see one JSON number kind.
    if (fits_json_number(t)) return json::value(static_cast<std::int64_t>(u));
    return json::string(std::to_string(u));
  }
  switch (t) {
    case DataType::Real32: {
      const float f = std::get<float>(v.data);
      if (!std::isfinite(f)) return non_finite(static_cast<double>(f));
      // Via the shortest float text, so 0.1f is 0.1 in JSON, not 0.10000000149011612.
      const std::string text = format_value(v);
      double d = 0;
      std::from_chars(text.data(), text.data() + text.size(), d);
      return json::value(d);
    }
    case DataType::Real64: {
      const double d = std::get<double>(v.data);
      if (!std::isfinite(d)) return non_finite(d);
      return json::value(d);
    }
    case DataType::VisibleString: return json::string(visible_to_utf8(std::get<std::string>(v.data)));
    case DataType::TimeDifference: {
      const auto& td = std::get<TimeOfDay>(v.data);
      return json::value(std::int64_t{td.days} * kMsPerDay + td.ms);
    }
    default:
      // os, d (hex), us (UTF-8), t (RFC 3339): the text form is the JSON string.
      return json::string(format_value(v));
  }
}

Result<Value> value_from_json(DataType type, const json::value& j) {
  if (type == DataType::Boolean) return bool_from_json(j);
  if (is_signed_integer(type) || is_unsigned_integer(type)) return integer_from_json(type, j);
  if (is_real(type)) return real_from_json(type, j);
  if (type == DataType::TimeDifference) return time_difference_from_json(j);
  if (cia309_name(type).empty()) {
    return error(SdoAbort::InvalidValue, "unknown data type " + std::to_string(static_cast<unsigned>(type)));
  }
  // vs, us, os, d, t: strings only.
  if (!j.is_string()) return wrong_kind(type, j);
  const json::string& s = j.get_string();
  return parse_value(type, std::string_view(s.data(), s.size()));
}

}  // namespace canopen
