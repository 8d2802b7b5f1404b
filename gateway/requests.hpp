// Requests that arrive over MQTT (and later REST/WebSocket), routed by
// topic or path but not yet interpreted: the transport hands the gateway
// the kind, the addressed network/node and the JSON (or protobuf) body, and
// gets back exactly one reply with an HTTP-style status and a body that is
// the same as the REST response (problem+json for errors).
//
// Thread safety: handlers run on the io_context thread; the reply callback
// MUST be called exactly once, on that thread, possibly later (an SDO
// transfer takes time). It must never be called from inside another thread.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "role.hpp"

namespace gateway {

enum class RequestKind : std::uint8_t { SdoRead, SdoWrite, Nmt };

struct ApiRequest {
  RequestKind kind = RequestKind::SdoRead;
  std::uint32_t network = 0;  // 1-based
  std::uint8_t node = 0;      // 0..127 (0 = all, NMT only)
  std::string body;           // JSON unless `protobuf`
  bool protobuf = false;      // body and reply in binary protobuf
  std::string who;            // authenticated identity, for the audit log ("" = anonymous)
  // A transport that checked the caller itself (HTTP) sets `authenticated`
  // and `role`. Otherwise (MQTT) `token` is the bearer token that came
  // with the request ("" = none) and the handler checks it.
  bool authenticated = false;
  Role role = Role::None;
  std::string token;
  // Who counts as one caller for per-caller limits (a share of each node's
  // SDO queue, the MQTT rate limit): set by a transport that checked the
  // caller (HTTP: "token '<name>'", or "address <ip>" without a token),
  // otherwise by auth::identify from the token.
  std::string caller;
};

struct ApiReply {
  int status = 200;       // HTTP semantics: 200, 400, 404, 422, 429, 503, 504 ...
  std::string body;       // JSON (problem+json when status >= 400) or protobuf
  std::string content_type = "application/json";
  int retry_after = 0;    // seconds, with 429/503: when to try again (HTTP Retry-After); 0 = not said
};

using ReplyFn = std::function<void(ApiReply)>;
using RequestHandler = std::function<void(const ApiRequest&, ReplyFn)>;

}  // namespace gateway
