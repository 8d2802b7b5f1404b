#include "messages/request_codec.hpp"

#include <boost/json/parse.hpp>
#include <boost/json/parse_options.hpp>
#include <charconv>
#include <cmath>

#include "messages/problem_json.hpp"
#include "canopen/json_value.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/sdo/abort.hpp"
#include "canopen_gateway.pb.h"
#include "http_status.hpp"
#include "google/protobuf/stubs/logging.h"
#include "google/protobuf/util/json_util.h"
#include "messages/json_text.hpp"
#include "messages/proto_value.hpp"

namespace gateway {

namespace pb = ::canopen::gateway::v1;
namespace json = boost::json;

namespace {

canopen::Error fail(std::string detail) {
  return canopen::Error{std::make_error_code(std::errc::invalid_argument), std::move(detail)};
}

std::string_view sv(const json::string& s) { return {s.data(), s.size()}; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::optional<std::uint64_t> parse_digits(std::string_view s, int base) {
  if (s.empty()) return std::nullopt;
  std::uint64_t v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (r.ec != std::errc{} || r.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

// A JSON number that is a non-negative integer <= max.
std::optional<std::uint64_t> json_uint(const json::value& j, std::uint64_t max) {
  std::uint64_t v = 0;
  if (j.is_uint64()) {
    v = j.get_uint64();
  } else if (j.is_int64()) {
    if (j.get_int64() < 0) return std::nullopt;
    v = static_cast<std::uint64_t>(j.get_int64());
  } else if (j.is_double()) {
    const double d = j.get_double();
    if (!std::isfinite(d) || d < 0 || d != std::trunc(d) || d > static_cast<double>(max)) return std::nullopt;
    v = static_cast<std::uint64_t>(d);
  } else {
    return std::nullopt;
  }
  if (v > max) return std::nullopt;
  return v;
}

// One JSON request body as an object. "" is {} (a GET has no body).
canopen::Result<json::object> parse_object(std::string_view body) {
  if (trim(body).empty()) return json::object{};
  json::parse_options opt;
  opt.max_depth = 16;
  std::error_code ec;
  json::value v = json::parse(body, ec, {}, opt);
  if (ec) return fail("body is not valid JSON: " + ec.message());
  if (!v.is_object()) return fail("body must be a JSON object");
  return std::move(v.get_object());
}

// Field lookup that accepts the lowerCamelCase and the snake_case name.
struct Fields {
  const json::object& obj;
  std::vector<std::string_view> known;

  const json::value* get(std::string_view camel, std::string_view snake = {}) {
    known.push_back(camel);
    if (const auto* v = obj.if_contains(camel)) return v;
    if (!snake.empty()) {
      known.push_back(snake);
      return obj.if_contains(snake);
    }
    return nullptr;
  }
  // The first field that is not one of `known`.
  std::optional<std::string> unknown() const {
    for (const auto& kv : obj) {
      bool ok = false;
      for (auto k : known) ok = ok || k == sv(kv.key());
      if (!ok) return detail::to_utf8(sv(kv.key()));
    }
    return std::nullopt;
  }
};

canopen::Error unknown_field(const std::string& name) {
  std::string d = "unknown field \"";
  d += name;
  d += '"';
  return fail(d);
}

canopen::Result<std::string> string_field(const json::value* v, std::string_view name) {
  if (!v || v->is_null()) return std::string{};
  if (!v->is_string()) return fail(std::string(name) + " must be a string");
  return std::string(sv(v->get_string()));
}

canopen::Result<std::optional<std::uint16_t>> index_field(const json::value* v) {
  if (!v || v->is_null()) return std::optional<std::uint16_t>{};
  if (v->is_string()) {
    if (auto i = parse_index_text(sv(v->get_string()))) return std::optional<std::uint16_t>{*i};
    return fail("index must be a hex object index 0000-FFFF (\"1017\", \"0x1017\" or \"1017h\")");
  }
  if (auto u = json_uint(*v, 0xFFFF)) return std::optional<std::uint16_t>{static_cast<std::uint16_t>(*u)};
  return fail("index must be an integer 0..65535 or a hex string");
}

canopen::Result<std::optional<std::uint8_t>> sub_field(const json::value* v) {
  if (!v || v->is_null()) return std::optional<std::uint8_t>{};
  if (v->is_string()) {
    if (auto i = parse_sub_index_text(sv(v->get_string()))) return std::optional<std::uint8_t>{*i};
    return fail("subIndex must be 0..255, decimal or 0x hex");
  }
  if (auto u = json_uint(*v, 0xFF)) return std::optional<std::uint8_t>{static_cast<std::uint8_t>(*u)};
  return fail("subIndex must be an integer 0..255");
}

canopen::Result<std::optional<canopen::DataType>> type_text(std::string_view s) {
  if (s.empty()) return std::optional<canopen::DataType>{};
  if (auto t = canopen::parse_type_name(s)) return std::optional<canopen::DataType>{*t};
  return fail("unknown type \"" + detail::to_utf8(s) +
              "\" (expected a CiA 309-3 name: b i8 i16 i24 i32 i40 i48 i56 i64 u8 u16 u24 u32 u40 u48 u56 u64 r32 r64 "
              "t td vs os us d)");
}

// proto3 JSON omits a zero subIndex, so an index without one means sub 0.
template <typename P>
bool complete_address(P& p, bool require_address) {
  if (p.index && !p.sub) p.sub = 0;
  return !require_address || p.index.has_value();
}

template <typename M>
bool parse_proto(M& m, std::string_view body) {
  if (body.size() > static_cast<std::size_t>(INT32_MAX)) return false;
  // Protobuf logs malformed input (e.g. invalid UTF-8) to stderr; a client
  // must not be able to flood the log with it. The failure is reported.
  const google::protobuf::LogSilencer quiet;
  return m.ParseFromArray(body.data(), static_cast<int>(body.size()));
}

// Replies are not on a hot path: protobuf's own JSON printer, with the
// same options as the event JSON.
template <typename M>
Reply reply(int status, const M& m, const ReplyOptions& opts, std::string_view json_type) {
  Reply r;
  r.status = status;
  if (opts.protobuf) {
    m.SerializeToString(&r.body);
    r.content_type = "application/x-protobuf";
    return r;
  }
  google::protobuf::util::JsonPrintOptions po;
  po.always_print_primitive_fields = true;
  if (!google::protobuf::util::MessageToJsonString(m, &r.body, po).ok()) r.body = "{}";
  r.content_type = std::string(json_type);
  return r;
}

}  // namespace

std::optional<std::uint16_t> parse_index_text(std::string_view s) {
  s = trim(s);
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    s.remove_prefix(2);
  } else if (!s.empty() && (s.back() == 'h' || s.back() == 'H')) {
    s.remove_suffix(1);
  }
  auto v = parse_digits(s, 16);
  if (!v || *v > 0xFFFF) return std::nullopt;
  return static_cast<std::uint16_t>(*v);
}

std::optional<std::uint8_t> parse_sub_index_text(std::string_view s) {
  s = trim(s);
  std::optional<std::uint64_t> v;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    v = parse_digits(s.substr(2), 16);
  } else {
    v = parse_digits(s, 10);
  }
  if (!v || *v > 0xFF) return std::nullopt;
  return static_cast<std::uint8_t>(*v);
}

canopen::Result<canopen::Value> SdoWriteParams::value_as(canopen::DataType t) const {
  auto v = canopen::value_from_json(t, value);
  if (!v && index) {
    auto e = v.error();
    e.detail = canopen::od::object_label(*index, sub.value_or(0)) + ": " + e.detail;
    return e;
  }
  return v;
}

namespace {

// The fields SDO read and write requests share: address, type, and the MQTT
// 3.1.1 reply address. P is SdoReadParams or SdoWriteParams.
template <typename P, typename M>
std::optional<canopen::Error> common_from_proto(const M& m, P& p) {
  if (m.index() > 0xFFFF) return fail("index must be 0..65535");
  if (m.sub_index() > 0xFF) return fail("subIndex must be 0..255");
  // proto3 has no presence for these: a zero index is "not given" (no object 0000h exists).
  if (m.index() != 0) p.index = static_cast<std::uint16_t>(m.index());
  if (m.index() != 0 || m.sub_index() != 0) p.sub = static_cast<std::uint8_t>(m.sub_index());
  auto t = type_text(m.type());
  if (!t) return t.error();
  p.type = *t;
  p.reply_to = m.reply_to();
  p.correlation_id = m.correlation_id();
  return std::nullopt;
}

template <typename P>
std::optional<canopen::Error> common_from_json(Fields& f, P& p) {
  auto index = index_field(f.get("index"));
  if (!index) return index.error();
  auto sub = sub_field(f.get("subIndex", "sub_index"));
  if (!sub) return sub.error();
  auto type = string_field(f.get("type"), "type");
  if (!type) return type.error();
  auto t = type_text(*type);
  if (!t) return t.error();
  auto reply_to = string_field(f.get("replyTo", "reply_to"), "replyTo");
  if (!reply_to) return reply_to.error();
  auto corr = string_field(f.get("correlationId", "correlation_id"), "correlationId");
  if (!corr) return corr.error();
  p.index = *index;
  p.sub = *sub;
  p.type = *t;
  p.reply_to = std::move(*reply_to);
  p.correlation_id = std::move(*corr);
  return std::nullopt;
}

}  // namespace

canopen::Result<json::object> parse_json_body(std::string_view body) { return parse_object(body); }

canopen::Result<SdoReadParams> parse_sdo_read(const json::object& body, bool require_address) {
  SdoReadParams p;
  Fields f{body, {}};
  if (auto e = common_from_json(f, p)) return *e;
  if (auto u = f.unknown()) return unknown_field(*u);
  if (!complete_address(p, require_address)) return fail("index is required");
  return p;
}

canopen::Result<SdoReadParams> parse_sdo_read(std::string_view body, bool protobuf, bool require_address) {
  if (!protobuf) {
    auto obj = parse_object(body);
    if (!obj) return obj.error();
    return parse_sdo_read(*obj, require_address);
  }
  SdoReadParams p;
  pb::SdoReadRequest m;
  if (!parse_proto(m, body)) return fail("body is not a valid SdoReadRequest protobuf message");
  if (auto e = common_from_proto(m, p)) return *e;
  if (!complete_address(p, require_address)) return fail("index is required");
  return p;
}

namespace {
// What every SDO write request must have, however it was sent.
canopen::Result<SdoWriteParams> complete_write(SdoWriteParams p, bool require_address) {
  if (p.value.is_null()) return fail("value is required");
  if (!complete_address(p, require_address)) return fail("index is required");
  // A type given with the request: check the value now, so the 400 comes
  // before any CAN traffic.
  if (p.type) {
    auto v = p.value_as(*p.type);
    if (!v) return fail(v.error().detail);
  }
  return p;
}
}  // namespace

canopen::Result<SdoWriteParams> parse_sdo_write(const json::object& body, bool require_address) {
  SdoWriteParams p;
  Fields f{body, {}};
  if (auto e = common_from_json(f, p)) return *e;
  if (const json::value* value = f.get("value")) p.value = *value;
  if (auto u = f.unknown()) return unknown_field(*u);
  return complete_write(std::move(p), require_address);
}

canopen::Result<SdoWriteParams> parse_sdo_write(std::string_view body, bool protobuf, bool require_address) {
  if (!protobuf) {
    auto obj = parse_object(body);
    if (!obj) return obj.error();
    return parse_sdo_write(*obj, require_address);
  }
  pb::SdoWriteRequest m;
  if (!parse_proto(m, body)) return fail("body is not a valid SdoWriteRequest protobuf message");
  return parse_sdo_write(m, require_address);
}

canopen::Result<SdoWriteParams> parse_sdo_write(const pb::SdoWriteRequest& m, bool require_address) {
  SdoWriteParams p;
  if (auto e = common_from_proto(m, p)) return *e;
  if (m.has_value()) p.value = detail::proto_value_to_json(m.value());
  return complete_write(std::move(p), require_address);
}

namespace {
canopen::Result<NmtParams> complete_nmt(NmtParams p, const std::string& command) {
  if (command.empty()) return fail("command is required (start, stop, preop, reset-node, reset-comm)");
  auto cmd = nmt_command_from_name(command);
  if (!cmd) {
    return fail("unknown command \"" + detail::to_utf8(command) +
                "\" (expected start, stop, preop, reset-node or reset-comm)");
  }
  p.command = *cmd;
  return p;
}
}  // namespace

canopen::Result<NmtParams> parse_nmt(const json::object& body) {
  NmtParams p;
  Fields f{body, {}};
  auto c = string_field(f.get("command"), "command");
  if (!c) return c.error();
  auto reply_to = string_field(f.get("replyTo", "reply_to"), "replyTo");
  if (!reply_to) return reply_to.error();
  auto corr = string_field(f.get("correlationId", "correlation_id"), "correlationId");
  if (!corr) return corr.error();
  if (auto u = f.unknown()) return unknown_field(*u);
  p.reply_to = std::move(*reply_to);
  p.correlation_id = std::move(*corr);
  return complete_nmt(std::move(p), *c);
}

canopen::Result<NmtParams> parse_nmt(std::string_view body, bool protobuf) {
  if (!protobuf) {
    auto obj = parse_object(body);
    if (!obj) return obj.error();
    return parse_nmt(*obj);
  }
  NmtParams p;
  pb::NmtRequest m;
  if (!parse_proto(m, body)) return fail("body is not a valid NmtRequest protobuf message");
  p.reply_to = m.reply_to();
  p.correlation_id = m.correlation_id();
  return complete_nmt(std::move(p), m.command());
}

Reply sdo_response(const canopen::Value& v, const ReplyOptions& opts) {
  pb::SdoResponse m;
  detail::set_proto_value(*m.mutable_value(), v);
  m.set_type(std::string(canopen::cia309_name(v.type)));
  m.set_raw(detail::to_hex(canopen::encode(v)));
  if (!opts.correlation_id.empty()) m.set_correlation_id(detail::to_utf8(opts.correlation_id));
  return reply(200, m, opts, "application/json");
}

Reply nmt_response(std::uint32_t network, std::uint8_t node, canopen::NmtCommand command,
                   const ReplyOptions& opts) {
  pb::NmtResponse m;
  m.set_network(network);
  m.set_node(node);
  m.set_command(std::string(nmt_command_name(command)));
  if (!opts.correlation_id.empty()) m.set_correlation_id(detail::to_utf8(opts.correlation_id));
  return reply(200, m, opts, "application/json");
}

Reply encode_problem(const core::Problem& p, const ReplyOptions& opts) {
  const std::string_view correlation = p.command_read ? std::string_view(opts.correlation_id) : std::string_view();
  Reply r;
  r.status = p.status;
  r.retry_after = p.retry_after;
  if (!opts.protobuf) {
    r.body = problem_json(p, correlation);
    r.content_type = "application/problem+json";
    return r;
  }
  pb::Problem m;
  m.set_type(p.type.empty() ? std::string("about:blank") : detail::to_utf8(p.type));
  m.set_title(p.title.empty() ? std::string(reason_phrase(p.status)) : detail::to_utf8(p.title));
  m.set_status(static_cast<std::uint32_t>(p.status));
  m.set_detail(detail::to_utf8(p.detail));
  if (p.abort_code) m.set_abort_code(detail::abort_code_text(*p.abort_code));
  if (!correlation.empty()) m.set_correlation_id(detail::to_utf8(correlation));
  m.SerializeToString(&r.body);
  r.content_type = "application/x-protobuf";
  return r;
}

Reply encode_result(const core::Result& result, const ReplyOptions& opts) {
  if (const auto* v = std::get_if<core::SdoValue>(&result)) return sdo_response(v->value, opts);
  if (const auto* n = std::get_if<core::NmtSent>(&result)) return nmt_response(n->network, n->node, n->command, opts);
  if (const auto* p = std::get_if<core::Problem>(&result)) return encode_problem(*p, opts);
  core::Problem none;
  none.detail = "this result has no reply in this format";
  return encode_problem(none, opts);
}

Reply problem(int status, std::string_view detail_text, const ReplyOptions& opts, std::string_view title,
              std::string_view type) {
  core::Problem p;
  p.status = status;
  p.detail = std::string(detail_text);
  p.title = std::string(title);
  p.type = std::string(type);
  return encode_problem(p, opts);
}

Reply bad_request(const canopen::Error& error, const ReplyOptions& opts) { return problem(400, error.detail, opts); }

Reply sdo_abort_problem(std::uint32_t abort_code, std::string_view context, const ReplyOptions& opts) {
  return encode_problem(core::sdo_problem(canopen::make_error_code(static_cast<canopen::SdoAbort>(abort_code)), true,
                                          context),
                        opts);
}

Reply sdo_error_reply(std::error_code ec, bool remote, std::string_view context, const ReplyOptions& opts) {
  return encode_problem(core::sdo_problem(ec, remote, context), opts);
}

}  // namespace gateway
