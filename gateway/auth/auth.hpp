// Who may call the gateway's API: bearer tokens (stored as SHA-256 hashes
// in the config), the role each route needs, a per-client rate limit,
// per-caller shares of bounded queues, and the HTTP authorizer that
// combines them with audit lines for failures.
//
// Roles (role.hpp): viewer reads, operator writes (SDO download, RPDO, SYNC,
// NMT start/stop/pre-operational, PDO configuration read), admin resets
// (NMT reset node/comm).
// NMT's role depends on the command in the body, so the HTTP layer only
// asks for operator on the NMT route and the request core checks the
// command with core::required_role (core/request.hpp) for REST and MQTT
// alike.
//
// Thread safety: TokenStore is immutable after construction (any thread).
// RateLimiter, QueueShares and the authorizer are for the io_context
// thread only.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/request.hpp"
#include "http/http_types.hpp"
#include "role.hpp"

namespace gateway {
class Logger;
}

namespace gateway::auth {

// Lower-case hex SHA-256 of `data` (OpenSSL).
std::string sha256_hex(std::string_view data);

struct Principal {
  std::string name;  // the token's name, for audit lines
  Role role = Role::None;
};

struct TokenEntry {
  std::string name;
  Role role = Role::Viewer;
  std::string sha256;  // lower-case hex
};

class TokenStore {
 public:
  TokenStore() = default;
  explicit TokenStore(std::vector<TokenEntry> tokens);
  // The token's principal, or nullopt. Compares the token's hash with every
  // stored hash in constant time, so timing tells nothing about which
  // (or how much of one) matched.
  std::optional<Principal> find(std::string_view token) const;
  bool empty() const { return tokens_.empty(); }

 private:
  std::vector<TokenEntry> tokens_;
};

// The role a route needs. Public (Role::None): the dashboard's files ("" route)
// and the OpenAPI document. Unknown routes need admin (fail closed).
Role required_role(std::string_view method, std::string_view route);

// Token bucket per client (an HTTP client address, an MQTT caller):
// `rate` requests per second, bursts up to `burst`. rate 0 = unlimited.
// Buckets idle long enough to be full are forgotten, so memory stays
// bounded by the clients of the last minute.
class RateLimiter {
 public:
  using Clock = std::chrono::steady_clock;
  RateLimiter(double rate, double burst) : rate_(rate), burst_(burst) {}
  // True when the request may go ahead (and takes a token); false: 429.
  bool allow(std::string_view client, Clock::time_point now);
  std::size_t clients() const { return buckets_.size(); }
  bool unlimited() const { return rate_ <= 0; }  // then allow() needs no time

 private:
  struct Bucket {
    double tokens = 0;
    Clock::time_point last;
  };
  double rate_, burst_;
  std::unordered_map<std::string, Bucket> buckets_;
  Clock::time_point last_prune_{};
};

// "203.0.113.5:4711" -> "203.0.113.5", "[::1]:80" -> "::1".
std::string_view peer_address(std::string_view peer);

// Callers for per-caller limits (core::Caller::key): a token's holder
// wherever it comes from, else a client address; MQTT requests without a
// (valid) token are one caller together, since nothing tells them apart.
std::string token_caller(std::string_view token_name);  // "token 'dashboard'"
std::string address_caller(std::string_view address);    // "address 10.0.0.7"
inline constexpr std::string_view kTokenlessMqttCaller = "MQTT requests without a token";

// The places of one caller in a bounded queue (each node's SDO queue) when
// the queue holds `capacity`: max(2, capacity / 4), so one caller cannot
// fill it and at least four share it.
constexpr std::size_t caller_share(std::size_t capacity) { return capacity / 4 > 2 ? capacity / 4 : 2; }

// Per-caller shares of bounded queues: a caller may hold at most `share`
// places of one queue (key: whatever names the queue, e.g. network and
// node). A place is taken when a request is queued and MUST be given back
// once when it leaves (completed, failed or refused by the queue). Memory
// is bounded by the places held.
class QueueShares {
 public:
  explicit QueueShares(std::size_t share) : share_(share) {}
  // Takes a place; false (nothing taken) when the caller holds `share` already.
  bool take(std::uint64_t queue, std::string_view caller);
  void give_back(std::uint64_t queue, std::string_view caller);
  std::size_t held(std::uint64_t queue, std::string_view caller) const;
  std::size_t share() const { return share_; }

 private:
  static std::string key(std::uint64_t queue, std::string_view caller);
  std::size_t share_;
  std::unordered_map<std::string, std::size_t> held_;
};

// The bearer token of an HTTP request: "Authorization: Bearer <t>", or for
// the WebSocket upgrade only (browsers cannot set its headers) the query
// parameter access_token. nullopt: none sent.
std::optional<std::string> bearer_token(const http::Request& req);

struct HttpAuthSettings {
  bool enabled = true;        // false: everyone is admin (demo, auth: false)
  Role anonymous = Role::None;  // role without a token (admin: loopback without tokens)
  double rate_limit = 0;      // per client address, requests per second (0 = off)
  double rate_burst = 1;
};

// The HttpServer's authorizer: rate limit (429 + Retry-After), then the
// token (401 + WWW-Authenticate when missing or unknown), then the route's
// role (403). Sets Request::who (token name, else "anonymous@<address>"),
// Request::caller (token_caller, else address_caller) and Request::role. Every 401/403 is an audit line (UTC time, who,
// method and path, result). `tokens` and `log` MUST outlive the authorizer.
http::Authorizer make_http_authorizer(HttpAuthSettings settings, const TokenStore& tokens, Logger& log);

// A refused request: 401 (no or unknown credentials) or 403 (role too low).
struct Denial {
  int status = 401;
  std::string detail;
};

// For transports that cannot check a caller themselves (MQTT requests):
// sets caller.role, caller.who and caller.key from caller.token
// (token_caller; the token is cleared once checked), or `anonymous` (who
// "anonymous", key kTokenlessMqttCaller) without one. A token that matches
// nothing: 401 (key kTokenlessMqttCaller). Does nothing for an already
// authenticated caller.
std::optional<Denial> identify(core::Caller& caller, const TokenStore& tokens, Role anonymous);

// Whether caller.role may do what needs `need`: 401 when it has no role at
// all, 403 when it is too low.
std::optional<Denial> check_role(const core::Caller& caller, Role need);

}  // namespace gateway::auth
