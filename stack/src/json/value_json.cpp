// Typed values <-> JSON (see json_value.hpp for the rules).
#include <boost/json/string.hpp>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>

#include "canopen/json_value.hpp"

namespace canopen {

namespace {

namespace json = boost::json;

constexpr std::int64_t kMsPerDay = 86'400'000;
// Integer types whose every value fits a JSON number exactly (<= 53 bits).
bool fits_json_number(DataType t) {
  return (is_signed_integer(t) || is_unsigned_integer(t)) && fixed_size(t).value_or(8) <= 6;
}

// JSON from a non-finite real: JSON has no NaN or infinity.
json::value non_finite(double d) {
  if (std::isnan(d)) return json::string("nan");
  return json::string(d < 0 ? "-inf" : "inf");
}

// VISIBLE_STRING bytes as JSON text: UTF-8 as is, anything else as Latin-1,
// so the serialized JSON is always valid.
std::string visible_to_utf8(const std::string& s) { return is_utf8(s) ? s : latin1_to_utf8(s); }

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

Literal literal_from_json(const json::value& j) {
  switch (j.kind()) {
    case json::kind::null: return Literal::of_kind(Literal::Kind::null);
    case json::kind::bool_: return Literal(j.get_bool());
    case json::kind::int64: return Literal(j.get_int64());
    case json::kind::uint64: return Literal(j.get_uint64());
    case json::kind::double_: return Literal(j.get_double());
    case json::kind::string: return Literal(std::string(j.get_string()));
    case json::kind::array: return Literal::of_kind(Literal::Kind::array);
    case json::kind::object: return Literal::of_kind(Literal::Kind::object);
  }
  return Literal::of_kind(Literal::Kind::null);
}

Result<Value> value_from_json(DataType type, const json::value& j) { return value_from_literal(type, literal_from_json(j)); }

}  // namespace canopen
