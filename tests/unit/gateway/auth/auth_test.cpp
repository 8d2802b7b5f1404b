// gateway/auth: token hashes, the role of each route and request, the
// per-client rate limit, per-caller queue shares, and how the bearer token
// and the caller are taken from a request.
#include "auth/auth.hpp"

#include <gtest/gtest.h>

#include "log.hpp"

namespace gateway::auth {
namespace {

using namespace std::chrono_literals;

// sha256("test"), as `printf test | sha256sum` prints it.
constexpr const char* kTestHash = "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08";

TEST(Sha256, KnownVectors) {
  EXPECT_EQ(sha256_hex("test"), kTestHash);
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(TokenStore, FindsByHashOnlyAndIgnoresHashCase) {
  std::string upper = kTestHash;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  TokenStore store({{"ops", Role::Operator, upper}, {"view", Role::Viewer, sha256_hex("other")}});
  auto p = store.find("test");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->name, "ops");
  EXPECT_EQ(p->role, Role::Operator);
  EXPECT_EQ(store.find("other")->role, Role::Viewer);
  EXPECT_FALSE(store.find(kTestHash));  // the hash itself is not a token
  EXPECT_FALSE(store.find(""));
  EXPECT_FALSE(store.find("tes"));
  EXPECT_FALSE(TokenStore{}.find("test"));
}

TEST(Roles, EachRouteNeedsItsRole) {
  EXPECT_EQ(required_role("GET", ""), Role::None);  // dashboard files
  EXPECT_EQ(required_role("GET", "/api/v1/openapi.json"), Role::None);
  EXPECT_EQ(required_role("GET", "/api/v1/networks/{net}/nodes"), Role::Viewer);
  EXPECT_EQ(required_role("HEAD", "/api/v1/networks/{net}/nodes"), Role::Viewer);
  EXPECT_EQ(required_role("GET", "/api/v1/events"), Role::Viewer);
  EXPECT_EQ(required_role("GET", "/metrics"), Role::Viewer);
  EXPECT_EQ(required_role("PUT", "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}"), Role::Operator);
  EXPECT_EQ(required_role("POST", "/api/v1/networks/{net}/nodes/{node}/nmt"), Role::Operator);
  EXPECT_EQ(required_role("PUT", "/api/v1/networks/{net}/nodes/{node}/rpdo/{n}"), Role::Operator);
  EXPECT_EQ(required_role("POST", "/api/v1/networks/{net}/sync"), Role::Operator);
  // A write route nobody listed: fail closed.
  EXPECT_EQ(required_role("DELETE", "/api/v1/networks/{net}"), Role::Admin);
}

TEST(Roles, RequestsNeedTheirRoleAndResetsNeedAdmin) {
  // The roles of the request core's commands: tests/unit/gateway/core/request_test.cpp.
  EXPECT_TRUE(allows(Role::Admin, Role::Operator));
  EXPECT_FALSE(allows(Role::Viewer, Role::Operator));
  EXPECT_FALSE(allows(Role::None, Role::Viewer));
}

TEST(RateLimiter, BurstThenRatePerClient) {
  RateLimiter rl(10, 3);  // 10/s, bursts of 3
  const auto t0 = RateLimiter::Clock::time_point{} + 1h;
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(rl.allow("10.0.0.1", t0));
  EXPECT_FALSE(rl.allow("10.0.0.1", t0));
  EXPECT_TRUE(rl.allow("10.0.0.2", t0));  // another client has its own bucket
  EXPECT_FALSE(rl.allow("10.0.0.1", t0 + 50ms));
  EXPECT_TRUE(rl.allow("10.0.0.1", t0 + 100ms));  // one token per 100 ms
  EXPECT_FALSE(rl.allow("10.0.0.1", t0 + 100ms));
  // Idle clients are forgotten once full again: memory stays bounded.
  EXPECT_TRUE(rl.allow("10.0.0.1", t0 + 1min));
  EXPECT_EQ(rl.clients(), 1U);
  RateLimiter off(0, 1);
  for (int i = 0; i < 1000; ++i) EXPECT_TRUE(off.allow("x", t0));
}

// Issue 12, item 12: a caller holds at most its share of each queue; what
// one caller holds does not count against another.
TEST(QueueShares, AtMostTheShareOfEachQueuePerCaller) {
  EXPECT_EQ(caller_share(32), 8U);
  EXPECT_EQ(caller_share(4), 2U);  // at least 2
  EXPECT_EQ(caller_share(0), 2U);
  QueueShares shares(2);
  EXPECT_TRUE(shares.take(1, "address 10.0.0.1"));
  EXPECT_TRUE(shares.take(1, "address 10.0.0.1"));
  EXPECT_FALSE(shares.take(1, "address 10.0.0.1"));
  EXPECT_EQ(shares.held(1, "address 10.0.0.1"), 2U);
  EXPECT_TRUE(shares.take(1, "address 10.0.0.2"));  // another caller
  EXPECT_TRUE(shares.take(2, "address 10.0.0.1"));  // another queue
  shares.give_back(1, "address 10.0.0.1");
  EXPECT_TRUE(shares.take(1, "address 10.0.0.1"));
  for (int i = 0; i < 3; ++i) shares.give_back(1, "address 10.0.0.1");  // more than held: stays at 0
  EXPECT_EQ(shares.held(1, "address 10.0.0.1"), 0U);
  EXPECT_TRUE(shares.take(1, "address 10.0.0.1"));
  EXPECT_EQ(shares.held(1, "address 10.0.0.1"), 1U);
}

// The HTTP authorizer names the caller for per-caller limits: the token's
// holder, else the client address.
TEST(HttpAuthorizer, NamesTheCallerByTokenElseAddress) {
  TokenStore store({{"ops", Role::Operator, kTestHash}});
  Logger log(LogLevel::Error);
  HttpAuthSettings settings;
  settings.anonymous = Role::Viewer;
  auto authorize = make_http_authorizer(settings, store, log);
  http::Request req;
  req.method = "GET";
  req.route = "/api/v1/networks/{net}/nodes";
  req.peer = "10.0.0.7:4711";
  EXPECT_FALSE(authorize(req));
  EXPECT_EQ(req.caller, "address 10.0.0.7");
  req.headers = {{"authorization", "Bearer test"}};
  EXPECT_FALSE(authorize(req));
  EXPECT_EQ(req.caller, "token 'ops'");
  settings.enabled = false;  // auth off: everyone is admin, still one caller per address
  http::Request open = req;
  EXPECT_FALSE(make_http_authorizer(settings, store, log)(open));
  EXPECT_EQ(open.caller, "address 10.0.0.7");
}

TEST(Bearer, FromHeaderOrForTheEventStreamFromTheQuery) {
  http::Request r;
  EXPECT_FALSE(bearer_token(r));
  r.headers = {{"authorization", "Bearer  abc "}};
  EXPECT_EQ(bearer_token(r), "abc");
  r.headers = {{"authorization", "bearer abc"}};
  EXPECT_EQ(bearer_token(r), "abc");
  r.headers = {{"authorization", "Basic dXNlcjpwYXNz"}};
  EXPECT_EQ(bearer_token(r), "");  // another scheme: present but unusable
  r.headers.clear();
  r.query = {{"access_token", "q"}};
  r.route = "/api/v1/networks/{net}";
  EXPECT_FALSE(bearer_token(r));  // the query is for the WebSocket only (logs, caches)
  r.route = "/api/v1/events";
  EXPECT_EQ(bearer_token(r), "q");
  EXPECT_EQ(peer_address("203.0.113.5:4711"), "203.0.113.5");
  EXPECT_EQ(peer_address("[::1]:80"), "::1");
}

TEST(Identify, TokenOrAnonymousRoleForUncheckedTransports) {
  TokenStore store({{"ops", Role::Operator, kTestHash}});
  core::Caller req;
  req.transport = core::Transport::mqtt;
  EXPECT_FALSE(identify(req, store, Role::None));
  EXPECT_EQ(req.role, Role::None);
  ASSERT_TRUE(check_role(req, Role::Operator));
  EXPECT_EQ(check_role(req, Role::Operator)->status, 401);

  EXPECT_EQ(req.who, "anonymous");
  EXPECT_EQ(req.key, kTokenlessMqttCaller);  // one caller for every tokenless request

  req.who = "mqtt";  // the transport's part of who
  req.token = "test";
  EXPECT_FALSE(identify(req, store, Role::None));
  EXPECT_EQ(req.who, "ops@mqtt");
  EXPECT_EQ(req.key, "token 'ops'");  // the token's holder, wherever it comes from
  EXPECT_EQ(req.role, Role::Operator);
  EXPECT_TRUE(req.token.empty());  // not kept once checked
  EXPECT_FALSE(check_role(req, Role::Operator));
  ASSERT_TRUE(check_role(req, Role::Admin));
  EXPECT_EQ(check_role(req, Role::Admin)->status, 403);

  core::Caller bad;
  bad.token = "wrong";
  auto d = identify(bad, store, Role::Admin);  // a bad token is refused even where anonymous may
  ASSERT_TRUE(d);
  EXPECT_EQ(d->status, 401);
  EXPECT_EQ(bad.key, kTokenlessMqttCaller);  // limited with the tokenless ones

  core::Caller http;  // checked by the HTTP layer already: left alone
  http.authenticated = true;
  http.role = Role::Viewer;
  http.token = "test";
  EXPECT_FALSE(identify(http, store, Role::None));
  EXPECT_EQ(http.role, Role::Viewer);
}

}  // namespace
}  // namespace gateway::auth
