// The pipeline's and the per-network metrics as their owners register them
// (gateway/pipeline/pipeline_metrics.hpp): the same families /metrics has
// always had, with values read at scrape time.
#include "pipeline_metrics.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "canopen/can/memory_bus.hpp"
#include "metrics.hpp"

namespace gateway {
namespace {

bool has_line(const std::string& text, const std::string& line) { return text.find(line + "\n") != std::string::npos; }

EncodedEventPtr encode(std::uint32_t net, const canopen::Event& ev) {
  auto e = std::make_shared<EncodedEvent>();
  e->network = net;
  e->seq = ev.seq;
  e->kind = std::holds_alternative<canopen::PdoEvent>(ev.body) ? EventKind::Tpdo : EventKind::State;
  return e;
}

canopen::Event heartbeat(std::uint64_t seq) {
  canopen::Event ev;
  ev.seq = seq;
  ev.body = canopen::HeartbeatEvent{5, canopen::NmtState::Operational};
  return ev;
}

TEST(PipelineMetrics, NetworksAndEventsAreRenderedAsMetricsSnapshotsWere) {
  StateCache cache;
  cache.add_network(1, "vcan0", false);
  cache.add_network(2, "sim", true);
  EventPipeline pipeline(encode, cache);
  canopen::can::MemoryBus bus;
  auto gateway_side = bus.attach("gateway");
  auto device = bus.attach("device");
  metrics::Registry r;
  metrics::register_network_families(r);
  register_network_metrics(r, cache, 1, [&] { return gateway_side.get(); });
  register_network_metrics(r, cache, 2, [] { return nullptr; });
  register_metrics(r, pipeline);

  // After registration: the scrape reads the values of now.
  gateway_side->send(canopen::can::Frame::standard(0x000, {0x01, 0x00}));
  gateway_side->send(canopen::can::Frame::standard(0x080, {}));
  device->send(canopen::can::Frame::standard(0x705, {0x05}));
  bus.deliver();
  pipeline.on_event(1, heartbeat(1));

  // What render_metrics() writes for the same values.
  metrics::NetworkMetrics one;
  one.network = 1;
  one.interface = "vcan0";
  one.bus_state = "error-active";
  one.tx_frames = 2;
  one.rx_frames = 1;
  one.events = 1;
  metrics::NetworkMetrics two;
  two.network = 2;
  two.interface = "demo";  // a simulated network
  metrics::MetricsSnapshot s;
  s.networks = {one, two};
  for (int k = 0; k <= static_cast<int>(EventKind::BootConfig); ++k)
    s.events_by_kind[std::string(to_string(static_cast<EventKind>(k)))] = 0;
  s.events_by_kind["state"] = 1;
  const std::string expected = metrics::render_metrics(s);
  const std::string text = r.render();
  const auto begin = expected.find("# HELP canopen_gateway_can_frames_total");
  const auto sdo = expected.find("# HELP canopen_gateway_sdo_requests_total");
  const auto events = expected.find("# HELP canopen_gateway_events_published_total");
  const auto mqtt = expected.find("# HELP canopen_gateway_mqtt_enabled");
  ASSERT_NE(begin, std::string::npos);
  EXPECT_EQ(text, expected.substr(begin, sdo - begin) + expected.substr(events, mqtt - events));
  EXPECT_TRUE(has_line(text, "canopen_gateway_can_frames_total{network=\"1\",interface=\"vcan0\",direction=\"tx\"} 2"));
  EXPECT_TRUE(has_line(text, "canopen_gateway_bus_state{network=\"2\",interface=\"demo\",state=\"error-active\"} 0"));
  EXPECT_TRUE(has_line(text, "canopen_gateway_events_published_total{kind=\"state\"} 1"));

  pipeline.on_event(1, heartbeat(2));  // a later scrape follows
  EXPECT_TRUE(has_line(r.render(), "canopen_gateway_network_events_total{network=\"1\",interface=\"vcan0\"} 2"));
}

}  // namespace
}  // namespace gateway
