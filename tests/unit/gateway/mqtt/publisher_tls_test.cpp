// MqttPublisher with a user name and password over TLS (issue 6: "TLS and
// credentials for MQTT"), against a real mosquitto whose only listener is
// TLS with a password file; the certificate is made for the test with
// openssl. (Server verification against the wrong CA: publisher_test.cpp.)
#include <gtest/gtest.h>

#include <cstdlib>

#include "mqtt/publisher.hpp"
#include "mqtt_support.hpp"
#include "support/memory_log.hpp"

using namespace mqtt_test;
using gateway::mqtt::MqttConfig;
using gateway::mqtt::MqttPublisher;

namespace {

class MqttTlsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
    broker_.extra_conf = tls_password_conf(dir_.path().string(), "gateway", "s3cret");
    ASSERT_FALSE(broker_.extra_conf.empty()) << "openssl or mosquitto_passwd failed";
    broker_.allow_anonymous = false;
    ASSERT_TRUE(broker_.start()) << broker_.log();
  }
  void TearDown() override {
    if (pub_) io_.call([&] { pub_.reset(); });
  }

  MqttConfig config() {
    MqttConfig c;
    c.server_uri = "mqtts://127.0.0.1:" + std::to_string(broker_.port());
    c.client_id = "gateway-tls";
    c.gateway_id = "gwtls";
    c.username = "gateway";
    c.password = "s3cret";
    c.ca_file = (dir_.path() / "cert.pem").string();
    c.queue.dir = dir_.path() / "q";
    c.reconnect_min = 100ms;
    c.reconnect_max = 300ms;
    return c;
  }
  void start(MqttConfig c) {
    io_.call([&] {
      pub_ = std::make_unique<MqttPublisher>(io_.io(), c, log_);
      pub_->start();
    });
  }
  MqttPublisher::Counters counters() {
    return io_.call([&] { return pub_->counters(); });
  }

  TempDir dir_;
  Broker broker_;
  MemoryLog log_text_;  // warnings: the refusal a test waits for
  gateway::Logger log_{gateway::LogLevel::Warn, log_text_.file};
  IoThread io_;
  std::unique_ptr<MqttPublisher> pub_;
};

TEST_F(MqttTlsTest, ConnectsOverTlsWithPasswordAndDelivers) {
  start(config());
  ASSERT_TRUE(eventually([&] { return counters().connected; })) << broker_.log();
  auto ev = std::make_shared<gateway::EncodedEvent>();
  ev->kind = gateway::EventKind::Emcy;  // QoS 1 by default: acknowledged by the broker
  ev->topic = "canopen/gwtls/1/5/emcy";
  ev->json = R"({"errorCode":4096})";
  io_.call([&] { pub_->publish(ev); });
  EXPECT_TRUE(eventually([&] { return counters().acked >= 1; })) << broker_.log();
}

TEST_F(MqttTlsTest, WrongPasswordNeverConnects) {
  auto bad_password = config();
  bad_password.password = "wrong";
  start(bad_password);
  // Waits for the broker's answer (logged once), not for a time; it never connected.
  EXPECT_TRUE(eventually([&] { return says_credentials_refused(io_.call([&] { return log_text_.text(); })); }, 10s))
      << io_.call([&] { return log_text_.text(); }) << broker_.log();
  EXPECT_FALSE(counters().connected);
  EXPECT_EQ(counters().connects, 0u);
}

}  // namespace
