// The gateway process with its Sparkplug B edge node on a real mosquitto
// (skipped without it): made by the composition root (add_sparkplug), owned
// by the App, which starts it after MQTT and stops it before the networks
// and the native session close.
#include <gtest/gtest.h>

#include <fstream>
#include <memory>

#include "app/app.hpp"
#include "app/front_ends.hpp"
#include "sparkplug/edge_node.hpp"
#include "unit/gateway/mqtt/mqtt_support.hpp"

namespace gateway {
namespace {

using namespace mqtt_test;

std::string file_text(const fs::path& p) {
  std::ifstream f(p);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Contract "Sparkplug B": --sparkplug G runs the edge node on mqtt's broker
// as edge node <gateway id>; bdSeq kept in state-dir goes up across runs
// (facts A.5); a clean stop publishes NDEATH (facts A.4.6) before the
// native session says the bus is down.
TEST(AppSparkplug, EdgeNodeRunsBesideMqttAndSaysNdeathFirstAtStop) {
  if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
  Broker broker;
  ASSERT_TRUE(broker.start()) << broker.log();
  TempDir state;
  CliOptions cli;
  cli.demo = true;
  cli.gateway_id = "test";
  cli.mqtt_uri = broker.uri();
  cli.sparkplug_group = "plant1";
  Config config = merge(Config{}, cli);
  config.state_dir = state.path().string();
  config.mqtt.queue.dir = state.path() / "q";
  Subscriber host(broker.uri(), "host", {"spBv1.0/#", "canopen/test/1/bus"}, {});
  ASSERT_TRUE(host.connect());
  Logger log(LogLevel::Error);

  for (int run = 0; run < 2; ++run) {
    SCOPED_TRACE(run);
    IoThread io;
    std::unique_ptr<App> app;
    const sparkplug::EdgeNode* node = nullptr;
    io.call([&] {
      app = std::make_unique<App>(io.io(), config, log);
      node = add_sparkplug(io.io(), *app, log);
      app->start();
      return 0;
    });
    ASSERT_TRUE(eventually([&] { return host.on_topic("spBv1.0/plant1/NBIRTH/test").size() == std::size_t(run + 1); }))
        << broker.log();
    io.call([&] {
      const auto* sp = node != nullptr ? &node->client() : nullptr;
      EXPECT_NE(sp, nullptr);
      if (sp == nullptr) return 0;
      EXPECT_TRUE(sp->connected());
      EXPECT_EQ(sp->config().mqtt.client_id, "canopen-gateway-test-spb");
      EXPECT_EQ(sp->edge().bd_seq(), run) << "one CONNECT per run, kept in state-dir";
      return 0;
    });
    EXPECT_EQ(file_text(state.path() / "sparkplug-bdseq"), std::to_string(run) + "\n");
    const auto before = host.messages().size();
    const auto deaths_before = host.on_topic("spBv1.0/plant1/NDEATH/test").size();
    io.call([&] {
      app->stop();
      return 0;
    });
    ASSERT_TRUE(eventually([&] { return host.on_topic("spBv1.0/plant1/NDEATH/test").size() > deaths_before; }));
    // The stop's NDEATH comes before the native bus `down` (the edge node
    // stops while the networks still run): a `down` follows the NDEATH.
    EXPECT_TRUE(eventually([&] {
      const auto all = host.messages();
      std::size_t i = before;
      while (i < all.size() && all[i]->get_topic() != "spBv1.0/plant1/NDEATH/test") ++i;
      for (; i < all.size(); ++i)
        if (all[i]->get_topic() == "canopen/test/1/bus" && all[i]->get_payload_str().find("\"down\"") != std::string::npos)
          return true;
      return false;
    }));
    io.call([&] {
      app.reset();
      return 0;
    });
  }
}

}  // namespace
}  // namespace gateway
