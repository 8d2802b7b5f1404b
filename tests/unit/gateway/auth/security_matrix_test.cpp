// Security of the API (issue 6): every route x {no token, viewer, operator,
// admin} against the whole gateway on the simulated demo network, over real
// HTTP on 127.0.0.1; audit lines for writes and refusals; the same roles
// for requests that arrive without HTTP (MQTT); the per-client rate limit.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <thread>

#include "auth/auth.hpp"
#include "unit/gateway/rest/rest_rig.hpp"
#include "messages/request_codec.hpp"
#include "support/memory_log.hpp"
#include "support/mqtt_request.hpp"

namespace gateway {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using test::HttpReply;

const std::map<Role, std::string> kTokens = {
    {Role::Viewer, "viewer-secret"}, {Role::Operator, "operator-secret"}, {Role::Admin, "admin-secret"}};

// The role each route must need, written down here independently of
// auth.cpp's table: a route added without a decision here fails the test.
struct Expect {
  Role need;
  std::string body;  // a valid body, so an allowed request succeeds
  std::vector<std::string> headers = {};  // e.g. the body's Content-Type (default JSON)
  std::string node = "5";                 // the node of the concrete path
};
const std::map<std::pair<std::string, std::string>, Expect> kMatrix = {
    {{"GET", "/api/v1/gateway"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}/nodes"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}/nodes/{node}"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}"}, {Role::Viewer, ""}},
    {{"PUT", "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}"}, {Role::Operator, R"({"value":1000})"}},
    {{"POST", "/api/v1/networks/{net}/nodes/{node}/nmt"}, {Role::Operator, R"({"command":"start"})"}},
    {{"GET", "/api/v1/networks/{net}/nodes/{node}/od"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}/nodes/{node}/emcy"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}/nodes/{node}/history"}, {Role::Viewer, ""}},  // issue 18: charts
    {{"PUT", "/api/v1/networks/{net}/nodes/{node}/rpdo/{n}"}, {Role::Operator, R"({"raw":"0f00"})"}},
    {{"GET", "/api/v1/networks/{net}/nodes/{node}/pdo"}, {Role::Viewer, ""}},
    {{"POST", "/api/v1/networks/{net}/nodes/{node}/pdo/read"}, {Role::Operator, ""}},
    {{"POST", "/api/v1/networks/{net}/sync"}, {Role::Operator, "{}"}},
    // Contract "LSS master (CiA 305), REST (role admin)"; run in this order by
    // the admin: the scan finds the demo's unconfigured device, configure
    // gives it node-ID 30, then nobody is left for assign-all (200, none).
    {{"POST", "/api/v1/networks/{net}/lss/fastscan"}, {Role::Admin, R"({"timeoutMs":5})"}},
    {{"POST", "/api/v1/networks/{net}/lss/configure"},
     {Role::Admin, R"({"identity":{"vendorId":1441,"productCode":34850,"revisionNumber":65539,)"
                   R"("serialNumber":1426063361},"nodeId":30})"}},
    {{"POST", "/api/v1/networks/{net}/lss/assign-all"}, {Role::Admin, R"({"firstNodeId":40,"timeoutMs":5})"}},
    {{"GET", "/api/v1/networks/{net}/lss/devices"}, {Role::Admin, ""}},
    // Contract "Remote configuration and maintenance": reading a node's
    // settings viewer, changing them admin (node 5 keeps the demo's settings;
    // the EDS has what later requests use).
    {{"GET", "/api/v1/networks/{net}/nodes/{node}/config"}, {Role::Viewer, ""}},
    {{"PUT", "/api/v1/networks/{net}/nodes/{node}/config"},
     {Role::Admin, R"x({"name":"drive-x","eds":"(built in)","heartbeat-consumer-ms":2000,"boot":{"start":true}})x"}},
    {{"DELETE", "/api/v1/networks/{net}/nodes/{node}/config"}, {Role::Admin, ""}},
    {{"PUT", "/api/v1/networks/{net}/nodes/{node}/eds"},
     {Role::Admin, "[DeviceInfo]\nVendorName=Test\n[1017]\nParameterName=Producer heartbeat time\nObjectType=0x7\n"
                   "DataType=0x0006\nAccessType=rw\nDefaultValue=500\n",
      {"Content-Type: application/octet-stream"}}},
    // Contract "Remote configuration and maintenance": DCF read viewer,
    // store/restore operator, DCF apply and program download admin. The
    // program goes to the I/O module (node 10), which has the CiA 302-3 objects.
    {{"GET", "/api/v1/networks/{net}/nodes/{node}/dcf"}, {Role::Viewer, ""}},
    {{"POST", "/api/v1/networks/{net}/nodes/{node}/dcf"},
     {Role::Admin, R"({"dcf":"[1017]\nParameterName=Producer heartbeat time\nObjectType=0x7\nDataType=0x0006\n)"
                   R"(AccessType=rw\nParameterValue=1000\n"})"}},
    {{"POST", "/api/v1/networks/{net}/nodes/{node}/store"}, {Role::Operator, ""}},
    {{"POST", "/api/v1/networks/{net}/nodes/{node}/restore"}, {Role::Operator, ""}},
    {{"PUT", "/api/v1/networks/{net}/nodes/{node}/program/{n}"},
     {Role::Admin, "program image", {"Content-Type: application/octet-stream"}, "10"}},
    {{"GET", "/api/v1/openapi.json"}, {Role::None, ""}},
    {{"GET", "/metrics"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}/capture"}, {Role::Viewer, ""}},
    {{"GET", "/api/v1/networks/{net}/trace"}, {Role::Viewer, ""}},  // WebSocket
};

// Pattern -> a concrete path on the demo network (node 5, heartbeat 1017h).
std::string concrete(std::string pattern, const std::string& node = "5") {
  const std::pair<const char*, const char*> subst[] = {
      {"{net}", "1"}, {"{node}", node.c_str()}, {"{index}", "1017"}, {"{sub}", "0"}, {"{n}", "1"}};
  for (auto [from, to] : subst)
    if (auto p = pattern.find(from); p != std::string::npos) pattern.replace(p, std::string(from).size(), to);
  return pattern;
}

// The REST rig with auth on (as outside --demo), three tokens, a dashboard
// directory and the log captured for audit lines.
struct SecureRig {
  explicit SecureRig(double rate_limit = 0, double burst = 1)
      : web(make_web()),
        state(std::filesystem::temp_directory_path() / ("auth-state-" + std::to_string(::getpid()))),
        rig(
            {},
            [&](Config& c) {
              c.http.auth = true;  // the demo turns it off; this is the production setting
              for (const auto& [role, token] : kTokens)
                c.http.tokens.push_back({std::string(to_string(role)), role, auth::sha256_hex(token)});
              c.mqtt.requests_role = Role::None;
              c.http.rate_limit = rate_limit;
              c.http.rate_burst = burst;
              c.state_dir = state.string();  // run-time node configuration keeps its changes there
            },
            log.file, web) {
    EXPECT_TRUE(rig.run_until([&] { return rig.operational(5); })) << "node 5 did not start";
  }
  ~SecureRig() {
    rig.server->stop();
    std::filesystem::remove_all(web);
    std::filesystem::remove_all(state);
  }
  static std::filesystem::path make_web() {
    auto dir = std::filesystem::temp_directory_path() / ("auth-web-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "index.html") << "<!doctype html><title>dashboard</title>";
    return dir;
  }

  HttpReply as(std::optional<Role> role, const std::string& method, const std::string& target,
               const std::string& body = {}, std::vector<std::string> headers = {}) {
    if (role) headers.push_back("Authorization: Bearer " + kTokens.at(*role));
    return rig.request(method, target, body, std::move(headers));
  }
  HttpReply request(const std::string& method, const std::string& target, const std::string& body,
                    std::vector<std::string> headers) {
    return rig.request(method, target, body, std::move(headers));
  }
  template <typename Pred>
  bool run_until(Pred pred) {
    return rig.run_until(pred);
  }

  std::string log_text() {
    rig.log->flush();
    return log.text();
  }

  MemoryLog log;  // outlives rig (declared before it)
  std::filesystem::path web;
  std::filesystem::path state;
  test::RestRig rig;
};

const std::vector<std::string> kUpgrade = {"Upgrade: websocket", "Connection: Upgrade",
                                           "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
                                           "Sec-WebSocket-Version: 13"};

std::string who(std::optional<Role> r) { return r ? std::string(to_string(*r)) : std::string("no token"); }

TEST(SecurityMatrix, EveryRouteByRole) {
  SecureRig rig;
  auto routes = rig.rig.server->routes();
  routes.emplace_back("GET", "/api/v1/events");  // the server's own WebSocket path
  routes.emplace_back("GET", "/");               // the dashboard
  ASSERT_GE(routes.size(), 13U);
  const std::optional<Role> callers[] = {std::nullopt, Role::Viewer, Role::Operator, Role::Admin};
  for (const auto& [method, pattern] : routes) {
    Expect e{Role::None, ""};
    const bool ws = pattern == "/api/v1/events" || pattern == "/api/v1/networks/{net}/trace";
    if (pattern == "/api/v1/events") {
      e.need = Role::Viewer;
    } else if (pattern != "/") {
      auto it = kMatrix.find({method, pattern});
      ASSERT_NE(it, kMatrix.end()) << method << " " << pattern << " has no expected role in this test";
      e = it->second;
    }
    const std::string path = concrete(pattern, e.node);
    for (const auto& caller : callers) {
      SCOPED_TRACE(method + " " + path + " as " + who(caller));
      const bool allowed = e.need == Role::None || (caller && allows(*caller, e.need));
      HttpReply r = ws ? rig.as(caller, method, path, {}, kUpgrade) : rig.as(caller, method, path, e.body, e.headers);
      if (allowed) {
        if (ws)
          EXPECT_EQ(r.status, 101) << r.body;
        else
          EXPECT_TRUE(r.status >= 200 && r.status < 300) << r.status << " " << r.body;
      } else if (!caller) {
        EXPECT_EQ(r.status, 401) << r.body;
        EXPECT_TRUE(r.has_header("www-authenticate: bearer")) << r.head;
        EXPECT_EQ(r.content_type, "application/problem+json");
      } else {
        EXPECT_EQ(r.status, 403) << r.body;
        EXPECT_THAT(r.body, HasSubstr("needs " + std::string(to_string(e.need))));
      }
    }
  }
}

TEST(SecurityMatrix, BadTokensAndTheWebSocketQueryToken) {
  SecureRig rig;
  const std::string nodes = "/api/v1/networks/1/nodes";
  EXPECT_EQ(rig.request("GET", nodes, {}, {"Authorization: Bearer nope"}).status, 401);
  EXPECT_EQ(rig.request("GET", nodes, {}, {"Authorization: Basic dXNlcjpwYXNz"}).status, 401);
  // ?access_token= is for the WebSocket only (browsers cannot set its headers).
  EXPECT_EQ(rig.request("GET", nodes + "?access_token=viewer-secret", {}, {}).status, 401);
  EXPECT_EQ(rig.request("GET", "/api/v1/events?access_token=viewer-secret", {}, kUpgrade).status, 101);
  EXPECT_EQ(rig.request("GET", "/api/v1/events?access_token=wrong", {}, kUpgrade).status, 401);
  const auto log = rig.log_text();
  EXPECT_THAT(log, HasSubstr("audit: auth failure: anonymous@127.0.0.1: GET /api/v1/networks/1/nodes: 401 the bearer "
                             "token is not valid"));
  EXPECT_THAT(log, HasSubstr("audit: auth failure: anonymous@127.0.0.1: GET /api/v1/events: 401"));
  EXPECT_EQ(log.find("viewer-secret"), std::string::npos) << "a token must never reach the log";
}

TEST(SecurityMatrix, NmtResetsNeedAdminAndEveryWriteIsAudited) {
  SecureRig rig;
  const std::string nmt = "/api/v1/networks/1/nodes/5/nmt";
  auto r = rig.as(Role::Operator, "POST", nmt, R"({"command":"reset-node"})");
  EXPECT_EQ(r.status, 403) << r.body;
  EXPECT_THAT(r.body, HasSubstr("needs admin"));
  EXPECT_EQ(rig.as(Role::Operator, "POST", nmt, R"({"command":"reset-comm"})").status, 403);
  EXPECT_EQ(rig.as(Role::Operator, "POST", nmt, R"({"command":"stop"})").status, 200);
  EXPECT_EQ(rig.as(Role::Admin, "POST", nmt, R"({"command":"reset-comm"})").status, 200);
  EXPECT_EQ(rig.as(Role::Operator, "PUT", "/api/v1/networks/1/nodes/5/sdo/1017/0", R"({"value":1000})").status, 200);
  EXPECT_EQ(rig.as(Role::Viewer, "PUT", "/api/v1/networks/1/nodes/5/sdo/1017/0", R"({"value":900})").status, 403);
  EXPECT_EQ(rig.as(Role::Operator, "PUT", "/api/v1/networks/1/nodes/5/rpdo/1", R"({"raw":"0f00"})").status, 200);
  EXPECT_EQ(rig.as(Role::Operator, "POST", "/api/v1/networks/1/sync", R"({"counter":3})").status, 200);

  const auto log = rig.log_text();
  // UTC time, who, target, result on each line.
  EXPECT_THAT(log, HasSubstr("audit: auth failure: operator@127.0.0.1: NMT reset-node net 1 node 5: 403"));
  EXPECT_THAT(log, HasSubstr("audit: NMT stop by operator@127.0.0.1: net 1 node 5: sent"));
  EXPECT_THAT(log, HasSubstr("audit: NMT reset-comm by admin@127.0.0.1: net 1 node 5: sent"));
  EXPECT_THAT(log, HasSubstr("audit: SDO write by operator@127.0.0.1: net 1 node 5 1017h sub 0 = 1000: ok"));
  EXPECT_THAT(log, HasSubstr("audit: auth failure: viewer@127.0.0.1: PUT /api/v1/networks/1/nodes/5/sdo/1017/0: 403"));
  EXPECT_THAT(log, HasSubstr("audit: RPDO write by operator@127.0.0.1: net 1 node 5 RPDO1 = 0f00: sent"));
  EXPECT_THAT(log, HasSubstr("audit: SYNC by operator@127.0.0.1: net 1 counter 3: sent"));
  for (std::size_t p = log.find("audit:"); p != std::string::npos; p = log.find("audit:", p + 1)) {
    const auto line_start = log.rfind('\n', p) == std::string::npos ? 0 : log.rfind('\n', p) + 1;
    const auto line = log.substr(line_start, p - line_start);
    EXPECT_TRUE(line.size() >= 20 && line[4] == '-' && line.find('T') == 10 && line.find('Z') != std::string::npos)
        << "audit line without a UTC time stamp: " << line;
  }
}

// Requests that did not come through HTTP (MQTT) carry their token; the
// App checks it with the same roles.
TEST(SecurityMatrix, RequestsWithoutHttpUseTheirTokenAndTheSameRoles) {
  SecureRig rig;
  auto call = [&](core::Operation op, std::string token, std::string body, std::uint8_t node = 5) {
    auto d = ::test::mqtt_request(op, 1, node, body, token);
    d.request.caller.who = "mqtt";
    std::optional<Reply> got;
    rig.rig.app->requests().execute(std::move(d.request),
                                    [&, opts = d.options](core::Result r) { got = encode_result(r, opts); });
    EXPECT_TRUE(rig.run_until([&] { return got.has_value(); }));
    return got.value_or(Reply{0, {}, {}});
  };
  const std::string read = R"({"index":"1017","subIndex":0})";
  EXPECT_EQ(call(core::Operation::sdo_read, "", read).status, 401);  // requests-role none: a token is required
  EXPECT_EQ(call(core::Operation::sdo_read, "wrong", read).status, 401);
  EXPECT_EQ(call(core::Operation::sdo_read, "viewer-secret", read).status, 200);
  const std::string write = R"({"index":"1017","subIndex":0,"value":1000})";
  EXPECT_EQ(call(core::Operation::sdo_write, "viewer-secret", write).status, 403);
  EXPECT_EQ(call(core::Operation::sdo_write, "operator-secret", write).status, 200);
  EXPECT_EQ(call(core::Operation::nmt, "operator-secret", R"({"command":"reset-node"})", 0).status, 403);
  EXPECT_EQ(call(core::Operation::nmt, "admin-secret", R"({"command":"start"})", 0).status, 200);
  const auto log = rig.log_text();
  EXPECT_THAT(log, HasSubstr("audit: auth failure: mqtt: request to net 1 node 5: 401 the token is not valid"));
  EXPECT_THAT(log, HasSubstr("audit: auth failure: viewer@mqtt: SDO write net 1 node 5: 403"));
  EXPECT_THAT(log, HasSubstr("audit: SDO write by operator@mqtt: net 1 node 5 1017h sub 0 = 1000: ok"));
  EXPECT_THAT(log, HasSubstr("audit: NMT start by admin@mqtt: net 1 node 0: sent"));
}

TEST(SecurityMatrix, RateLimitPerClientAnswers429ButNotForPublicFiles) {
  SecureRig rig(2, 3);  // 2/s, bursts of 3
  int ok = 0, limited = 0;
  HttpReply last;
  for (int i = 0; i < 6; ++i) {
    last = rig.as(Role::Viewer, "GET", "/api/v1/gateway");
    (last.status == 200 ? ok : limited) += 1;
    if (last.status == 429) break;
  }
  EXPECT_GE(ok, 3);
  EXPECT_EQ(last.status, 429);
  EXPECT_TRUE(last.has_header("retry-after: 1")) << last.head;
  EXPECT_EQ(rig.as(std::nullopt, "GET", "/").status, 200);  // the dashboard still loads
  std::this_thread::sleep_for(600ms);                        // a token refills in 500 ms
  EXPECT_EQ(rig.as(Role::Viewer, "GET", "/api/v1/gateway").status, 200);
}

// Issue 12, item 12, over HTTP: a viewer filling its share of a silent
// node's SDO queue gets 429 with Retry-After and the reason, and does not
// lock the operator out of the node.
TEST(SecurityMatrix, OneCallerGetsOnlyItsShareOfANodesSdoQueue) {
  SecureRig rig;
  const std::string silent = "/api/v1/networks/1/nodes/42/sdo/1018/1?type=u32";  // no device: requests wait
  const std::vector<std::string> viewer = {"Authorization: Bearer " + kTokens.at(Role::Viewer)};
  std::vector<std::future<HttpReply>> replies;
  for (int i = 0; i < 9; ++i)
    replies.push_back(std::async(std::launch::async, test::fetch, rig.rig.port, "GET", silent, "", viewer));
  auto answered = [&] {
    return std::count_if(replies.begin(), replies.end(),
                         [](auto& f) { return !f.valid() || f.wait_for(0s) == std::future_status::ready; });
  };
  ASSERT_TRUE(rig.run_until([&] { return answered() == 1; })) << "the ninth is refused at once";
  HttpReply refused;
  for (auto& f : replies)
    if (f.wait_for(0s) == std::future_status::ready) refused = f.get();  // f is !valid() from here on
  EXPECT_EQ(refused.status, 429);
  EXPECT_TRUE(refused.has_header("retry-after: 1")) << refused.head;
  EXPECT_EQ(refused.content_type, "application/problem+json");
  EXPECT_THAT(refused.body, HasSubstr("token 'viewer' has 8 SDO requests waiting for node 42 already"));
  // The operator's request goes into the node's queue (counted as started).
  const auto before = rig.rig.app->counters().sdo_requests;
  auto op = std::async(std::launch::async, test::fetch, rig.rig.port, "GET", silent, "",
                       std::vector<std::string>{"Authorization: Bearer " + kTokens.at(Role::Operator)});
  EXPECT_TRUE(rig.run_until([&] { return rig.rig.app->counters().sdo_requests == before + 1; }));
  EXPECT_EQ(rig.rig.app->counters().sdo_share_refused, 1u);
  // Closing the connections ends the waiting clients.
  rig.rig.server->stop();
  rig.run_until([&] { return answered() == 9 && op.wait_for(0s) == std::future_status::ready; });
}

}  // namespace
}  // namespace gateway
