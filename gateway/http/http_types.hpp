// The request and response shapes the HTTP server hands to route handlers.
// No Beast here: handlers (REST layer) include only this header.
//
// Thread safety: a Request is read-only for the handler; a Responder may be
// called from any thread (it hops onto the server's io_context), at most
// once (later calls are ignored), and is a no-op once the connection is gone.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "http_status.hpp"  // reason_phrase

namespace gateway::http {

struct Request {
  std::string method;  // "GET", "PUT" ... as sent (upper case by convention)
  std::string target;  // raw request-target, e.g. "/api/v1/x?type=u16"
  std::string path;    // percent-decoded path, e.g. "/api/v1/x"
  // Path parameters of the matched route pattern, decoded: {"net": "1"}.
  std::map<std::string, std::string, std::less<>> params;
  // Query parameters in order, decoded ('+' is a space); repeated keys kept.
  std::vector<std::pair<std::string, std::string>> query;
  // Header fields in order; names lower-cased.
  std::vector<std::pair<std::string, std::string>> headers;
  std::string body;
  std::string peer;  // "127.0.0.1:50312" or "[::1]:50312"
  bool tls = false;
  // The matched route pattern ("/api/v1/networks/{net}"), kEventsPath for
  // the WebSocket upgrade, "" for static files.
  std::string route;
  // Set by the Authorizer for the handler: the authenticated identity (for
  // audit lines; "" = anonymous) and the application's role value.
  std::string who;
  std::uint8_t role = 0;
  // Set by the Authorizer too: who counts as one caller for per-caller
  // limits (e.g. the token's name, else the client address); "" = the peer.
  std::string caller;
  // True when an Authorizer ran and let the request through; false when
  // the server has none (everything is open).
  bool authorized = false;

  // First value of a path parameter; "" when absent.
  std::string_view param(std::string_view name) const;
  // First value of a query parameter; nullopt when absent.
  std::optional<std::string_view> query_param(std::string_view name) const;
  // First value of a header (name case-insensitive); nullopt when absent.
  std::optional<std::string_view> header(std::string_view name) const;
};

// The body of a streamed response (Response::stream): bytes a route
// produces over time (a live capture), sent as they come: HTTP/1.1 chunked
// transfer encoding, or to an HTTP/1.0 client the raw bytes ended by the
// close. The connection closes after the body.
//
// Thread safety: every call on the io_context thread.
class BodySink {
 public:
  virtual ~BodySink() = default;
  // Queues `bytes` behind what is waiting. False, with nothing queued, when
  // the client is gone, the body is finished, or the bytes would take what
  // waits for a client that does not read beyond the response's
  // stream_buffer_bytes: the caller then drops (and counts) them. Never
  // blocks and never calls on_close.
  virtual bool write(std::string_view bytes) = 0;
  // Ends the body after what is queued plus `tail` (queued even beyond the
  // bound: keep it small). Later writes and finishes are ignored.
  virtual void finish(std::string_view tail = {}) = 0;
  // True once the connection is gone (client closed or reset, write error,
  // server stopping); what was queued is freed then.
  virtual bool closed() const = 0;
  // Called once, on the io_context thread but never from inside write() or
  // finish(), when the connection goes away before finish(): the route MUST
  // stop producing. Cleared after the call and by finish(), so it may hold
  // the route's state.
  std::function<void()> on_close;
};

struct Response {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  // Extra header fields (e.g. {"Allow", "GET, PUT"}, {"WWW-Authenticate", ...}).
  std::vector<std::pair<std::string, std::string>> headers;
  // A streamed body: when set, the server sends the status and header
  // fields at once (no Content-Length; `body` is ignored), then calls
  // `stream` on the io_context thread with the sink the route writes the
  // body to, and closes the connection after it. A HEAD request gets the
  // header fields only and `stream` is not called.
  std::function<void(std::shared_ptr<BodySink>)> stream;
  // How much of a streamed body may wait for a client that does not read.
  std::size_t stream_buffer_bytes = 1u << 20;

  // RFC 9457 problem document: {"type":"about:blank","title":<reason>,
  // "status":<status>,"detail":<detail>} as application/problem+json
  // (problem_json, messages/problem_json.hpp: the builder REST and MQTT replies use too).
  static Response problem(int status, std::string_view detail);
  static Response json(std::string body, int status = 200);
};


// Completes one request. See the thread-safety note at the top.
using Responder = std::function<void(Response)>;

// A route handler. It runs on the io_context thread and MUST arrange for the
// Responder to be called exactly once, now or later (e.g. after an SDO round
// trip); it must not block. The Request stays valid until the Responder has
// been called or destroyed, so a handler may keep a reference to it while
// the Responder is pending. If it never answers, the server answers 500
// after HttpConfig::handler_timeout.
using Handler = std::function<void(const Request&, Responder)>;

// What a route needs of the server beyond the defaults (HttpConfig). Most
// routes take none; a file upload (a DCF, a program image) takes its own
// body limit, media types and time.
struct RouteOptions {
  // The largest body this route reads (larger -> 413, close); 0 =
  // HttpConfig::max_body_bytes. Applied from the request's header on, so
  // other routes keep the server's limit.
  std::size_t max_body_bytes = 0;
  // Media types a state-changing request's body may have besides
  // application/json and application/x-protobuf (e.g.
  // "application/octet-stream"). Never add a CORS-safelisted one
  // (text/plain, forms): those are what the 415 check keeps out.
  std::vector<std::string> body_types;
  // Replaces HttpConfig::handler_timeout for this route; zero = none (the
  // handler MUST then answer by itself, e.g. because every step it waits for
  // has its own timeout).
  std::optional<std::chrono::milliseconds> handler_timeout;
};

// Security hook, run before every matched route (including static files)
// and before the WebSocket upgrade, after the body has been read: nullopt =
// let the request through (it may fill in `who` and `role`); a Response
// (e.g. 401 problem+json) is sent instead of running the route. Paths that
// match no route get 404/405 without it.
using Authorizer = std::function<std::optional<Response>(Request&)>;

}  // namespace gateway::http
