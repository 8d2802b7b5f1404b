// The HTTP server's settings (HttpServer, http_server.hpp), the one place
// their defaults live. The YAML configuration (config/config.hpp) parses
// straight into this struct; the gateway's own HTTP keys extend it there.
//
// Pure data; no threads, no I/O.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

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

}  // namespace gateway::http
