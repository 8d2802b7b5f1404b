// Bodies of SDO and NMT requests and their replies, shared by MQTT and REST
// (../shared/api-contract.md): request bodies in JSON (proto3 JSON of
// SdoReadRequest, SdoWriteRequest, NmtRequest, lenient where the contract
// allows) or binary protobuf are decoded into typed structs, and the
// request core's results (core/request.hpp) are encoded as a Reply (JSON or
// protobuf; errors as application/problem+json or a protobuf Problem: the
// one problem builder, encode_problem).
//
// Decoding never throws or crashes on any input; every failure is a Result
// error whose detail is one line for a 400 reply (see bad_request()).
//
// JSON request rules: field names in lowerCamelCase or snake_case; unknown
// fields are refused (typos would otherwise be ignored silently).
// "index" is a number, or a hex string ("1017", "0x1017", "1017h");
// "subIndex" a number, or a decimal or 0x hex string; "type" a CiA 309-3
// (or standard) type name; "value" any JSON, typed later with value_as().
//
// Thread safety: pure functions, thread-safe.
#pragma once

#include <boost/json/value.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include "canopen/events.hpp"
#include "canopen/result.hpp"
#include "canopen/types.hpp"
#include "core/request.hpp"

namespace canopen::gateway::v1 {
class SdoWriteRequest;
}

namespace gateway {

// One reply as the transports send it: HTTP status semantics and a body
// that is the same for REST and MQTT.
struct Reply {
  int status = 200;       // 200, 400, 404, 422, 429, 503, 504 ...
  std::string body;       // JSON (problem+json when status >= 400) or protobuf
  std::string content_type = "application/json";
  int retry_after = 0;    // seconds, with 429/503: when to try again (HTTP Retry-After); 0 = not said
};

struct SdoReadParams {
  std::optional<std::uint16_t> index;  // nullopt when the body had none (REST: from the path)
  std::optional<std::uint8_t> sub;
  std::optional<canopen::DataType> type;  // nullopt: from the EDS
  std::string reply_to;                   // MQTT 3.1.1 fallback; "" when absent
  std::string correlation_id;
};

struct SdoWriteParams {
  std::optional<std::uint16_t> index;
  std::optional<std::uint8_t> sub;
  std::optional<canopen::DataType> type;
  boost::json::value value;  // as sent; never null after a successful parse
  std::string reply_to;
  std::string correlation_id;

  // The value as `t` (the request's type or the EDS one): errors are
  // InvalidValue / ValueTooHigh / ValueTooLow with a detail for a 400 that
  // names the object (when index is set) and the type:
  // "1017h sub 0: 70000 is above 65535 (u16)".
  canopen::Result<canopen::Value> value_as(canopen::DataType t) const;
};

struct NmtParams {
  canopen::NmtCommand command = canopen::NmtCommand::Start;
  std::string reply_to;
  std::string correlation_id;
};

// protobuf = the body is a binary protobuf message, else JSON. An empty
// JSON body is an empty object (REST GET). require_address: index and
// subIndex must be in the body (MQTT); REST passes false, takes them from the path.
canopen::Result<SdoReadParams> parse_sdo_read(std::string_view body, bool protobuf, bool require_address = true);
canopen::Result<SdoWriteParams> parse_sdo_write(std::string_view body, bool protobuf, bool require_address = true);
canopen::Result<NmtParams> parse_nmt(std::string_view body, bool protobuf);

// The same for a JSON body parsed already (parse_json_body): a transport
// that reads fields of its own from the body first (MQTT 3.1.1's replyTo)
// parses it once.
canopen::Result<boost::json::object> parse_json_body(std::string_view body);
canopen::Result<SdoReadParams> parse_sdo_read(const boost::json::object& body, bool require_address = true);
canopen::Result<SdoWriteParams> parse_sdo_write(const boost::json::object& body, bool require_address = true);
// The same from a decoded protobuf message (REST puts the path's address into it first).
canopen::Result<SdoWriteParams> parse_sdo_write(const canopen::gateway::v1::SdoWriteRequest& message,
                                                bool require_address = true);
canopen::Result<NmtParams> parse_nmt(const boost::json::object& body);

// "start" "stop" "preop" "reset-node" "reset-comm"
using core::nmt_command_from_name;
using core::nmt_command_name;

// Path or topic text of an object index: "1017", "0x1017" or "1017h" (hex);
// of a sub-index: decimal or 0x hex. nullopt when malformed or out of range.
std::optional<std::uint16_t> parse_index_text(std::string_view s);
std::optional<std::uint8_t> parse_sub_index_text(std::string_view s);

struct ReplyOptions {
  bool protobuf = false;       // binary protobuf body instead of JSON
  std::string correlation_id;  // echoed in the body when not empty (MQTT 3.1.1)
};

// 200 SdoResponse {value, type, raw}. Precondition: holds_its_type(v).
Reply sdo_response(const canopen::Value& v, const ReplyOptions& opts = {});
// 200 NmtResponse {network, node, command}.
Reply nmt_response(std::uint32_t network, std::uint8_t node, canopen::NmtCommand command,
                   const ReplyOptions& opts = {});
// The problem builder (RFC 9457) of every reply: problem+json or a protobuf
// Problem. Title defaults to the HTTP reason phrase, type to
// "about:blank"; abortCode when the problem has one; Retry-After as given.
// The correlation id only when p.command_read (it came in the command's body).
Reply encode_problem(const core::Problem& p, const ReplyOptions& opts = {});
// A core result: SdoValue as sdo_response, NmtSent as nmt_response, Problem
// as encode_problem. The results of REST-only commands (RPDO, SYNC, PDO
// read) have no message here: the REST layer writes them.
Reply encode_result(const core::Result& r, const ReplyOptions& opts = {});
// A problem reply: status >= 400; title and type as encode_problem.
Reply problem(int status, std::string_view detail, const ReplyOptions& opts = {}, std::string_view title = {},
              std::string_view type = {});
// 400 with the parse error's detail.
Reply bad_request(const canopen::Error& error, const ReplyOptions& opts = {});
// 422 for an SDO abort: abortCode "0x06020000", detail = the CiA 301 text
// (": " and `context` appended when given).
Reply sdo_abort_problem(std::uint32_t abort_code, std::string_view context = {}, const ReplyOptions& opts = {});
// The reply for a failed SDO transfer (core::sdo_problem): remote (the
// device sent an abort) -> 422; a local timeout (0x05040000) -> 504; other
// local failures (malformed response, ...) -> 502. All carry abortCode.
Reply sdo_error_reply(std::error_code ec, bool remote, std::string_view context = {}, const ReplyOptions& opts = {});

}  // namespace gateway
