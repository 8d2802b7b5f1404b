// The gateway process with MQTT on a real mosquitto (skipped without it),
// seen by a subscriber that comes later: what is retained on the broker.
#include <gtest/gtest.h>

#include <boost/json.hpp>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>
#include <set>

#include "app/app.hpp"
#include "mqtt/publisher.hpp"
#include "unit/gateway/mqtt/mqtt_support.hpp"

namespace gateway {
namespace {

using namespace mqtt_test;

// "2026-11-22T06:05:39.572Z" (RFC 3339 UTC, 0, 3, 6 or 9 fraction digits).
std::chrono::system_clock::time_point parse_utc(const std::string& text) {
  std::tm tm{};
  int frac_at = 0;
  if (std::sscanf(text.c_str(), "%d-%d-%dT%d:%d:%d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour, &tm.tm_min,
                  &tm.tm_sec, &frac_at) != 6)
    return {};
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  auto t = std::chrono::system_clock::from_time_t(::timegm(&tm));
  std::int64_t nanos = 0;
  auto i = static_cast<std::size_t>(frac_at);
  if (i < text.size() && text[i] == '.') {
    int digits = 0;
    for (++i; i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])) != 0 && digits < 9; ++i, ++digits)
      nanos = nanos * 10 + (text[i] - '0');
    for (; digits < 9; ++digits) nanos *= 10;
  }
  return t + std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::nanoseconds(nanos));
}

// The demo network as gateway "test" on `broker`, its state in `state`.
Config demo_config(const Broker& broker, const TempDir& state) {
  CliOptions cli;
  cli.demo = true;
  cli.gateway_id = "test";
  cli.mqtt_uri = broker.uri();
  Config config = merge(Config{}, cli);
  config.state_dir = state.path().string();
  config.mqtt.queue.dir = state.path() / "q";
  return config;
}

// api-contract "MQTT topics": canopen/<gw>/<net>/bus is retained; it must be
// there from the start, not only once the bus state changes (the demo
// network's never does).
TEST(AppMqtt, BusTopicIsRetainedFromTheStartWithoutAStateChange) {
  if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
  Broker broker;
  ASSERT_TRUE(broker.start()) << broker.log();
  TempDir state;
  Config config = demo_config(broker, state);
  Logger log(LogLevel::Error);
  IoThread io;
  std::unique_ptr<App> app;
  io.call([&] {
    app = std::make_unique<App>(io.io(), config, log);
    app->start();
    return 0;
  });
  auto connected = [&] {
    return io.call([&] {
      const auto* p = app->mqtt_publisher();
      return p != nullptr && p->counters().connected && p->counters().acked > 0;
    });
  };
  ASSERT_TRUE(eventually(connected)) << broker.log();
  std::this_thread::sleep_for(300ms);  // the start's messages are at the broker

  Subscriber late(broker.uri(), "late", {"canopen/test/1/bus"}, {});
  ASSERT_TRUE(late.connect());
  ASSERT_TRUE(late.wait_topic("canopen/test/1/bus", 5s)) << "no retained bus state";
  const auto msgs = late.on_topic("canopen/test/1/bus");
  ASSERT_EQ(msgs.size(), 1U);
  EXPECT_TRUE(msgs[0]->is_retained());
  const auto json = boost::json::parse(msgs[0]->get_payload_str()).as_object();
  EXPECT_EQ(json.at("state").as_string(), "error-active");
  EXPECT_EQ(json.at("tec").to_number<int>(), 0);
  EXPECT_EQ(json.at("rec").to_number<int>(), 0);

  io.call([&] {
    app->stop();
    app.reset();
    return 0;
  });
}

// Issue 12 item 13: once the gateway has stopped cleanly, no retained
// message claims a node is running, the bus is `down`, and the offline
// status says when it went offline and after how long (not the Will's start
// time and uptime 0).
TEST(AppMqtt, AfterACleanStopNothingRetainedClaimsANodeRuns) {
  if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
  Broker broker;
  ASSERT_TRUE(broker.start()) << broker.log();
  TempDir state;
  Config config = demo_config(broker, state);
  Logger log(LogLevel::Error);
  IoThread io;
  std::unique_ptr<App> app;
  Subscriber early(broker.uri(), "early", {"canopen/test/#"}, {});
  ASSERT_TRUE(early.connect());
  io.call([&] {
    app = std::make_unique<App>(io.io(), config, log);
    app->start();
    return 0;
  });
  // The demo's nodes boot and are started: retained `operational` states.
  auto operational = [&] {
    for (const auto& m : early.messages()) {
      if (m->get_topic().ends_with("/state") && m->get_payload_str().find("\"operational\"") != std::string::npos)
        return true;
    }
    return false;
  };
  ASSERT_TRUE(eventually(operational)) << broker.log();
  const auto before_stop = std::chrono::system_clock::now();
  io.call([&] {
    app->stop();
    app.reset();
    return 0;
  });

  Subscriber late(broker.uri(), "late", {"canopen/test/#"}, {});
  ASSERT_TRUE(late.connect());
  ASSERT_TRUE(late.wait_topic("canopen/test/status", 5s));
  ASSERT_TRUE(late.wait_topic("canopen/test/1/bus", 5s));
  std::this_thread::sleep_for(200ms);  // the rest of the retained batch
  for (const auto& m : late.messages())
    EXPECT_FALSE(m->get_topic().ends_with("/state")) << m->get_topic() << " still retained: " << m->get_payload_str();

  const auto bus = boost::json::parse(late.on_topic("canopen/test/1/bus").back()->get_payload_str()).as_object();
  EXPECT_EQ(bus.at("state").as_string(), "down");
  const auto status = boost::json::parse(late.on_topic("canopen/test/status").back()->get_payload_str()).as_object();
  EXPECT_EQ(status.at("state").as_string(), "offline");
  EXPECT_GT(std::stoull(std::string(status.at("uptimeMs").as_string())), 0U) << "the real uptime";
  const std::string stamp(status.at("timestamp").as_string());
  EXPECT_GE(parse_utc(stamp), std::chrono::floor<std::chrono::milliseconds>(before_stop))
      << stamp << ": the stop time, not the start";

  // The first run's node states were seen before (so the absence above
  // is the deletion, not states that never came).
  std::set<std::string> deleted;
  for (const auto& m : early.messages())
    if (m->get_topic().ends_with("/state") && m->get_payload_str().empty()) deleted.insert(m->get_topic());
  EXPECT_TRUE(deleted.contains("canopen/test/1/5/state"));
}

// Issue 27 item 2 (contract "Brokers"): with mqtt.uri a list, the
// gateway's status view (GET /api/v1/gateway's "mqtt") and /metrics say
// which broker it is connected to; after the first goes, the second has
// the retained status and bus topics (published again on the new
// connection).
TEST(AppMqtt, StatusAndMetricsNameTheConnectedBrokerOfAList) {
  if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
  Broker first, second;
  ASSERT_TRUE(first.start()) << first.log();
  ASSERT_TRUE(second.start()) << second.log();
  TempDir state;
  Config config = demo_config(first, state);
  config.mqtt.standby_uris = {"mqtt://127.0.0.1:" + std::to_string(second.port())};
  config.mqtt.reconnect_min = std::chrono::milliseconds(100);
  Logger log(LogLevel::Error);
  IoThread io;
  std::unique_ptr<App> app;
  io.call([&] {
    app = std::make_unique<App>(io.io(), config, log);
    app->start();
    return 0;
  });
  auto status = [&] { return io.call([&] { return *app->status().mqtt(); }); };
  auto metrics = [&] { return io.call([&] { return app->metrics().render(); }); };
  auto series = [](const Broker& b, int v) {
    return "canopen_gateway_mqtt_broker_connected{uri=\"" + b.uri() + "\"} " + std::to_string(v) + "\n";
  };
  ASSERT_TRUE(eventually([&] { return status().connected; })) << first.log();
  auto s = status();
  EXPECT_EQ(s.broker, first.uri());
  EXPECT_EQ(s.mqtt_version, 5);
  EXPECT_EQ(s.brokers, (std::vector<std::string>{first.uri(), second.uri()})) << "normalized, in order";
  auto m = metrics();
  EXPECT_NE(m.find(series(first, 1)), std::string::npos) << m;
  EXPECT_NE(m.find(series(second, 0)), std::string::npos) << m;

  first.stop();
  ASSERT_TRUE(eventually([&] { return status().broker == second.uri(); }, 10s)) << second.log();
  m = metrics();
  EXPECT_NE(m.find(series(first, 0)), std::string::npos) << m;
  EXPECT_NE(m.find(series(second, 1)), std::string::npos) << m;
  EXPECT_EQ(status().reconnects, 1u);

  Subscriber late(second.uri(), "late", {"canopen/test/status", "canopen/test/1/bus"}, {});
  ASSERT_TRUE(late.connect());
  ASSERT_TRUE(late.wait_topic("canopen/test/status", 5s)) << "retained on the new broker";
  ASSERT_TRUE(late.wait_topic("canopen/test/1/bus", 5s));
  EXPECT_EQ(boost::json::parse(late.on_topic("canopen/test/status").back()->get_payload_str()).at("state").as_string(),
            "online");

  io.call([&] {
    app->stop();
    app.reset();
    return 0;
  });
}

}  // namespace
}  // namespace gateway
