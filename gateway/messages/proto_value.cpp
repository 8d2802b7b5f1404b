#include "messages/proto_value.hpp"

#include <charconv>
#include <cmath>
#include <variant>

#include "canopen/json_value.hpp"
#include "messages/json_text.hpp"

namespace gateway::detail {

namespace {
bool fits_json_number(canopen::DataType t) { return canopen::fixed_size(t).value_or(8) <= 6; }
}  // namespace

void set_proto_value(google::protobuf::Value& out, const canopen::Value& v) {
  using canopen::DataType;
  const DataType t = v.type;
  if (t == DataType::Boolean) return out.set_bool_value(std::get<bool>(v.data));
  if (canopen::is_signed_integer(t)) {
    const auto i = std::get<std::int64_t>(v.data);
    if (fits_json_number(t)) return out.set_number_value(static_cast<double>(i));
    return out.set_string_value(std::to_string(i));
  }
  if (canopen::is_unsigned_integer(t)) {
    const auto u = std::get<std::uint64_t>(v.data);
    if (fits_json_number(t)) return out.set_number_value(static_cast<double>(u));
    return out.set_string_value(std::to_string(u));
  }
  switch (t) {
    case DataType::Real32: {
      const float f = std::get<float>(v.data);
      if (!std::isfinite(f)) break;
      // The double that the shortest float text reads as (0.1f -> 0.1).
      std::array<char, 32> buf{};
      const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), f);
      double d = 0;
      std::from_chars(buf.data(), r.ptr, d);
      return out.set_number_value(d);
    }
    case DataType::Real64: {
      const double d = std::get<double>(v.data);
      if (!std::isfinite(d)) break;
      return out.set_number_value(d);
    }
    case DataType::OctetString:
    case DataType::Domain: return out.set_string_value(to_hex(std::get<canopen::Bytes>(v.data)));
    case DataType::VisibleString: return out.set_string_value(to_utf8(std::get<std::string>(v.data)));
    default: break;
  }
  // Rare shapes: via the reference JSON conversion.
  const boost::json::value j = canopen::value_to_json(v);
  if (j.is_string()) {
    const auto& s = j.get_string();
    out.set_string_value(std::string(s.data(), s.size()));
  } else if (j.is_int64()) {
    out.set_number_value(static_cast<double>(j.get_int64()));
  } else if (j.is_uint64()) {
    out.set_number_value(static_cast<double>(j.get_uint64()));
  } else if (j.is_double()) {
    out.set_number_value(j.get_double());
  } else if (j.is_bool()) {
    out.set_bool_value(j.get_bool());
  } else {
    out.set_null_value(google::protobuf::NULL_VALUE);
  }
}

boost::json::value proto_value_to_json(const google::protobuf::Value& v) {
  switch (v.kind_case()) {
    case google::protobuf::Value::kNumberValue: {
      const double d = v.number_value();
      // Integral numbers as integers, so integer types see exact values.
      if (std::isfinite(d) && d == std::trunc(d) && std::fabs(d) < 9007199254740992.0) {
        return boost::json::value(static_cast<std::int64_t>(d));
      }
      return boost::json::value(d);
    }
    case google::protobuf::Value::kStringValue: return boost::json::value(v.string_value());
    case google::protobuf::Value::kBoolValue: return boost::json::value(v.bool_value());
    case google::protobuf::Value::kStructValue: return boost::json::object{};
    case google::protobuf::Value::kListValue: return boost::json::array{};
    default: return nullptr;
  }
}

}  // namespace gateway::detail
