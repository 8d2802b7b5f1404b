// CAN frame -> MQTT publish, the whole gateway path (issue 5 benchmark):
// PDO frames of a CiA 402 drive (node 5, TPDO2: Statusword u16 + Modes of
// operation display i8, decoded with the EDS) go through canopen::Network,
// the event pipeline (state cache, history, one JSON + protobuf encoding)
// and the MQTT publisher (disk queue, its own MQTT client) to a real
// broker, until the broker has acknowledged every one.
//
// Prints the gateway's CPU time per event (user + system of the whole
// process, from getrusage) and events per second.
// Not a test: numbers for people (bench/README.md).
//
//   mqtt_path_bench URI EVENTS QUEUE_DIR [QOS]
#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <string>

#include <boost/asio/io_context.hpp>

#include "canopen/eds/eds.hpp"
#include "canopen/network.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "messages/event_encoder.hpp"
#include "log.hpp"
#include "pipeline/pipeline.hpp"
#include "mqtt/publisher.hpp"

namespace {

double cpu_seconds() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  auto tv = [](const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) / 1e6; };
  return tv(ru.ru_utime) + tv(ru.ru_stime);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: mqtt_path_bench URI EVENTS QUEUE_DIR [QOS]\n");
    return 2;
  }
  const std::string uri = argv[1];
  const auto events = std::stoull(argv[2]);
  const std::filesystem::path queue_dir = argv[3];
  const int qos = argc > 4 ? std::stoi(argv[4]) : 1;
  std::filesystem::remove_all(queue_dir);

  boost::asio::io_context io;
  gateway::Logger log(gateway::LogLevel::Warn);
  auto own = canopen::od::make_gateway_dictionary(127, {});
  auto desc = canopen::eds::load_device_description(CANOPEN_SOURCE_DIR "/deploy/eds/cia402-drive.eds", 5);

  gateway::mqtt::MqttConfig mc;
  mc.server_uri = uri;
  mc.client_id = "mqtt-path-bench";
  mc.gateway_id = "bench";
  mc.queue.dir = queue_dir;
  mc.qos.fill(static_cast<std::uint8_t>(qos));
  // As the gateway's default storage for that QoS: QoS 0 in memory while
  // connected (`outage`), QoS 1 through the disk queue.
  mc.storage.fill(qos == 0 ? gateway::mqtt::StorageMode::Outage : gateway::mqtt::StorageMode::Disk);
  mc.accept_requests = false;
  gateway::mqtt::MqttPublisher publisher(io, mc, log);

  gateway::StateCache cache;
  cache.add_network(1, "bench", false);
  // As the gateway encodes with MQTT in JSON and no WebSocket client asking
  // for protobuf: JSON only (CANOPEN_BENCH_PROTOBUF=1: protobuf as well).
  gateway::EncodeContext ctx{"bench"};
  ctx.protobuf = std::getenv("CANOPEN_BENCH_PROTOBUF") != nullptr;
  gateway::EventPipeline pipeline(
      [&ctx](std::uint32_t net, const canopen::Event& ev) { return gateway::encode_event(ev, net, ctx); }, cache);
  pipeline.add_consumer([&publisher](const gateway::EncodedEventPtr& ev) { publisher.publish(ev); });
  canopen::Network network(own, [](const canopen::can::Frame&) {},
                           [&pipeline](const canopen::Event& ev) { pipeline.on_event(1, ev); });
  network.add_node(5, desc.od);

  publisher.start();
  const auto connect_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!publisher.counters().connected && std::chrono::steady_clock::now() < connect_deadline)
    io.run_for(std::chrono::milliseconds(10));
  if (!publisher.counters().connected) {
    std::fprintf(stderr, "mqtt_path_bench: cannot connect to %s\n", uri.c_str());
    return 1;
  }
  const auto base_acked = publisher.counters().acked;
  const auto base_writes = publisher.counters().socket_writes;

  const double cpu0 = cpu_seconds();
  const auto t0 = std::chrono::steady_clock::now();
  canopen::can::Frame f = canopen::can::Frame::standard(0x285, {0x37, 0x06, 0x08});
  double cpu_feed = 0;
  for (std::uint64_t i = 0; i < events; ++i) {
    f.data[0] = static_cast<std::uint8_t>(i);
    f.data[1] = static_cast<std::uint8_t>(i >> 8);
    f.timestamp = canopen::can::Frame::Clock::now();
    network.on_frame(f, canopen::SteadyClock::now());
    if (i % 256 == 255) io.poll();  // let the publisher drain, as the loop would between batches
  }
  cpu_feed = cpu_seconds() - cpu0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (publisher.counters().acked - base_acked < events && std::chrono::steady_clock::now() < deadline)
    io.run_for(std::chrono::milliseconds(5));
  const auto t1 = std::chrono::steady_clock::now();
  const double cpu = cpu_seconds() - cpu0;
  const auto acked = publisher.counters().acked - base_acked;
  const auto writes = publisher.counters().socket_writes - base_writes;
  const double wall = std::chrono::duration<double>(t1 - t0).count();
  publisher.stop();
  std::printf("events %llu acked %llu qos %d\n", static_cast<unsigned long long>(events),
              static_cast<unsigned long long>(acked), qos);
  std::printf("gateway CPU per event (all threads, until acked): %.2f us\n", cpu / static_cast<double>(events) * 1e6);
  std::printf("of which frame -> queued (io thread, synchronous): %.2f us\n",
              cpu_feed / static_cast<double>(events) * 1e6);
  std::printf("events per second to the broker: %.0f\n", static_cast<double>(acked) / wall);
  std::printf("socket writes: %llu (%.1f events per write)\n", static_cast<unsigned long long>(writes),
              writes > 0 ? static_cast<double>(acked) / static_cast<double>(writes) : 0.0);
  return acked == events ? 0 : 1;
}
