// The pipeline's and the per-network metrics as their owners register them
// (gateway/pipeline/pipeline_metrics.hpp): the same families /metrics has
// always had, with values read at scrape time.
#include "pipeline/pipeline_metrics.hpp"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <string>

#include "canopen/can/memory_bus.hpp"
#include "metrics/metrics.hpp"

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

TEST(PipelineMetrics, NetworksAndEventsFollowTheChannelAndThePipeline) {
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

  // What the generic registrations write for the same values.
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
  std::map<std::string, std::uint64_t> by_kind;
  for (int k = 0; k <= static_cast<int>(kLastEventKind); ++k)
    by_kind[std::string(to_string(static_cast<EventKind>(k)))] = 0;
  by_kind["state"] = 1;
  metrics::Registry same;
  metrics::register_network_families(same);
  metrics::register_network(same, [one] { return one; });
  metrics::register_network(same, [two] { return two; });
  metrics::register_events_by_kind(same, [by_kind] { return by_kind; });
  const std::string text = r.render();
  EXPECT_EQ(text, same.render());
  EXPECT_TRUE(has_line(text, "canopen_gateway_can_frames_total{network=\"1\",interface=\"vcan0\",direction=\"tx\"} 2"));
  EXPECT_TRUE(has_line(text, "canopen_gateway_bus_state{network=\"2\",interface=\"demo\",state=\"error-active\"} 0"));
  EXPECT_TRUE(has_line(text, "canopen_gateway_events_published_total{kind=\"state\"} 1"));

  pipeline.on_event(1, heartbeat(2));  // a later scrape follows
  EXPECT_TRUE(has_line(r.render(), "canopen_gateway_network_events_total{network=\"1\",interface=\"vcan0\"} 2"));
}

}  // namespace
}  // namespace gateway
