// HTTP/1.1 + WebSocket server of the gateway (REST, /api/v1/events, static
// dashboard), on the process's single io_context. Beast stays inside
// the server's own .cpp files; this header is light on purpose.
//
// Usage:
//   HttpServer srv(ioc, cfg);           // throws on bad TLS files
//   srv.add_route("GET", "/api/v1/networks/{net}", handler);
//   srv.set_authorizer(...);            // optional
//   srv.start();                        // binds; throws std::system_error:
//                                       // code() the errno (address_in_use, ...),
//                                       // what() "bind: <strerror>"
//   ... srv.publish(event) from the event pipeline ...
//   srv.stop();                         // or destroy it
//
// Thread safety: every member function MUST be called on the io_context's
// thread (or before the loop runs), except stats() and bound_port(), which
// may be called from any thread. Responders may be called from any thread.
// The io_context MUST outlive the HttpServer and be run (or destroyed)
// after stop() so the connections' last handlers can finish.
#pragma once

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "event_message.hpp"
#include "http/http_config.hpp"
#include "http/http_types.hpp"

namespace gateway {
class Logger;
}

namespace gateway::http {

// Counters for /metrics. Snapshot, consistent per field only.
struct HttpStats {
  std::uint64_t connections_accepted = 0;
  std::uint64_t connections_rejected = 0;              // closed at accept, both reasons:
  std::uint64_t connections_rejected_per_address = 0;  //   its address had max_connections_per_address
  std::uint64_t connections_rejected_full = 0;         //   max_connections open, none idle
  std::uint64_t connections_evicted_idle = 0;  // idle ones closed to admit a new one
  std::uint64_t connections_active = 0;        // HTTP + WebSocket
  std::uint64_t connections_idle = 0;          // of those, waiting for a request
  std::uint64_t header_timeouts = 0;           // closed after header_timeout
  // Requests refused before their route ran: ambiguous framing (400),
  // foreign or missing Host (421/400), foreign Origin (403), body media
  // type (415).
  std::uint64_t refused_framing = 0, refused_host = 0, refused_origin = 0, refused_media_type = 0;
  std::uint64_t tls_handshake_failures = 0;
  std::uint64_t ws_clients = 0;  // currently connected
  std::uint64_t ws_clients_total = 0;
  std::uint64_t ws_messages_sent = 0;
  std::uint64_t ws_messages_dropped = 0;  // thinned, all clients
  std::uint64_t ws_clients_closed_slow = 0;
  std::map<int, std::uint64_t> responses_by_status;  // 200 -> n, 404 -> n ...
};

// A server-push WebSocket endpoint other than /api/v1/events (e.g. the bus
// trace): the session pulls text messages from its source whenever it can
// write, so the source decides what to queue and drop. All calls on the
// io_context thread.
class StreamSource {
 public:
  virtual ~StreamSource() = default;
  // The next message to send; null when nothing is queued now.
  virtual std::shared_ptr<const std::string> next() = 0;
  // A text message from the client (binary ones are refused by the server).
  virtual void on_message(std::string_view text) = 0;
  // The connection is gone; called once. The source MUST NOT call wake after it.
  virtual void on_close() {}
  // Set by the server when the session opens: call it when next() has
  // something again (never from inside next()).
  std::function<void()> wake;
};

// A stream route's answer to an upgrade request (after the authorizer
// allowed it): a source to serve, or a refusal (e.g. 404 unknown network,
// 503 too many clients).
struct StreamAccept {
  std::shared_ptr<StreamSource> source;
  Response refusal;
};
using StreamHandler = std::function<StreamAccept(const Request&)>;

class HttpServer {
 public:
  // Loads the TLS certificate and key when configured (throws
  // std::runtime_error naming the file on failure) and checks host_names
  // and allowed_origins (std::invalid_argument). Does not bind yet.
  HttpServer(boost::asio::io_context& ioc, HttpConfig config, Logger* log = nullptr);
  ~HttpServer();  // stop()
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Adds a route (see router.hpp for patterns and precedence). Throws
  // std::invalid_argument on a bad or duplicate pattern. The path
  // /api/v1/events is the server's own (WebSocket).
  // `options`: the route's own body limit, body media types and handler
  // timeout (RouteOptions); the body limit applies before the body is read.
  void add_route(std::string method, std::string_view pattern, Handler handler, RouteOptions options = {});
  // Adds a WebSocket route GET `pattern` (router.hpp patterns) served by
  // the sources `handler` gives. A plain GET on it answers 426.
  void add_stream_route(std::string_view pattern, StreamHandler handler);
  // Every (method, pattern) added, in the order added (stream routes after the others).
  std::vector<std::pair<std::string, std::string>> routes() const;
  // Replaces the security hook (default: allow everything).
  void set_authorizer(Authorizer authorizer);

  // Binds and starts accepting. Throws std::system_error (e.g. address in use).
  void start();
  // Stops accepting, closes every connection (WebSocket clients get 1001
  // going away). Idempotent.
  void stop();
  // The bound port (useful with port 0); 0 before start().
  std::uint16_t bound_port() const;

  // Hands one event to every WebSocket client whose filter matches. Never
  // blocks: a slow client's queue is thinned or the client closed.
  void publish(const EncodedEventPtr& event);

  HttpStats stats() const;
  // WebSocket clients now connected that asked for protobuf (any thread).
  std::size_t binary_clients() const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;  // shared with connections, which may outlive *this
};

}  // namespace gateway::http
