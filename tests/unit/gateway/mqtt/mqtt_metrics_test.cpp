// The MQTT publisher's metrics as it registers them (mqtt/mqtt_metrics.hpp):
// the families /metrics has always had, read from the publisher at scrape
// time. No broker: the publisher is not started.
#include "mqtt/mqtt_metrics.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <filesystem>
#include <memory>
#include <string>

#include "log.hpp"

namespace gateway::mqtt {
namespace {

TEST(MqttMetrics, RegisteredFamiliesFollowThePublisherBuiltAfterRegistration) {
  const auto dir = std::filesystem::temp_directory_path() / ("mqtt-metrics-test." + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  boost::asio::io_context io;
  Logger log(LogLevel::Error);
  MqttConfig cfg;
  cfg.server_uri = "tcp://127.0.0.1:1";
  cfg.client_id = "metrics-test";
  cfg.gateway_id = "gw";
  cfg.queue.dir = dir;
  cfg.accept_requests = false;
  {
    // The slots as the owner holds them: registered before the publisher
    // exists (it is built at start), read at scrape time.
    std::unique_ptr<MqttPublisher> publisher;
    metrics::Registry r;
    register_metrics(r, publisher, {});  // no request front end
    const std::string before = r.render();
    EXPECT_NE(before.find("canopen_gateway_mqtt_enabled 1\n"), std::string::npos);
    EXPECT_NE(before.find("canopen_gateway_mqtt_messages_total{result=\"published\"} 0\n"), std::string::npos);

    publisher = std::make_unique<MqttPublisher>(io, cfg, log);
    publisher->publish(QueuedMessage{"canopen/gw/test", "1", 1, false});  // after registration: read at scrape
    io.poll();

    // What the MQTT families of /metrics hold for the same values.
    const auto m = to_metrics(*publisher);
    EXPECT_EQ(m.published, 1U);
    EXPECT_FALSE(m.connected);
    metrics::MqttMetrics same;
    same.published = m.published;
    same.queue_depth = m.queue_depth;
    same.queue_bytes = m.queue_bytes;
    same.storage_bytes = m.storage_bytes;
    same.storage_syncs = m.storage_syncs;
    same.dropped_by_reason = m.dropped_by_reason;
    metrics::Registry expected;
    metrics::register_mqtt(expected, [same] { return same; });
    const std::string text = r.render();
    EXPECT_EQ(text, expected.render());
    EXPECT_NE(text.find("canopen_gateway_mqtt_messages_total{result=\"published\"} 1\n"), std::string::npos);
    EXPECT_NE(text.find("canopen_gateway_mqtt_dropped_total{reason=\"storage_full\"} 0\n"), std::string::npos);
  }
  std::filesystem::remove_all(dir);
}

TEST(MqttMetrics, WithoutAPublisherOnlyEnabledZeroIsWritten) {
  metrics::Registry r;
  metrics::register_mqtt(r, {});
  EXPECT_EQ(r.render(),
            "# HELP canopen_gateway_mqtt_enabled 1 when MQTT publishing is configured.\n"
            "# TYPE canopen_gateway_mqtt_enabled gauge\ncanopen_gateway_mqtt_enabled 0\n");
}

}  // namespace
}  // namespace gateway::mqtt
