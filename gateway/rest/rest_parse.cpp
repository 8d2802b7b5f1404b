#include "rest_parse.hpp"

#include <boost/json/parse.hpp>
#include <boost/json/value.hpp>
#include <charconv>

#include "canopen/json_value.hpp"
#include "request_codec.hpp"

namespace gateway::rest {

namespace json = boost::json;

namespace {

std::optional<std::uint16_t> json_index(const json::value& v) {
  if (v.is_int64() && v.as_int64() >= 0 && v.as_int64() <= 0xFFFF) return static_cast<std::uint16_t>(v.as_int64());
  if (v.is_uint64() && v.as_uint64() <= 0xFFFF) return static_cast<std::uint16_t>(v.as_uint64());
  if (v.is_string()) return parse_index_text(v.as_string());
  return std::nullopt;
}

std::optional<std::uint8_t> json_sub(const json::value& v) {
  if (v.is_int64() && v.as_int64() >= 0 && v.as_int64() <= 0xFF) return static_cast<std::uint8_t>(v.as_int64());
  if (v.is_uint64() && v.as_uint64() <= 0xFF) return static_cast<std::uint8_t>(v.as_uint64());
  if (v.is_string()) return parse_sub_index_text(v.as_string());
  return std::nullopt;
}

}  // namespace

std::optional<canopen::Bytes> parse_hex(std::string_view s) {
  canopen::Bytes out;
  int nibble = -1;
  for (char c : s) {
    int d = -1;
    if (c >= '0' && c <= '9') d = c - '0';
    else if (c >= 'a' && c <= 'f') d = c - 'a' + 10;
    else if (c >= 'A' && c <= 'F') d = c - 'A' + 10;
    else if (c == ' ') continue;
    else return std::nullopt;
    if (nibble < 0) {
      nibble = d;
    } else {
      out.push_back(static_cast<std::uint8_t>(nibble << 4 | d));
      nibble = -1;
    }
  }
  if (nibble >= 0) return std::nullopt;
  return out;
}

std::optional<RpdoBody> parse_rpdo_body(std::string_view body, const canopen::pdo::PdoConfig& pdo,
                                        const canopen::od::ObjectDictionary& od, std::string_view what,
                                        std::string& error) {
  auto fail = [&](std::string detail) -> std::optional<RpdoBody> {
    error = std::move(detail);
    return std::nullopt;
  };
  boost::system::error_code ec;
  auto parsed = json::parse(body, ec);
  if (ec || !parsed.is_object()) return fail("the body must be a JSON object {\"values\": [...]} or {\"raw\": \"hex\"}");
  const auto& o = parsed.as_object();
  RpdoBody out;
  if (const auto* r = o.if_contains("raw")) {
    if (!r->is_string()) return fail("\"raw\" must be a hex string");
    out.raw = parse_hex(r->as_string());
    if (!out.raw) return fail("\"raw\" is not hex: '" + std::string(r->as_string()) + "'");
    if (out.raw->size() != pdo.byte_length())
      return fail(std::string(what) + " carries " + std::to_string(pdo.byte_length()) + " bytes, not " +
                  std::to_string(out.raw->size()));
    return out;
  }
  const auto* vs = o.if_contains("values");
  if (vs == nullptr || !vs->is_array() || vs->as_array().empty())
    return fail("the body needs \"values\" (a non-empty array) or \"raw\"");
  for (const auto& item : vs->as_array()) {
    const auto* it = item.if_object();
    if (it == nullptr || !it->contains("index") || !it->contains("value"))
      return fail("each of \"values\" must be {\"index\", \"subIndex\", \"value\"}");
    const auto index = json_index(it->at("index"));
    const auto* sv = it->if_contains("subIndex");
    const auto sub = sv != nullptr ? json_sub(*sv) : std::optional<std::uint8_t>{0};
    if (!index || !sub) return fail("malformed index or subIndex in \"values\"");
    const canopen::pdo::MappingEntry* entry = nullptr;
    for (const auto& e : pdo.entries)
      if (!e.dummy && e.index == *index && e.sub == *sub) entry = &e;
    const std::string obj = canopen::od::object_label(*index, *sub);
    if (entry == nullptr) return fail(std::string(what) + " does not map " + obj);
    // Type and limit errors name the type themselves: "6040h sub 0: 70000 is above 65535 (u16)".
    auto v = canopen::value_from_json(entry->type, it->at("value"));
    if (!v) return fail(obj + ": " + v.error().detail);
    if (const auto* se = od.find(*index, *sub)) {
      std::string detail;
      if (canopen::check_limits(*v, se->low, se->high, &detail)) return fail(obj + ": " + detail);
    }
    out.values.push_back(canopen::MappedValue{*index, *sub, entry->name, std::move(*v)});
  }
  return out;
}

}  // namespace gateway::rest
