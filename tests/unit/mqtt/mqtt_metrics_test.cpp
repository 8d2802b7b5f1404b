// The MQTT publisher's metrics as it registers them (mqtt/mqtt_metrics.hpp):
// the families /metrics has always had, read from the publisher at scrape
// time. No broker: the publisher is not started.
#include "mqtt/mqtt_metrics.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <filesystem>
#include <string>

#include "log.hpp"

namespace gateway::mqtt {
namespace {

TEST(MqttMetrics, RegisteredFamiliesMatchTheSnapshotsAndFollowThePublisher) {
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
    MqttPublisher publisher(io, cfg, log);
    metrics::Registry r;
    register_metrics(r, publisher);
    publisher.publish(QueuedMessage{"canopen/gw/test", "1", 1, false});  // after registration: read at scrape
    io.poll();

    metrics::MetricsSnapshot s;
    s.mqtt_enabled = true;
    const auto m = to_metrics(publisher);
    EXPECT_EQ(m.published, 1U);
    EXPECT_FALSE(m.connected);
    s.mqtt_published = m.published;
    s.mqtt_queue_depth = m.queue_depth;
    s.mqtt_queue_bytes = m.queue_bytes;
    s.mqtt_storage_bytes = m.storage_bytes;
    s.mqtt_storage_syncs = m.storage_syncs;
    s.mqtt_dropped_by_reason = m.dropped_by_reason;
    const std::string all = metrics::render_metrics(s);
    const auto begin = all.find("# HELP canopen_gateway_mqtt_enabled");
    const auto end = all.find("# HELP canopen_gateway_websocket_clients");
    const std::string text = r.render();
    EXPECT_EQ(text, all.substr(begin, end - begin));
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
