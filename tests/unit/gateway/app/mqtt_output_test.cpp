// The gateway's MQTT output (gateway/app/mqtt_output.hpp) without a broker:
// the heartbeat rate limit per node, the heartbeat switch, and what a clean
// stop sends last (the retained state topics deleted, the offline status).
// The whole path against a real mosquitto is app_mqtt_test.cpp.
#include "app/mqtt_output.hpp"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/json.hpp>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "unit/gateway/mqtt/mqtt_support.hpp"

namespace gateway {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

MqttConfig config(std::chrono::milliseconds heartbeat_min_interval, const mqtt_test::TempDir& dir) {
  MqttConfig c;
  c.enabled = true;
  c.server_uri = "tcp://127.0.0.1:1";  // nothing listens: start() only tries to connect
  c.client_id = "mqtt-output-test";
  c.queue.dir = dir.path() / "q";
  c.heartbeat_min_interval = heartbeat_min_interval;
  return c;
}

struct Rig {
  explicit Rig(MqttConfig c, const std::vector<MqttOutput::Node>& nodes = {})
      : out(io, std::move(c), "gw", log, MqttOutput::Status{"1.2.3", 9, {1, 2}, Clock::now() - 5s}, nodes) {}
  boost::asio::io_context io;
  Logger log{LogLevel::Error};
  MqttOutput out;
};

EncodedEventPtr event(EventKind kind, std::uint32_t network, std::uint8_t node, std::string topic) {
  auto e = std::make_shared<EncodedEvent>();
  e->kind = kind;
  e->network = network;
  e->node = node;
  e->topic = std::move(topic);
  e->json = "{}";
  return e;
}

// mqtt.heartbeat-min-interval: at most one heartbeat per node per interval,
// counted from the last one that went out; other nodes and networks have
// their own.
TEST(MqttOutput, HeartbeatRateLimitPerNode) {
  mqtt_test::TempDir dir;
  Rig rig(config(1000ms, dir));
  const auto t0 = Clock::now();
  EXPECT_TRUE(rig.out.heartbeat_due(1, 5, t0));
  EXPECT_FALSE(rig.out.heartbeat_due(1, 5, t0 + 500ms));
  EXPECT_TRUE(rig.out.heartbeat_due(1, 6, t0 + 500ms)) << "another node";
  EXPECT_TRUE(rig.out.heartbeat_due(2, 5, t0 + 500ms)) << "the same node-ID on another network";
  EXPECT_FALSE(rig.out.heartbeat_due(1, 5, t0 + 999ms));
  EXPECT_TRUE(rig.out.heartbeat_due(1, 5, t0 + 1000ms));
  EXPECT_FALSE(rig.out.heartbeat_due(1, 5, t0 + 1500ms)) << "counted from the last one sent, not the first";
  EXPECT_TRUE(rig.out.heartbeat_due(1, 5, t0 + 2000ms));
}

TEST(MqttOutput, WithoutAMinimumIntervalEveryHeartbeatIsDue) {
  mqtt_test::TempDir dir;
  Rig rig(config(0ms, dir));
  const auto t0 = Clock::now();
  EXPECT_TRUE(rig.out.heartbeat_due(1, 5, t0));
  EXPECT_TRUE(rig.out.heartbeat_due(1, 5, t0));
  EXPECT_TRUE(rig.out.heartbeat_due(1, 5, t0 + 1ms));
}

// What reaches the publisher: heartbeats within the limit (or none with
// mqtt.heartbeat off), every other event.
TEST(MqttOutput, HeartbeatsPassTheSwitchAndTheLimitOtherEventsAll) {
  mqtt_test::TempDir dir;
  Rig limited(config(1h, dir));
  limited.out.on_event(event(EventKind::Heartbeat, 1, 5, "canopen/gw/1/5/heartbeat"));  // before start: not sent
  EXPECT_EQ(limited.out.publisher(), nullptr);
  limited.out.start();
  ASSERT_NE(limited.out.publisher(), nullptr);
  limited.out.on_event(event(EventKind::Heartbeat, 1, 6, "canopen/gw/1/6/heartbeat"));
  limited.out.on_event(event(EventKind::Heartbeat, 1, 6, "canopen/gw/1/6/heartbeat"));  // within the hour
  limited.out.on_event(event(EventKind::Heartbeat, 1, 5, "canopen/gw/1/5/heartbeat"));  // within the hour too
  limited.out.on_event(event(EventKind::Tpdo, 1, 6, "canopen/gw/1/6/tpdo/1"));
  limited.out.on_event(event(EventKind::Tpdo, 1, 6, "canopen/gw/1/6/tpdo/1"));
  EXPECT_EQ(limited.out.publisher()->counters().published, 3U);
  limited.out.stop();

  mqtt_test::TempDir dir2;
  auto off = config(0ms, dir2);
  off.heartbeat = false;
  Rig silent(off);
  silent.out.start();
  silent.out.on_event(event(EventKind::Heartbeat, 1, 5, "canopen/gw/1/5/heartbeat"));
  silent.out.on_event(event(EventKind::Emcy, 1, 5, "canopen/gw/1/5/emcy"));
  EXPECT_EQ(silent.out.publisher()->counters().published, 1U);
  silent.out.stop();
}

// Issue 12 item 13: after a clean stop no retained message claims a node
// runs: every configured node's state topic and every state topic published
// in this run is deleted (empty, retained, at the state kind's QoS), and
// the offline status says when and after how long.
TEST(MqttOutput, FarewellDeletesEveryStateTopicAndSaysOffline) {
  mqtt_test::TempDir dir;
  auto c = config(0ms, dir);
  c.qos[EventKind::State] = 0;
  Rig rig(c, {{1, 5}, {1, 10}, {2, 5}});
  rig.out.on_event(event(EventKind::State, 1, 77, "canopen/gw/1/77/state"));  // an unconfigured node seen
  rig.out.on_event(event(EventKind::State, 1, 5, "canopen/gw/1/5/state"));    // configured: once
  rig.out.on_event(event(EventKind::Tpdo, 1, 6, "canopen/gw/1/6/tpdo/1"));    // not a state
  const auto last = rig.out.farewell();
  std::vector<std::string> topics;
  for (const auto& m : last.messages) {
    topics.push_back(m.topic);
    EXPECT_TRUE(m.payload.empty()) << m.topic;
    EXPECT_TRUE(m.retained) << m.topic;
    EXPECT_EQ(m.qos, 0) << m.topic;
  }
  EXPECT_EQ(topics, (std::vector<std::string>{"canopen/gw/1/10/state", "canopen/gw/1/5/state", "canopen/gw/1/77/state",
                                              "canopen/gw/2/5/state"}));
  const auto status = boost::json::parse(last.offline_payload).as_object();
  EXPECT_EQ(status.at("state").as_string(), "offline");
  EXPECT_EQ(status.at("version").as_string(), "1.2.3");
  EXPECT_EQ(status.at("gatewayId").as_string(), "gw");
  EXPECT_EQ(status.at("nodeId").to_number<int>(), 9);
  EXPECT_GE(std::stoull(std::string(status.at("uptimeMs").as_string())), 5000U) << "the uptime as of the stop";
  EXPECT_EQ(boost::json::parse(rig.out.status_payload(true)).as_object().at("state").as_string(), "online");
}

}  // namespace
}  // namespace gateway
