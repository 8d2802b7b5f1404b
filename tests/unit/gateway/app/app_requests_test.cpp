// The request core's per-caller limits (issue 12, items 8 and 12), on the
// simulated demo network in-process: who may queue how much on a node, MQTT
// requests rate-limited per caller as HTTP ones are per address, and
// tokenless MQTT requests refused unless mqtt.requests-role says otherwise.
#include "app/app.hpp"
#include "messages/request_codec.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <optional>
#include <vector>

namespace gateway {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

const std::string kViewerToken = "viewer-secret";
const std::string kOperatorToken = "operator-secret";

struct Rig {
  explicit Rig(const std::function<void(Config&)>& configure = {}) {
    CliOptions cli;
    cli.demo = true;
    cli.gateway_id = "test";
    Config c = merge(Config{}, cli);
    if (configure) configure(c);
    log = std::make_unique<Logger>(LogLevel::Error);
    app = std::make_unique<App>(io, c, *log);
    app->start();
  }
  ~Rig() { app->stop(); }

  template <typename Pred>
  bool run_until(Pred pred, std::chrono::milliseconds limit = 10s) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!pred() && std::chrono::steady_clock::now() < end) io.run_for(10ms);
    return pred();
  }
  bool operational(std::uint8_t node) const {
    const auto* n = app->cache().node(1, node);
    return n != nullptr && n->state == canopen::NmtState::Operational;
  }

  // Hands a request to the App's request core and returns where its reply
  // will be (set at once for a refusal, later for an SDO transfer).
  std::shared_ptr<std::optional<Reply>> send(core::Request r) {
    auto out = std::make_shared<std::optional<Reply>>();
    app->requests().execute(std::move(r), [out](core::Result result) { *out = encode_result(result); });
    return out;
  }

  boost::asio::io_context io;
  std::unique_ptr<Logger> log;
  std::unique_ptr<App> app;
};

// An SDO read of 1018h sub 1 (the vendor-ID), typed so that nodes without an
// EDS are asked too.
core::Request read_request(std::uint8_t node) {
  core::Request r;
  r.network = 1;
  r.command = core::SdoRead{node, 0x1018, 1, canopen::DataType::Unsigned32};
  return r;
}

// As REST hands it over: the HTTP authorizer checked the caller.
core::Request from_http(core::Request r, std::string caller, Role role = Role::Viewer) {
  r.caller.transport = core::Transport::rest;
  r.caller.authenticated = true;
  r.caller.role = role;
  r.caller.who = caller;
  r.caller.key = std::move(caller);
  return r;
}

// As the MQTT unit hands it over: a token, or none.
core::Request from_mqtt(core::Request r, std::string token = {}) {
  r.caller.transport = core::Transport::mqtt;
  r.caller.token = std::move(token);
  return r;
}

void add_tokens(Config& c) {
  c.http.tokens.push_back({"viewer", Role::Viewer, auth::sha256_hex(kViewerToken)});
  c.http.tokens.push_back({"operator", Role::Operator, auth::sha256_hex(kOperatorToken)});
}

// Item 12: one caller (a viewer) filling a silent node's SDO queue locked
// everyone else out of that node (429) until its requests timed out. Now it
// gets its share and a 429 that says why; other callers still get in.
TEST(AppRequests, OneCallerFillsItsShareOfASilentNodesQueueOthersStillGetIn) {
  Rig rig;
  constexpr std::uint8_t kSilent = 42;  // no device answers: every request waits for its timeout
  const std::size_t share = auth::caller_share(canopen::sdo::ClientConfig{}.queue_limit);
  ASSERT_EQ(share, 8u);  // max(2, 32 / 4)
  std::vector<std::shared_ptr<std::optional<Reply>>> mine;
  for (std::size_t i = 0; i < share; ++i)
    mine.push_back(rig.send(from_http(read_request(kSilent), "address 10.0.0.7")));
  for (const auto& r : mine) EXPECT_FALSE(r->has_value()) << "queued, waiting for the silent node";
  const auto over = rig.send(from_http(read_request(kSilent), "address 10.0.0.7"));
  ASSERT_TRUE(over->has_value()) << "over its share: refused at once";
  EXPECT_EQ((*over)->status, 429);
  EXPECT_EQ((*over)->content_type, "application/problem+json");
  EXPECT_EQ((*over)->retry_after, 1);
  EXPECT_THAT((*over)->body, HasSubstr("address 10.0.0.7 has 8 SDO requests waiting for node 42 already, its share of "
                                       "the node's queue of 32"));
  // Everyone else is still queued: another address, a token holder, MQTT without a token.
  const auto other = rig.send(from_http(read_request(kSilent), "address 10.0.0.8"));
  const auto token = rig.send(from_http(read_request(kSilent), auth::token_caller("dashboard")));
  const auto mqtt = rig.send(from_mqtt(read_request(kSilent)));
  EXPECT_FALSE(other->has_value());
  EXPECT_FALSE(token->has_value());
  EXPECT_FALSE(mqtt->has_value());
  // The share is per node: the same caller still reaches the other nodes.
  const auto elsewhere = rig.send(from_http(read_request(43), "address 10.0.0.7"));
  EXPECT_FALSE(elsewhere->has_value());
  EXPECT_EQ(rig.app->counters().sdo_share_refused, 1u);
}

// The share is given back as requests are answered, and the callers
// sharing a node are all served.
TEST(AppRequests, SharesAreGivenBackAndEveryCallerIsServed) {
  Rig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  std::vector<std::shared_ptr<std::optional<Reply>>> mine;
  for (int i = 0; i < 8; ++i) mine.push_back(rig.send(from_http(read_request(5), "address 10.0.0.7")));
  EXPECT_EQ(rig.send(from_http(read_request(5), "address 10.0.0.7"))->value_or(Reply{}).status, 429);
  const auto other = rig.send(from_http(read_request(5), "address 10.0.0.8"));
  auto all_answered = [&] { return std::all_of(mine.begin(), mine.end(), [](const auto& r) { return r->has_value(); }); };
  ASSERT_TRUE(rig.run_until([&] { return other->has_value() && all_answered(); }));
  EXPECT_EQ((*other)->status, 200) << (*other)->body;
  for (const auto& r : mine) EXPECT_EQ((*r)->status, 200) << (*r)->body;
  // Answered: the caller has its whole share again.
  for (auto& r : mine) r = rig.send(from_http(read_request(5), "address 10.0.0.7"));
  for (const auto& r : mine) EXPECT_FALSE(r->has_value());
  ASSERT_TRUE(rig.run_until(all_answered));
  for (const auto& r : mine) EXPECT_EQ((*r)->status, 200) << (*r)->body;
}

// Item 12: MQTT requests are rate-limited as HTTP ones are (http.rate-limit),
// per MQTT caller: each token, and all tokenless requests together (bad
// tokens included, so a flood of them is limited before it is audited).
TEST(AppRequests, MqttRequestsAreRateLimitedPerCaller) {
  Rig rig([](Config& c) {
    add_tokens(c);
    c.mqtt.requests_role = Role::Viewer;
    c.http.rate_limit = 1;
    c.http.rate_burst = 3;
  });
  // The gateway's own node answers from its dictionary at once: no bus, no waiting.
  const core::Request own = read_request(127);
  int ok = 0, limited = 0;
  for (int i = 0; i < 5; ++i) {
    const auto r = rig.send(from_mqtt(own));
    ASSERT_TRUE(r->has_value());
    if ((*r)->status == 200) ++ok;
    if ((*r)->status == 429) {
      ++limited;
      EXPECT_THAT((*r)->body, HasSubstr("too many requests from MQTT requests without a token; slow down"));
      EXPECT_EQ((*r)->retry_after, 1);
    }
  }
  EXPECT_EQ(ok, 3) << "the burst";
  EXPECT_EQ(limited, 2);
  EXPECT_EQ(rig.send(from_mqtt(own, "not-a-token"))->value_or(Reply{}).status, 429) << "bad tokens share the bucket";
  // A token holder has its own bucket.
  for (int i = 0; i < 3; ++i) EXPECT_EQ(rig.send(from_mqtt(own, kViewerToken))->value_or(Reply{}).status, 200);
  EXPECT_EQ(rig.send(from_mqtt(own, kViewerToken))->value_or(Reply{}).status, 429);
  EXPECT_EQ(rig.send(from_mqtt(own, kOperatorToken))->value_or(Reply{}).status, 200);
  // REST requests were limited by the HTTP authorizer already; not again here.
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(rig.send(from_http(own, "address 10.0.0.7"))->value_or(Reply{}).status, 200);
  EXPECT_EQ(rig.app->counters().requests_rate_limited, 4u);
}

// Item 8: without mqtt.requests-role a request without a token is refused,
// also when no tokens are configured at all.
TEST(AppRequests, TokenlessMqttRequestsAreRefusedWithoutRequestsRole) {
  Rig rig([](Config& c) { c.mqtt.requests_role.reset(); });
  ASSERT_TRUE(rig.app->tokens().empty());
  const auto r = rig.send(from_mqtt(read_request(127)));
  ASSERT_TRUE(r->has_value());
  EXPECT_EQ((*r)->status, 401);
  EXPECT_THAT((*r)->body, HasSubstr("needs a token"));
}

}  // namespace
}  // namespace gateway
