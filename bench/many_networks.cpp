// 16 CAN networks at full classic-CAN load through the whole gateway path
// (issue 14): can the gateway carry 16 buses of 1 Mbit/s on one core?
//
// Each network is a can::MemoryBus with two endpoints: the "devices" (8
// CiA 401 I/O modules, nodes 10..17, sending TPDO2 = 4 x INTEGER16 analog
// inputs, 8 data bytes, decoded with the shipped EDS's mapping) and the
// gateway's channel, whose frames go to a canopen::Network, the event
// pipeline (state cache, one JSON encoding) and the MQTT publisher at QoS 0
// (the default storage for QoS 0: memory while connected) to a real broker,
// all on one io_context with no threads, as in the gateway. In-memory
// channels, not SocketCAN: this measures our code on the host
// (docs: "measure speed on the host"); a real broker, not an in-process
// sink, because the publisher's socket writes and the kernel's loopback TCP
// work are part of what the gateway pays per event.
//
// Frames are fed in real time: a 1 ms timer puts RATE/1000 frames on each
// bus per tick (8 per bus at 8,000 frames/s, i.e. 128 per tick for 16
// buses); the gateway's channel gets each bus's frames as one batch, as a
// SocketCAN recvmmsg() would return them. Before that, the same feeding
// runs for a while with the gateway's channel discarding the frames, so the
// simulated devices' own cost can be subtracted.
//
// Prints CPU time (CLOCK_PROCESS_CPUTIME_ID: user + system of the whole
// process) per frame and per bus, and CPU seconds per wall second: below
// 1.0 means all buses fit on one core, and 1 - that is the room to spare.
// Not a test: numbers for people (bench/README.md).
//
//   many_networks_bench URI SECONDS [NETWORKS [FRAMES_PER_SECOND_PER_BUS]]
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include "canopen/can/memory_bus.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/network.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "messages/event_encoder.hpp"
#include "log.hpp"
#include "mqtt/publisher.hpp"
#include "pipeline/pipeline.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) / 1e9;
}

constexpr std::uint8_t kFirstNode = 10;
constexpr int kNodesPerBus = 8;

// One simulated bus: the devices' endpoint and the gateway's.
struct Bus {
  canopen::can::MemoryBus bus;
  std::unique_ptr<canopen::can::MemoryEndpoint> devices = bus.attach("devices");
  std::unique_ptr<canopen::can::MemoryEndpoint> gateway = bus.attach("gateway");
  std::unique_ptr<canopen::Network> network;
  std::uint64_t sent = 0;      // frames the devices put on the bus
  std::uint64_t received = 0;  // frames the gateway's channel got
};

// Puts `count` TPDO2 frames on the bus, round robin over the nodes, with
// changing analog values (so the state cache sees real updates).
void feed(Bus& b, std::uint64_t count) {
  for (std::uint64_t i = 0; i < count; ++i, ++b.sent) {
    const auto node = static_cast<std::uint8_t>(kFirstNode + b.sent % kNodesPerBus);
    const auto v = static_cast<std::uint16_t>(b.sent / kNodesPerBus);
    auto f = canopen::can::Frame::standard(
        0x280U + node, {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), 0x10, 0x00,
                        static_cast<std::uint8_t>(~v), 0x20, 0x00, 0x30});
    f.timestamp = canopen::can::Frame::Clock::now();
    b.devices->send(f);
  }
  b.bus.deliver();
}

struct Phase {
  double wall = 0, cpu = 0;
  std::uint64_t frames = 0;
};

// Feeds every bus at `rate` frames/s for `seconds`, in 1 ms ticks.
Phase run_fed(boost::asio::io_context& io, std::vector<std::unique_ptr<Bus>>& buses, double rate, double seconds,
              const std::function<void()>& per_tick) {
  boost::asio::steady_timer timer(io);
  const auto t0 = Clock::now();
  const auto end = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  std::vector<std::uint64_t> start(buses.size());
  for (std::size_t i = 0; i < buses.size(); ++i) start[i] = buses[i]->sent;
  const double cpu0 = process_cpu_seconds();
  std::uint64_t ticks = 0;
  bool finished = false;
  std::function<void()> tick = [&] {
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - t0).count();
    for (std::size_t i = 0; i < buses.size(); ++i) {
      const auto due = static_cast<std::uint64_t>(elapsed * rate);
      const auto done = buses[i]->sent - start[i];
      if (due > done) feed(*buses[i], due - done);
    }
    per_tick();
    if (now >= end) {
      finished = true;
      return;
    }
    ++ticks;
    timer.expires_at(t0 + std::chrono::milliseconds(ticks));
    timer.async_wait([&](const boost::system::error_code& ec) {
      if (!ec) tick();
    });
  };
  tick();
  // Not io.run(): the publisher's keep-alive timer never lets it return.
  while (!finished) io.run_one();
  Phase p;
  p.wall = std::chrono::duration<double>(Clock::now() - t0).count();
  p.cpu = process_cpu_seconds() - cpu0;
  for (std::size_t i = 0; i < buses.size(); ++i) p.frames += buses[i]->sent - start[i];
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: many_networks_bench URI SECONDS [NETWORKS [FRAMES_PER_SECOND_PER_BUS]]\n");
    return 2;
  }
  const std::string uri = argv[1];
  const double seconds = std::stod(argv[2]);
  const auto networks = static_cast<std::size_t>(argc > 3 ? std::stoul(argv[3]) : 16);
  const double rate = argc > 4 ? std::stod(argv[4]) : 8000.0;

  boost::asio::io_context io;
  gateway::Logger log(gateway::LogLevel::Warn);
  auto own = canopen::od::make_gateway_dictionary(127, {});
  std::vector<canopen::od::ObjectDictionary> descriptions;
  for (int n = 0; n < kNodesPerBus; ++n)
    descriptions.push_back(
        canopen::eds::load_device_description(CANOPEN_SOURCE_DIR "/deploy/eds/cia401-io-module.eds",
                                              static_cast<std::uint8_t>(kFirstNode + n))
            .od);

  gateway::mqtt::MqttConfig mc;
  mc.server_uri = uri;
  mc.client_id = "many-networks-bench";
  mc.gateway_id = "bench";
  mc.queue.dir = std::filesystem::temp_directory_path() / ("many-networks-bench." + std::to_string(getpid()));
  mc.qos.fill(0);
  mc.storage.fill(gateway::mqtt::StorageMode::Outage);  // the default for QoS 0
  mc.accept_requests = false;
  gateway::mqtt::MqttPublisher publisher(io, mc, log);

  gateway::StateCache cache;
  gateway::EncodeContext ctx{"bench"};  // MQTT in JSON, no WebSocket client: JSON only, as the gateway
  gateway::EventPipeline pipeline(
      [&ctx](std::uint32_t net, const canopen::Event& ev) { return gateway::encode_event(ev, net, ctx); }, cache);
  bool publish = false;  // off while the devices' own cost is measured
  std::uint64_t published_bytes = 0;  // the JSON payloads handed to the publisher
  pipeline.add_consumer([&](const gateway::EncodedEventPtr& ev) {
    if (publish) {
      published_bytes += ev->json.size();
      publisher.publish(ev);
    }
  });

  std::vector<std::unique_ptr<Bus>> buses;
  bool to_gateway = false;  // off: the gateway's channel drops what it receives
  for (std::size_t i = 0; i < networks; ++i) {
    auto b = std::make_unique<Bus>();
    const auto number = static_cast<std::uint32_t>(i + 1);
    cache.add_network(number, "can" + std::to_string(i), false);
    b->network = std::make_unique<canopen::Network>(
        own, [ep = b->gateway.get()](const canopen::can::Frame& f) { ep->send(f); },
        [&pipeline, number](const canopen::Event& ev) { pipeline.on_event(number, ev); });
    for (int n = 0; n < kNodesPerBus; ++n) {
      const auto problems = b->network->add_node(static_cast<std::uint8_t>(kFirstNode + n), descriptions[static_cast<std::size_t>(n)]);
      if (!problems.empty()) std::fprintf(stderr, "node %d: %s\n", kFirstNode + n, problems.front().c_str());
    }
    b->gateway->on_frames([bp = b.get(), &to_gateway](std::span<const canopen::can::Frame> frames) {
      bp->received += frames.size();
      if (!to_gateway) return;
      const auto now = canopen::SteadyClock::now();
      for (const auto& f : frames) bp->network->on_frame(f, now);
    });
    buses.push_back(std::move(b));
  }

  publisher.start();
  const auto connect_deadline = Clock::now() + std::chrono::seconds(10);
  while (!publisher.counters().connected && Clock::now() < connect_deadline) io.run_for(std::chrono::milliseconds(10));
  if (!publisher.counters().connected) {
    std::fprintf(stderr, "many_networks_bench: cannot connect to %s\n", uri.c_str());
    return 1;
  }

  // 1. The simulated devices alone (frames generated and delivered to the
  //    gateway's channel, which drops them): subtracted below.
  const double sim_seconds = std::max(1.0, seconds / 4);
  const Phase sim = run_fed(io, buses, rate, sim_seconds, [] {});

  // 2. The whole path; the io_context also runs the publisher between ticks.
  to_gateway = true;
  publish = true;
  const auto base = publisher.counters();
  std::uint64_t events0 = 0;
  for (const auto& [n, info] : cache.networks()) events0 += info.events;
  const Phase all = run_fed(io, buses, rate, seconds, [&] {
    const auto now = canopen::SteadyClock::now();
    for (auto& b : buses)
      if (now >= b->network->next_deadline()) b->network->on_time(now);
  });
  // Let the publisher write out what the last tick queued (counted).
  const double cpu_tail0 = process_cpu_seconds();
  const auto drain_deadline = Clock::now() + std::chrono::seconds(10);
  while (publisher.counters().acked - base.acked < publisher.counters().published - base.published &&
         Clock::now() < drain_deadline)
    io.run_for(std::chrono::milliseconds(2));
  const double cpu_tail = process_cpu_seconds() - cpu_tail0;
  const auto c = publisher.counters();
  std::uint64_t events = 0;
  for (const auto& [n, info] : cache.networks()) events += info.events;
  events -= events0;
  publisher.stop();
  std::filesystem::remove_all(mc.queue.dir);

  const double sim_cpu_per_frame = sim.cpu / static_cast<double>(sim.frames);
  const double frames = static_cast<double>(all.frames);
  const double gw_cpu = all.cpu + cpu_tail - sim_cpu_per_frame * frames;
  const double n = static_cast<double>(networks);
  std::printf("networks %zu, %.0f frames/s per bus (%.0f in all), %.1f s, %llu frames, %llu events\n", networks,
              rate, rate * n, all.wall, static_cast<unsigned long long>(all.frames),
              static_cast<unsigned long long>(events));
  std::printf("MQTT QoS 0: published %llu, sent %llu, dropped %llu, socket writes %llu (%.1f messages per write)\n",
              static_cast<unsigned long long>(c.published - base.published),
              static_cast<unsigned long long>(c.acked - base.acked),
              static_cast<unsigned long long>(c.dropped - base.dropped),
              static_cast<unsigned long long>(c.socket_writes - base.socket_writes),
              c.socket_writes > base.socket_writes
                  ? static_cast<double>(c.acked - base.acked) / static_cast<double>(c.socket_writes - base.socket_writes)
                  : 0.0);
  const auto& q = publisher.queue_counters();
  const auto& t = publisher.tier_counters();
  std::printf("queue: spilled to disk %llu, dropped queue_full %llu, memory_full %llu, storage_full %llu, "
              "backpressure %llu\n",
              static_cast<unsigned long long>(t.spilled + t.to_disk),
              static_cast<unsigned long long>(q.dropped_qos0 + q.dropped_qos1 + q.dropped_span),
              static_cast<unsigned long long>(t.dropped_memory),
              static_cast<unsigned long long>(q.dropped_full + t.dropped_spill),
              static_cast<unsigned long long>(t.dropped_backpressure));
  // Issue 27 item 4: storage writes per payload byte published (<= 0.1).
  const std::uint64_t payload_bytes = published_bytes;
  std::printf("storage: %llu bytes written for %llu payload bytes published (%.4f per byte)\n",
              static_cast<unsigned long long>(q.storage_bytes), static_cast<unsigned long long>(payload_bytes),
              payload_bytes > 0 ? static_cast<double>(q.storage_bytes) / static_cast<double>(payload_bytes) : 0.0);
  std::printf("achieved: %.0f frames/s in all (%.0f per bus)\n", frames / all.wall, frames / all.wall / n);
  std::printf("simulated devices alone: %.3f us CPU per frame (subtracted)\n", sim_cpu_per_frame * 1e6);
  std::printf("gateway CPU per frame: %.3f us\n", gw_cpu / frames * 1e6);
  std::printf("gateway CPU per bus: %.4f CPU s per wall s (%.2f%% of a core)\n", gw_cpu / all.wall / n,
              gw_cpu / all.wall / n * 100);
  std::printf("gateway CPU for all %zu buses: %.3f CPU s per wall s (%.1f%% of one core; %s)\n", networks,
              gw_cpu / all.wall, gw_cpu / all.wall * 100,
              gw_cpu / all.wall < 1.0 ? "fits on one core" : "does NOT fit on one core");
  std::printf("whole process incl. simulated devices: %.3f CPU s per wall s\n", (all.cpu + cpu_tail) / all.wall);
  // Messages dropped under backpressure (a broker slower than the buses,
  // QoS 0: the oldest go instead of flash writes) are the intended answer,
  // not a failure; any other drop is.
  const bool ok = c.dropped - base.dropped == t.dropped_backpressure && events == all.frames;
  if (!ok) std::printf("WARNING: events (%llu) != frames or messages dropped\n", static_cast<unsigned long long>(events));
  return ok ? 0 : 1;
}
