// Test helper for the kill -9 test: an MqttPublisher in its own process.
//
//   mqtt_publish_tool URI QUEUE_DIR GATEWAY_ID COUNT [RATE_PER_S [hold]]
//
// Publishes COUNT QoS 1 messages "0".."COUNT-1" to canopen/<gw>/test/seq at
// RATE_PER_S (0 = as fast as possible), prints "queued" once all are in the
// queue, then runs until the queue is empty and prints "drained" and exits 0
// (COUNT 0: just drain what the queue directory holds). With "hold" it
// keeps running after that (until killed). Exit 2 on timeout (60 s).
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>

#include "mqtt/publisher.hpp"

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s URI QUEUE_DIR GATEWAY_ID COUNT [RATE]\n", argv[0]);
    return 1;
  }
  const std::string gw = argv[3];
  const long count = std::strtol(argv[4], nullptr, 10);
  const long rate = argc > 5 ? std::strtol(argv[5], nullptr, 10) : 0;
  const bool hold = argc > 6 && std::string(argv[6]) == "hold";

  boost::asio::io_context io;
  gateway::Logger log(gateway::LogLevel::Warn);
  gateway::mqtt::MqttConfig cfg;
  cfg.server_uri = argv[1];
  cfg.client_id = "publish-tool-" + gw;
  cfg.gateway_id = gw;
  cfg.queue.dir = argv[2];
  cfg.reconnect_min = std::chrono::milliseconds(100);
  cfg.reconnect_max = std::chrono::milliseconds(500);
  cfg.accept_requests = false;
  gateway::mqtt::MqttPublisher pub(io, cfg, log);
  pub.start();

  long next = 0;
  bool queued_said = false;
  boost::asio::steady_timer tick(io);
  const auto start = std::chrono::steady_clock::now();
  std::function<void()> step = [&] {
    const auto elapsed = std::chrono::steady_clock::now() - start;
    long due = count;
    if (rate > 0)
      due = std::min<long>(count, static_cast<long>(
                                      std::chrono::duration_cast<std::chrono::milliseconds>(elapsed).count() * rate / 1000));
    for (; next < due; ++next)
      pub.publish(gateway::mqtt::QueuedMessage{"canopen/" + gw + "/test/seq", std::to_string(next), 1, false});
    // "queued" one tick after the last publish: the publisher writes what
    // it accepted to the queue's files within the io loop turn, not in
    // publish() itself (MqttPublisher's durability guarantee).
    static bool all_published = false;
    if (next == count && all_published && !queued_said) {
      queued_said = true;
      std::printf("queued\n");
      std::fflush(stdout);
    }
    if (next == count) all_published = true;
    static bool drained_said = false;
    if (next == count && !drained_said && pub.counters().queue_depth == 0 && pub.counters().connected) {
      drained_said = true;
      std::printf("drained\n");
      std::fflush(stdout);
    }
    if (drained_said && !hold) {
      pub.stop();
      io.stop();
      return;
    }
    if (!hold && elapsed > std::chrono::seconds(60)) {
      std::fprintf(stderr, "timeout\n");
      std::exit(2);
    }
    tick.expires_after(std::chrono::milliseconds(5));
    tick.async_wait([&](const boost::system::error_code&) { step(); });
  };
  step();
  io.run();
  return 0;
}
