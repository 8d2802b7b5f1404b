// The gateway process with MQTT on a real mosquitto (skipped without it),
// seen by a subscriber that comes later: what is retained on the broker.
#include <gtest/gtest.h>

#include <boost/json.hpp>
#include <memory>

#include "app.hpp"
#include "unit/mqtt/mqtt_support.hpp"

namespace gateway {
namespace {

using namespace mqtt_test;

// api-contract "MQTT topics": canopen/<gw>/<net>/bus is retained; it must be
// there from the start, not only once the bus state changes (the demo
// network's never does).
TEST(AppMqtt, BusTopicIsRetainedFromTheStartWithoutAStateChange) {
  if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
  Broker broker;
  ASSERT_TRUE(broker.start()) << broker.log();
  TempDir state;
  CliOptions cli;
  cli.demo = true;
  cli.gateway_id = "test";
  cli.mqtt_uri = broker.uri();
  Config config = merge(Config{}, cli);
  config.mqtt.queue_dir = (state.path() / "q").string();
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
      const auto c = app->mqtt_counters();
      return c && c->connected && c->acked > 0;
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

}  // namespace
}  // namespace gateway
