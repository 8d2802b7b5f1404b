#include "auth/auth.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <memory>

#include "log.hpp"

namespace gateway::auth {

namespace {

bool iequals_prefix(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() &&
         std::equal(prefix.begin(), prefix.end(), s.begin(), [](char a, char b) {
           return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
         });
}

// Route patterns by the role they need (see auth.hpp); GET of anything
// not listed is viewer.
struct RouteRole {
  std::string_view method, route;
  Role role;
};
constexpr RouteRole kRouteRoles[] = {
    {"GET", "", Role::None},  // dashboard files
    {"GET", "/api/v1/openapi.json", Role::None},
    {"PUT", "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}", Role::Operator},
    {"POST", "/api/v1/networks/{net}/nodes/{node}/nmt", Role::Operator},
    {"PUT", "/api/v1/networks/{net}/nodes/{node}/rpdo/{n}", Role::Operator},
    // Reads the device, but changes how the gateway decodes and produces its PDOs.
    {"POST", "/api/v1/networks/{net}/nodes/{node}/pdo/read", Role::Operator},
    {"POST", "/api/v1/networks/{net}/sync", Role::Operator},
    // Contract "LSS master (CiA 305), REST (role admin)": the listing too
    // (the POSTs are admin by default).
    {"GET", "/api/v1/networks/{net}/lss/devices", Role::Admin},
    // Contract "Remote configuration and maintenance": store/restore operator
    // (the DCF read is viewer, DCF apply and program download admin by default).
    {"POST", "/api/v1/networks/{net}/nodes/{node}/store", Role::Operator},
    {"POST", "/api/v1/networks/{net}/nodes/{node}/restore", Role::Operator},
};

std::string audit_target(const http::Request& req) { return req.method + " " + req.path; }

}  // namespace

std::string sha256_hex(std::string_view data) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> md{};
  unsigned int len = 0;
  EVP_Digest(data.data(), data.size(), md.data(), &len, EVP_sha256(), nullptr);
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * len);
  for (unsigned i = 0; i < len; ++i) {
    out.push_back(kHex[md[i] >> 4]);
    out.push_back(kHex[md[i] & 0xF]);
  }
  return out;
}

TokenStore::TokenStore(std::vector<TokenEntry> tokens) : tokens_(std::move(tokens)) {
  for (auto& t : tokens_)
    std::transform(t.sha256.begin(), t.sha256.end(), t.sha256.begin(),
                   [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); });
}

std::optional<Principal> TokenStore::find(std::string_view token) const {
  if (token.empty()) return std::nullopt;
  const std::string h = sha256_hex(token);
  const TokenEntry* hit = nullptr;
  for (const auto& t : tokens_) {
    // Every entry is compared in full (no early exit), constant time each.
    const bool same = t.sha256.size() == h.size() && CRYPTO_memcmp(t.sha256.data(), h.data(), h.size()) == 0;
    if (same && hit == nullptr) hit = &t;
  }
  if (hit == nullptr) return std::nullopt;
  return Principal{hit->name, hit->role};
}

Role required_role(std::string_view method, std::string_view route) {
  const std::string_view m = method == "HEAD" ? std::string_view("GET") : method;
  for (const auto& r : kRouteRoles)
    if (r.method == m && r.route == route) return r.role;
  return m == "GET" ? Role::Viewer : Role::Admin;
}

bool RateLimiter::allow(std::string_view client, Clock::time_point now) {
  if (rate_ <= 0) return true;
  // Forget buckets that have refilled completely: they behave like new ones.
  const auto full_after = std::chrono::duration<double>(burst_ / rate_);
  if (now - last_prune_ > std::chrono::seconds(10)) {
    last_prune_ = now;
    for (auto it = buckets_.begin(); it != buckets_.end();)
      it = now - it->second.last > full_after ? buckets_.erase(it) : std::next(it);
  }
  auto [it, fresh] = buckets_.try_emplace(std::string(client));
  Bucket& b = it->second;
  if (fresh) {
    b.tokens = burst_;
  } else {
    const double dt = std::chrono::duration<double>(now - b.last).count();
    b.tokens = std::min(burst_, b.tokens + std::max(0.0, dt) * rate_);
  }
  b.last = now;
  if (b.tokens < 1) return false;
  b.tokens -= 1;
  return true;
}

std::string_view peer_address(std::string_view peer) {
  if (!peer.empty() && peer.front() == '[') {
    const auto close = peer.find(']');
    return close == std::string_view::npos ? peer : peer.substr(1, close - 1);
  }
  const auto colon = peer.rfind(':');
  return colon == std::string_view::npos ? peer : peer.substr(0, colon);
}

std::string token_caller(std::string_view token_name) { return "token '" + std::string(token_name) + "'"; }
std::string address_caller(std::string_view address) { return "address " + std::string(address); }

std::string QueueShares::key(std::uint64_t queue, std::string_view caller) {
  std::string k = std::to_string(queue);
  k += '\n';  // not in a queue number
  k += caller;
  return k;
}

bool QueueShares::take(std::uint64_t queue, std::string_view caller) {
  auto& n = held_[key(queue, caller)];
  if (n >= share_) {
    if (n == 0) held_.erase(key(queue, caller));  // share 0: nothing held, nothing kept
    return false;
  }
  ++n;
  return true;
}

void QueueShares::give_back(std::uint64_t queue, std::string_view caller) {
  auto it = held_.find(key(queue, caller));
  if (it == held_.end()) return;
  if (--it->second == 0) held_.erase(it);
}

std::size_t QueueShares::held(std::uint64_t queue, std::string_view caller) const {
  auto it = held_.find(key(queue, caller));
  return it == held_.end() ? 0 : it->second;
}

std::optional<std::string> bearer_token(const http::Request& req) {
  if (auto h = req.header("authorization")) {
    std::string_view v = *h;
    constexpr std::string_view kBearer = "Bearer ";
    if (!iequals_prefix(v, kBearer)) return std::string();  // another scheme: no usable token
    v.remove_prefix(kBearer.size());
    while (!v.empty() && v.front() == ' ') v.remove_prefix(1);
    while (!v.empty() && v.back() == ' ') v.remove_suffix(1);
    return std::string(v);
  }
  // WebSockets only: browsers cannot set the header there.
  if (req.route == "/api/v1/events" || req.route == "/api/v1/networks/{net}/trace")
    if (auto q = req.query_param("access_token")) return std::string(*q);
  return std::nullopt;
}

http::Authorizer make_http_authorizer(HttpAuthSettings settings, const TokenStore& tokens, Logger& log) {
  auto limiter = std::make_shared<RateLimiter>(settings.rate_limit, settings.rate_burst);
  return [settings, &tokens, &log, limiter](http::Request& req) -> std::optional<http::Response> {
    const std::string_view address = peer_address(req.peer);
    const Role need = required_role(req.method, req.route);
    if (need != Role::None && !limiter->unlimited() && !limiter->allow(address, RateLimiter::Clock::now())) {
      auto r = http::Response::problem(429, "too many requests from " + std::string(address) + "; slow down");
      r.headers.emplace_back("Retry-After", "1");
      return r;
    }
    req.caller = address_caller(address);
    if (!settings.enabled) {
      req.role = static_cast<std::uint8_t>(Role::Admin);
      return std::nullopt;
    }
    Role role = settings.anonymous;
    req.who = "anonymous@" + std::string(address);
    auto deny = [&](int status, const std::string& detail) {
      log.info("audit: auth failure: " + req.who + ": " + audit_target(req) + ": " + std::to_string(status) + " " +
               detail);
      log.flush();
      auto r = http::Response::problem(status, detail);
      if (status == 401) r.headers.emplace_back("WWW-Authenticate", "Bearer realm=\"canopen-gateway\"");
      return r;
    };
    if (auto token = bearer_token(req)) {
      auto p = tokens.find(*token);
      if (!p) return deny(401, "the bearer token is not valid");
      req.who = p->name + "@" + std::string(address);
      req.caller = token_caller(p->name);
      role = p->role;
    }
    req.role = static_cast<std::uint8_t>(role);
    if (allows(role, need)) return std::nullopt;
    if (role == Role::None) return deny(401, "this needs a bearer token (Authorization: Bearer <token>)");
    return deny(403, "role " + std::string(to_string(role)) + " may not " + audit_target(req) + " (needs " +
                         std::string(to_string(need)) + ")");
  };
}

std::optional<Denial> identify(core::Caller& req, const TokenStore& tokens, Role anonymous) {
  if (req.authenticated) return std::nullopt;
  req.key = std::string(kTokenlessMqttCaller);
  if (req.token.empty()) {
    req.role = anonymous;
    if (req.who.empty()) req.who = "anonymous";
    return std::nullopt;
  }
  auto p = tokens.find(req.token);
  req.token.clear();  // not kept around once checked
  if (!p) {
    req.role = Role::None;
    return Denial{401, "the token is not valid"};
  }
  req.who = p->name + (req.who.empty() ? std::string() : "@" + req.who);
  req.key = token_caller(p->name);
  req.role = p->role;
  return std::nullopt;
}

std::optional<Denial> check_role(const core::Caller& req, Role need) {
  if (allows(req.role, need)) return std::nullopt;
  if (req.role == Role::None)
    return Denial{401, "this request needs a token (MQTT 5 user property \"authorization\", or \"token\" in the body)"};
  return Denial{403, "role " + std::string(to_string(req.role)) + " may not do this (needs " +
                         std::string(to_string(need)) + ")"};
}

}  // namespace gateway::auth
