// HTTP/1.1 + WebSocket server of the gateway (REST, /api/v1/events, static
// dashboard), on the process's single io_context. Beast stays inside
// server.cpp; this header is light on purpose.
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
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "event_message.hpp"
#include "http_types.hpp"

namespace gateway {
class Logger;
}

namespace gateway::http {

struct HttpConfig {
  std::string address = "127.0.0.1";  // IPv4 or IPv6 literal
  std::uint16_t port = 8080;          // 0 = ephemeral, see bound_port()

  // TLS (HTTPS/WSS) when both are set: PEM certificate chain and key. With
  // TLS on, the port speaks only TLS: a plain HTTP request fails the TLS
  // handshake and the connection is closed without an HTTP answer.
  std::filesystem::path cert_file;
  std::filesystem::path key_file;

  std::size_t max_header_bytes = 16 * 1024;   // larger header -> 431, close
  std::size_t max_body_bytes = 1024 * 1024;   // larger body -> 413, close
  // Limit for the TLS handshake, for reading a request's body once its
  // header is in, for writing a response, and for the WebSocket handshake.
  std::chrono::milliseconds read_timeout{std::chrono::seconds(15)};
  // Limit for the first byte of a request, from the end of the previous
  // response (or the connection's start): an idle keep-alive connection is
  // closed after it. While a handler is pending the connection is not read
  // (requests are answered in order, one at a time).
  std::chrono::milliseconds idle_timeout{std::chrono::seconds(60)};
  // Limit for the rest of the request's header, from its first byte: a
  // client that sends its header slowly (slowloris) is closed after it.
  std::chrono::milliseconds header_timeout{std::chrono::seconds(10)};
  // A handler that has not called its Responder by then gets a 500 sent
  // for it (its late answer is ignored).
  std::chrono::milliseconds handler_timeout{std::chrono::seconds(60)};
  // HTTP and WebSocket connections together. A new connection beyond it
  // closes the connection that has been idle longest (an HTTP connection
  // waiting for the first byte of a request, or for its TLS handshake); with
  // none idle, the new one is closed at once. Closed connections go away
  // asynchronously, so the count may exceed this for a moment.
  std::size_t max_connections = 256;
  // HTTP and WebSocket connections of one client address (IPv4, or the whole
  // IPv6 address); beyond it its new connections are closed at once, so one
  // client cannot lock the others out. 0 = no limit.
  std::size_t max_connections_per_address = 32;

  // Directory of the dashboard (see static_files.hpp); empty = none.
  std::filesystem::path static_dir;
  std::size_t max_static_file_bytes = 16 * 1024 * 1024;

  // WebSocket /api/v1/events: JSON text frames (ev->ws_json, the
  // EventEnvelope {kind, topic, <kind>: event}) by default;
  // "?format=protobuf" gives binary frames (ev->ws_binary) instead. The client
  // sends its filter as JSON text (schema: EventFilter in event_stream.hpp)
  // and gets {"subscribed":<filter>} or {"error":<problem>} back as text.

  // Browsers (see OriginPolicy in request_checks.hpp). Every request's Host
  // must be the server's own: the listen address (loopback: also localhost,
  // 127.0.0.1, [::1]; wildcard: any IP literal, localhost, the machine's
  // name) or one of host_names (names or IP literals, no port); otherwise
  // 421 (400 when missing in HTTP/1.1 or malformed). A state-changing
  // request (not GET/HEAD/OPTIONS) and the WebSocket upgrade with an Origin
  // header must come from the server's own origin (scheme, host and port of
  // the request's Host) or one of allowed_origins ("https://host:port";
  // "*" allows any, i.e. turns the check off); otherwise 403. A state-
  // changing request to a route whose body is not application/json or
  // application/x-protobuf gets 415. The constructor throws
  // std::invalid_argument for a malformed entry.
  std::vector<std::string> host_names;
  std::vector<std::string> allowed_origins;
  // The server pings a client that has sent nothing for ws_ping_interval
  // and closes it when nothing (no pong) arrives within another interval.
  std::chrono::milliseconds ws_ping_interval{std::chrono::seconds(20)};
  std::size_t ws_queue_max_messages = 1024;  // per client, see SendQueue
  std::size_t ws_queue_max_bytes = 8 * 1024 * 1024;
  // Queue full this long -> close with 1008 (policy violation).
  std::chrono::milliseconds ws_stall_timeout{std::chrono::seconds(10)};
  std::size_t ws_max_incoming_message = 4096;  // filter messages
  // SO_SNDBUF of WebSocket connections (0 = system default); a small one
  // keeps the kernel from hiding a slow client behind megabytes of buffer.
  int ws_socket_send_buffer = 0;
};

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
  void add_route(std::string method, std::string_view pattern, Handler handler);
  // Every (method, pattern) added, in the order added.
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
