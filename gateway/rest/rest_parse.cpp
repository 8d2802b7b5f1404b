#include "rest/rest_parse.hpp"

#include <boost/json/parse.hpp>
#include <boost/json/value.hpp>
#include <algorithm>
#include <boost/json/object.hpp>
#include <charconv>
#include <chrono>

#include "canopen/json_value.hpp"
#include "messages/request_codec.hpp"

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

core::RpdoWrite decode_rpdo_body(std::uint8_t node, std::uint16_t number, std::string_view body) {
  core::RpdoWrite out{node, number, {}, {}, {}};
  boost::system::error_code ec;
  auto parsed = json::parse(body, ec);
  if (ec || !parsed.is_object()) {
    out.invalid = "the body must be a JSON object {\"values\": [...]} or {\"raw\": \"hex\"}";
    return out;
  }
  const auto& o = parsed.as_object();
  if (const auto* r = o.if_contains("raw")) {
    if (!r->is_string()) {
      out.invalid = "\"raw\" must be a hex string";
    } else if (auto raw = parse_hex(r->as_string())) {
      out.raw = std::move(*raw);
    } else {
      out.invalid = "\"raw\" is not hex: '" + std::string(r->as_string()) + "'";
    }
    return out;
  }
  const auto* vs = o.if_contains("values");
  if (vs == nullptr || !vs->is_array() || vs->as_array().empty()) {
    out.invalid = "the body needs \"values\" (a non-empty array) or \"raw\"";
    return out;
  }
  for (const auto& item : vs->as_array()) {
    core::RpdoItem& v = out.values.emplace_back();
    const auto* it = item.if_object();
    if (it == nullptr || !it->contains("index") || !it->contains("value")) {
      v.invalid = "each of \"values\" must be {\"index\", \"subIndex\", \"value\"}";
      break;  // nothing after it is looked at
    }
    const auto index = json_index(it->at("index"));
    const auto* sv = it->if_contains("subIndex");
    const auto sub = sv != nullptr ? json_sub(*sv) : std::optional<std::uint8_t>{0};
    if (!index || !sub) {
      v.invalid = "malformed index or subIndex in \"values\"";
      break;
    }
    v.index = *index;
    v.sub = *sub;
    v.value = canopen::literal_from_json(it->at("value"));
  }
  return out;
}

std::optional<RpdoBody> parse_rpdo_body(std::string_view body, const canopen::pdo::PdoConfig& pdo,
                                        const canopen::od::ObjectDictionary& od, std::string_view what,
                                        std::string& error) {
  return core::typed_rpdo_values(decode_rpdo_body(0, 0, body), pdo, od, what, error);
}

// ---- LSS bodies ----------------------------------------------------------------

namespace {

// The body as a JSON object with only `allowed` keys ("" = {} when empty_ok).
std::optional<json::object> lss_object(std::string_view body, std::initializer_list<std::string_view> allowed,
                                       bool empty_ok, std::string& error) {
  if (empty_ok && body.find_first_not_of(" \t\r\n") == std::string_view::npos) return json::object{};
  boost::system::error_code ec;
  auto v = json::parse(body, ec);
  if (ec || !v.is_object()) {
    error = "the body must be a JSON object";
    return std::nullopt;
  }
  for (const auto& kv : v.as_object()) {
    if (std::find(allowed.begin(), allowed.end(), std::string_view(kv.key())) == allowed.end()) {
      std::string list;
      for (auto a : allowed) list += std::string(list.empty() ? "" : ", ") + std::string(a);
      error = "unknown key \"" + std::string(kv.key()) + "\" (known: " + list + ")";
      return std::nullopt;
    }
  }
  return std::move(v.as_object());
}

// A whole number in [lo, hi]: a JSON number, or with hex_ok a "0x..." string.
std::optional<std::uint64_t> lss_number(const json::object& o, std::string_view key, std::uint64_t lo,
                                        std::uint64_t hi, bool hex_ok, std::string& error) {
  const auto* v = o.if_contains(key);
  std::optional<std::uint64_t> n;
  if (v == nullptr) {
    error = "\"" + std::string(key) + "\" is required";
    return std::nullopt;
  }
  if (v->is_int64() && v->as_int64() >= 0) n = static_cast<std::uint64_t>(v->as_int64());
  if (v->is_uint64()) n = v->as_uint64();
  if (v->is_string() && hex_ok) {
    const std::string_view s = v->as_string();
    std::uint64_t x = 0;
    if (s.size() > 2 && s.size() <= 10 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      auto [p, e] = std::from_chars(s.data() + 2, s.data() + s.size(), x, 16);
      if (e == std::errc() && p == s.data() + s.size()) n = x;
    }
  }
  if (!n || *n < lo || *n > hi) {
    error = "\"" + std::string(key) + "\" must be a whole number " + std::to_string(lo) + ".." + std::to_string(hi) +
            (hex_ok ? " (or a \"0x...\" string)" : "");
    return std::nullopt;
  }
  return n;
}

std::optional<bool> lss_flag(const json::object& o, std::string_view key, bool fallback, std::string& error) {
  const auto* v = o.if_contains(key);
  if (v == nullptr) return fallback;
  if (!v->is_bool()) {
    error = "\"" + std::string(key) + "\" must be true or false";
    return std::nullopt;
  }
  return v->as_bool();
}

// "timeoutMs": the fastscan step window, when given.
bool lss_timeout(const json::object& o, std::optional<std::chrono::milliseconds>& out, std::string& error) {
  if (!o.contains("timeoutMs")) return true;
  auto n = lss_number(o, "timeoutMs", 1, 10000, false, error);
  if (!n) return false;
  out = std::chrono::milliseconds(*n);
  return true;
}

}  // namespace

std::optional<core::LssFastscan> parse_lss_fastscan(std::string_view body, std::string& error) {
  auto o = lss_object(body, {"timeoutMs"}, true, error);
  if (!o) return std::nullopt;
  core::LssFastscan f;
  if (!lss_timeout(*o, f.timeout, error)) return std::nullopt;
  return f;
}

std::optional<core::LssConfigure> parse_lss_configure(std::string_view body, std::string& error) {
  auto o = lss_object(body, {"identity", "nodeId", "bitrate", "store"}, false, error);
  if (!o) return std::nullopt;
  const auto* id = o->if_contains("identity");
  if (id == nullptr || !id->is_object()) {
    error = "\"identity\" is required: {\"vendorId\", \"productCode\", \"revisionNumber\", \"serialNumber\"}";
    return std::nullopt;
  }
  const auto& ido = id->as_object();
  for (const auto& kv : ido) {
    const std::string_view k = kv.key();
    if (k != "vendorId" && k != "productCode" && k != "revisionNumber" && k != "serialNumber") {
      error = "unknown key \"identity." + std::string(k) +
              "\" (known: vendorId, productCode, revisionNumber, serialNumber)";
      return std::nullopt;
    }
  }
  core::LssConfigure c;
  std::uint32_t* words[] = {&c.address.vendor_id, &c.address.product_code, &c.address.revision, &c.address.serial};
  const char* keys[] = {"vendorId", "productCode", "revisionNumber", "serialNumber"};
  for (int i = 0; i < 4; ++i) {
    auto w = lss_number(ido, keys[i], 0, 0xFFFFFFFF, true, error);
    if (!w) {
      error.insert(1, "identity.");  // "identity.vendorId" ...
      return std::nullopt;
    }
    *words[i] = static_cast<std::uint32_t>(*w);
  }
  auto node = lss_number(*o, "nodeId", 1, 127, false, error);
  if (!node) return std::nullopt;
  c.node_id = static_cast<std::uint8_t>(*node);
  if (o->contains("bitrate")) {
    auto b = lss_number(*o, "bitrate", 1, 1'000'000, false, error);
    if (!b) return std::nullopt;
    c.bitrate = static_cast<std::uint32_t>(*b);
  }
  auto store = lss_flag(*o, "store", true, error);
  if (!store) return std::nullopt;
  c.store = *store;
  return c;
}

std::optional<core::LssAssignAll> parse_lss_assign_all(std::string_view body, std::string& error) {
  auto o = lss_object(body, {"firstNodeId", "store", "timeoutMs"}, false, error);
  if (!o) return std::nullopt;
  core::LssAssignAll a;
  auto first = lss_number(*o, "firstNodeId", 1, 127, false, error);
  if (!first) return std::nullopt;
  a.first_node_id = static_cast<std::uint8_t>(*first);
  auto store = lss_flag(*o, "store", true, error);
  if (!store) return std::nullopt;
  a.store = *store;
  if (!lss_timeout(*o, a.timeout, error)) return std::nullopt;
  return a;
}

}  // namespace gateway::rest
