// Checks of a request's header that need no Beast and no socket, applied by
// the server before it reads a body or runs a route:
//   - framing (request smuggling): one unambiguous way to find the body's end;
//   - Host (DNS rebinding): the request was meant for this gateway;
//   - Origin (CSRF, cross-site WebSocket hijacking): a browser page that is
//     not the gateway's own may not change anything or open the event stream;
//   - the media type of a state-changing request's body, so an HTML form or a
//     text/plain fetch cannot pass as an API call even without an Origin.
//
// Thread safety: pure functions; an OriginPolicy is immutable after
// construction and may be used from any thread.
#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace gateway::http {

// A Host header value or an origin's authority, normalised.
struct HostPort {
  // Lower case; a trailing dot of a DNS name removed; an IPv4 address in
  // dotted form, an IPv6 address in brackets, both canonical ("[::1]").
  std::string host;
  std::optional<std::uint16_t> port;  // nullopt: none given
  bool ip_literal = false;
};

// uri-host [":" port] of RFC 9110 7.2 with a DNS name of letters, digits,
// '-', '.', '_' and '~' only; nullopt for anything else (user info, percent
// encoding, an unbracketed IPv6 address, a port over 65535, ...).
std::optional<HostPort> parse_host(std::string_view value);

// An origin ("https://host[:port]", RFC 6454) of scheme http or https.
struct Origin {
  std::string scheme;  // "http" or "https"
  std::string host;    // as HostPort::host
  std::uint16_t port;  // explicit, or the scheme's default
  std::string canonical() const { return scheme + "://" + host + ":" + std::to_string(port); }
};
// nullopt for "null", other schemes, paths, and malformed hosts.
std::optional<Origin> parse_origin(std::string_view value);

// Header fields as received (names in any case), in order.
using HeaderFields = std::vector<std::pair<std::string_view, std::string_view>>;

// Why the request's framing or identity headers are ambiguous, or nullopt
// when they are not: a Transfer-Encoding other than exactly one "chunked"
// (any case, optional whitespace), Transfer-Encoding with Content-Length or
// in HTTP/1.0, Content-Length values that are not one number, or more than
// one Host or Authorization field. The caller MUST answer 400 and close the
// connection without reading further (the rest may be a smuggled request).
// `version` is 10 or 11.
std::optional<std::string> framing_error(const HeaderFields& fields, unsigned version);

// Methods that may change something: all but GET, HEAD and OPTIONS.
bool is_state_changing(std::string_view method);

// True when a state-changing request's body is something the API decodes:
// Content-Type application/json or application/x-protobuf (parameters such
// as charset ignored), one of the route's `extra` types, or neither a body
// nor a Content-Type at all.
bool acceptable_body_type(std::optional<std::string_view> content_type, bool has_body,
                          const std::vector<std::string>& extra = {});

// Which Host and Origin values belong to this gateway.
//
// Host: the listen address; for a loopback listener also localhost,
// 127.0.0.1 and [::1]; for a wildcard listener (0.0.0.0, ::) any IP
// literal, localhost and the machine's name; and every entry of
// host_names. IP literals are not open to DNS rebinding (that needs a DNS
// name the attacker controls), names are compared exactly. The port is not
// compared: it proves nothing about rebinding and a reverse proxy may
// change it; it does count for the Origin (same origin = same scheme, host
// and port).
class OriginPolicy {
 public:
  struct Settings {
    std::string listen_address;              // IP literal, or "localhost"
    std::vector<std::string> host_names;     // host names or IP literals, no port
    std::vector<std::string> allowed_origins;  // origins, or "*" for any
    std::string machine_name;                // gethostname(); used for wildcard listeners
  };
  // Throws std::invalid_argument naming the bad listen address, host name
  // or origin.
  explicit OriginPolicy(Settings settings);

  enum class HostVerdict : std::uint8_t {
    Own,        // go ahead
    Missing,    // HTTP/1.1 without Host: 400
    Malformed,  // 400
    Foreign,    // 421 Misdirected Request
  };
  // `host`: the request's Host value, nullopt when it has none (allowed in
  // HTTP/1.0). `version` is 10 or 11.
  HostVerdict check_host(std::optional<std::string_view> host, unsigned version) const;

  // True when a request with this Origin header may change state or open
  // the event stream: the origin is in allowed_origins (or that has "*"),
  // or it is the gateway's own as the browser addressed it: its scheme is
  // the connection's (https when `tls`), and its host and port are those
  // of the request's `host` (nullopt: none; the default port when it has
  // none). A request without Origin is not a browser's cross-site request
  // and is not checked here.
  bool origin_allowed(std::string_view origin, std::optional<std::string_view> host, bool tls) const;

 private:
  bool any_ip_ = false;
  bool any_origin_ = false;
  std::set<std::string, std::less<>> ips_;    // canonical IP literals
  std::set<std::string, std::less<>> names_;  // lower-case DNS names
  std::set<std::string, std::less<>> origins_;  // Origin::canonical()
};

}  // namespace gateway::http
