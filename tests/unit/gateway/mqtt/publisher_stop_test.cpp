// MqttPublisher::stop() with a farewell (issue 12 item 13), against a real
// mosquitto: what a subscriber that comes after a clean stop finds retained,
// and that the last messages overtake nothing published before them.
#include "mqtt/publisher.hpp"

#include <gtest/gtest.h>

#include "mqtt_support.hpp"

using namespace mqtt_test;
using gateway::EncodedEvent;
using gateway::EventKind;
using gateway::mqtt::MqttConfig;
using gateway::mqtt::MqttPublisher;
using gateway::mqtt::QueuedMessage;

namespace {

constexpr const char* kGw = "gw1";
const std::string kState = "canopen/gw1/1/5/state";

class PublisherStopTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
    broker_.emplace(true);  // persistence: retained messages survive a broker restart
    ASSERT_TRUE(broker_->start()) << broker_->log();
  }
  void TearDown() override {
    if (pub_) io_.call([&] { pub_.reset(); });
  }

  MqttConfig config() {
    MqttConfig c;
    c.server_uri = broker_->uri();
    c.client_id = "gateway-under-test";
    c.gateway_id = kGw;
    c.queue.dir = dir_.path() / "q";
    c.reconnect_min = 100ms;
    c.reconnect_max = 300ms;
    return c;
  }
  void start_publisher() {
    io_.call([&] {
      pub_ = std::make_unique<MqttPublisher>(io_.io(), config(), log_);
      pub_->start();
    });
  }
  bool connected() {
    return io_.call([&] { return pub_->counters().connected; });
  }
  // Published and acknowledged by the broker.
  void publish_acked(const QueuedMessage& m) {
    const auto before = io_.call([&] { return pub_->counters().acked; });
    io_.call([&] { pub_->publish(m); });
    ASSERT_TRUE(eventually([&] { return io_.call([&] { return pub_->counters().acked; }) > before; }));
  }
  static MqttPublisher::Farewell farewell() {
    MqttPublisher::Farewell f;
    f.messages.push_back({kState, "", 1, true});  // deletes the retained state
    f.offline_payload = R"({"state":"offline","at":"stop"})";
    return f;
  }
  // What a subscriber connecting now finds retained under canopen/gw1/#.
  std::vector<::mqtt::const_message_ptr> retained_now() {
    Subscriber late(broker_->uri(), "late", {"canopen/gw1/#"}, {});
    EXPECT_TRUE(late.connect());
    EXPECT_TRUE(late.wait_topic("canopen/gw1/status", 5s));
    std::this_thread::sleep_for(200ms);  // the rest of the retained batch
    return late.messages();
  }

  TempDir dir_;
  std::optional<Broker> broker_;
  gateway::Logger log_{gateway::LogLevel::Error};
  IoThread io_;
  std::unique_ptr<MqttPublisher> pub_;
};

TEST_F(PublisherStopTest, FarewellDeletesRetainedTopicsAndTheOfflineStatusIsTheStopTimeOne) {
  start_publisher();
  ASSERT_TRUE(eventually([&] { return connected(); })) << broker_->log();
  publish_acked({kState, R"({"state":"operational"})", 1, true});

  io_.call([&] {
    pub_->stop(2s, farewell());
    return 0;
  });
  const auto msgs = retained_now();
  for (const auto& m : msgs) EXPECT_NE(m->get_topic(), kState) << "still retained: " << m->get_payload_str();
  ASSERT_EQ(msgs.size(), 1U);
  EXPECT_EQ(msgs[0]->get_payload_str(), farewell().offline_payload) << "not the Will's payload";
}

// Messages published in the same io turn as stop() (not yet sent) still go
// out, before the farewell: a consumer sees them in order, the last one last.
TEST_F(PublisherStopTest, MessagesPublishedJustBeforeStopGoOutFirst) {
  start_publisher();
  ASSERT_TRUE(eventually([&] { return connected(); })) << broker_->log();
  Subscriber sub(broker_->uri(), "sub", {"canopen/gw1/1/#"}, {});
  ASSERT_TRUE(sub.connect());
  constexpr int kCount = 10;
  io_.call([&] {
    for (int i = 0; i < kCount; ++i) pub_->publish(QueuedMessage{"canopen/gw1/1/bus", std::to_string(i), 1, true});
    pub_->stop(2s, farewell());
    return 0;
  });
  ASSERT_TRUE(sub.wait_count(kCount + 1, 5s)) << sub.messages().size() << " messages";
  const auto msgs = sub.messages();
  for (int i = 0; i < kCount; ++i) EXPECT_EQ(msgs[static_cast<std::size_t>(i)]->get_payload_str(), std::to_string(i));
  EXPECT_EQ(msgs[kCount]->get_topic(), kState);
  EXPECT_EQ(msgs[kCount]->get_payload_str(), "") << "the farewell comes after them";
}

// Stopped while the broker is away: the farewell cannot be sent, so it is
// queued; the next run (same queue) delivers it once connected.
TEST_F(PublisherStopTest, AFarewellThatCannotBeSentIsDeliveredByTheNextRun) {
  start_publisher();
  ASSERT_TRUE(eventually([&] { return connected(); })) << broker_->log();
  publish_acked({kState, R"({"state":"operational"})", 1, true});
  broker_->stop();
  ASSERT_TRUE(eventually([&] { return !connected(); }));
  io_.call([&] {
    pub_->stop(2s, farewell());
    pub_.reset();
    return 0;
  });

  ASSERT_TRUE(broker_->start()) << broker_->log();
  {
    Subscriber before(broker_->uri(), "before", {kState}, {});
    ASSERT_TRUE(before.connect());
    ASSERT_TRUE(before.wait_topic(kState, 5s)) << "the retained state survived the broker restart";
  }
  start_publisher();
  ASSERT_TRUE(eventually([&] { return connected() && io_.call([&] { return pub_->counters().queue_depth; }) == 0; }));
  for (const auto& m : retained_now()) EXPECT_NE(m->get_topic(), kState) << "still retained: " << m->get_payload_str();
}

}  // namespace
