// EdgeClient with a user name and password over TLS (issue 15: "TLS and
// credentials as for the native session"), against a real mosquitto whose
// only listener is TLS with a password file; the certificate is made for
// the test with openssl. The broker's own log (log_type all) proves what it
// received: no subscriber could join this listener without the same setup.
#include <gtest/gtest.h>

#include <cstdlib>

#include "sparkplug/edge_client.hpp"
#include "support/memory_log.hpp"
#include "unit/gateway/mqtt/mqtt_support.hpp"

namespace gateway::sparkplug {
namespace {

using namespace std::chrono_literals;
using mqtt_test::eventually;

class EdgeClientTlsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!mqtt_test::have_mosquitto()) GTEST_SKIP() << "no mosquitto";
    const auto conf = mqtt_test::tls_password_conf(dir.path().string(), "edge", "s3cret");
    ASSERT_FALSE(conf.empty()) << "openssl or mosquitto_passwd failed";
    broker.allow_anonymous = false;
    broker.extra_conf = conf + "log_type all\n";
    ASSERT_TRUE(broker.start()) << broker.log();
  }
  void TearDown() override { io.call([&] { client.reset(); }); }

  EdgeClientConfig config() {
    EdgeClientConfig c;
    c.session = {"plant1", "gw1", ""};
    c.mqtt.server_uri = "mqtts://127.0.0.1:" + std::to_string(broker.port());
    c.mqtt.client_id = "edge-tls";
    c.mqtt.username = "edge";
    c.mqtt.password = "s3cret";
    c.mqtt.ca_file = (dir.path() / "cert.pem").string();
    c.mqtt.reconnect_min = 100ms;
    c.mqtt.reconnect_max = 300ms;
    c.state_dir = dir.path();
    return c;
  }
  void start(EdgeClientConfig c) {
    io.call([&] {
      client = std::make_unique<EdgeClient>(io.io(), std::move(c), log);
      client->start();
    });
  }
  bool connected() {
    return io.call([&] { return client->connected(); });
  }

  mqtt_test::TempDir dir;
  mqtt_test::Broker broker;
  MemoryLog log_text;  // warnings: the refusal a test waits for
  Logger log{LogLevel::Warn, log_text.file};
  mqtt_test::IoThread io;
  std::unique_ptr<EdgeClient> client;
};

TEST_F(EdgeClientTlsTest, ConnectsOverTlsWithPasswordAndTheBrokerGetsNbirthAndTheWill) {
  start(config());
  ASSERT_TRUE(eventually([&] { return connected(); }, 10s)) << broker.log();
  // The broker authenticated the user and took the NDEATH Will with the CONNECT.
  EXPECT_TRUE(eventually([&] {
    const auto l = broker.log();
    return l.find("u'edge'") != std::string::npos && l.find("Will message specified") != std::string::npos &&
           l.find("'spBv1.0/plant1/NBIRTH/gw1'") != std::string::npos;
  }, 10s)) << broker.log();
}

TEST_F(EdgeClientTlsTest, WrongPasswordNeverConnects) {
  auto bad = config();
  bad.mqtt.password = "wrong";
  start(bad);
  // Waits for the broker's answer (logged once), not for a time; it never connected.
  EXPECT_TRUE(eventually([&] { return mqtt_test::says_credentials_refused(io.call([&] { return log_text.text(); })); }, 10s))
      << io.call([&] { return log_text.text(); }) << broker.log();
  EXPECT_FALSE(connected());
  EXPECT_EQ(io.call([&] { return client->counters().connects; }), 0u);
}

}  // namespace
}  // namespace gateway::sparkplug
