// canopen-gateway: opens the configured CAN networks and runs everything on
// one io_context. On each network the gateway is a CANopen device: it sends
// its boot-up message (CiA 301 7.2.8.3.3) and serves its own object
// dictionary over SDO (7.2.4); it logs frames and bus-state changes.
#include <csignal>
#include <cstdio>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/sdo/server.hpp"
#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/service_driver.hpp"
#include "cli.hpp"
#include "log.hpp"

namespace {

constexpr int kExitUsage = 2;
constexpr int kExitCanUnavailable = 3;

void print_error(const std::string& msg) { std::fprintf(stderr, "canopen-gateway: error: %s\n", msg.c_str()); }

std::string stats_line(const canopen::can::Channel& ch) {
  const auto s = ch.stats();
  return std::string(ch.name()) + ": rx " + std::to_string(s.rx_frames) + " frames, tx " +
         std::to_string(s.tx_frames) + ", rx dropped " + std::to_string(s.rx_dropped) + ", tx dropped " +
         std::to_string(s.tx_dropped) + ", error frames " + std::to_string(s.error_frames) + ", reopens " +
         std::to_string(s.reopens);
}

int run(const gateway::CliOptions& opts) {
  gateway::Logger log(opts.log_level);
  boost::asio::io_context io;
  auto monitor = canopen::socketcan::LinkMonitor::create(io);
  std::vector<std::shared_ptr<canopen::socketcan::SocketCanChannel>> channels;

  for (const auto& iface : opts.can_interfaces) {
    try {
      channels.push_back(canopen::socketcan::SocketCanChannel::open(io, iface, monitor));
    } catch (const canopen::socketcan::CanUnavailable& e) {
      print_error(e.what());
      return kExitCanUnavailable;
    }
  }

  // Per network: the gateway's own dictionary, its SDO server, and the
  // driver that feeds them frames and time. Deques: addresses stay put.
  canopen::od::GatewayIdentity identity;
  identity.software_version = CANOPEN_GATEWAY_VERSION;
  std::deque<canopen::od::ObjectDictionary> dictionaries;
  std::deque<canopen::sdo::SdoServer> sdo_servers;
  std::deque<canopen::socketcan::ServiceDriver> drivers;

  for (std::size_t i = 0; i < channels.size(); ++i) {
    auto& ch = *channels[i];
    const std::string prefix = "net " + std::to_string(i + 1) + " " + std::string(ch.name());
    auto& od = dictionaries.emplace_back(
        canopen::od::make_gateway_dictionary(static_cast<std::uint8_t>(opts.node_id), identity));
    canopen::sdo::ServerConfig sdo_cfg;
    sdo_cfg.node_id = static_cast<std::uint8_t>(opts.node_id);
    auto& server = sdo_servers.emplace_back(od, sdo_cfg, [&ch](const canopen::can::Frame& f) { ch.send(f); });
    auto& driver = drivers.emplace_back(io, ch);
    driver.add(server);
    driver.on_frames([&log, prefix](std::span<const canopen::can::Frame> frames) {
      if (log.enabled(gateway::LogLevel::Debug)) {
        for (const auto& f : frames) log.debug(prefix + " rx " + canopen::can::to_string(f));
      }
      log.flush();
    });
    ch.on_bus_event([&log, prefix](const canopen::can::BusEvent& ev) {
      std::string msg = prefix + " bus " + std::string(canopen::can::to_string(ev.previous)) + " -> " +
                        std::string(canopen::can::to_string(ev.state)) + " (" +
                        std::string(canopen::can::to_string(ev.cause));
      if (ev.cause == canopen::can::BusEventCause::RxOverflow) msg += ", " + std::to_string(ev.dropped) + " lost";
      msg += ", tec " + std::to_string(ev.tx_error_counter) + ", rec " + std::to_string(ev.rx_error_counter) + ")";
      const bool bad = ev.state != canopen::can::BusState::ErrorActive ||
                       ev.cause == canopen::can::BusEventCause::RxOverflow;
      log.log(bad ? gateway::LogLevel::Warn : gateway::LogLevel::Info, msg);
      log.flush();  // rare and important: never left waiting in the buffer
    });
    if (ch.state() == canopen::can::BusState::Down) log.warn(prefix + " is down; waiting for it to come up");
    // Boot-up: COB-ID 700h + node-ID, one data byte 00h.
    const auto bootup = canopen::can::Frame::standard(0x700U + static_cast<unsigned>(opts.node_id), {0x00});
    ch.send(bootup);
    log.debug(prefix + " tx " + canopen::can::to_string(bootup));
  }
  log.info("canopen-gateway started on " + std::to_string(channels.size()) + " network(s), node-ID " +
           std::to_string(opts.node_id));
  log.flush();

  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int sig) {
    if (ec) return;
    log.info(std::string("received ") + (sig == SIGINT ? "SIGINT" : "SIGTERM") + ", shutting down");
    drivers.clear();
    for (auto& ch : channels) ch->close();
    monitor->stop();
  });
  io.run();
  for (auto& ch : channels) log.info(stats_line(*ch));
  log.info("stopped");
  log.flush();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  gateway::CliOptions opts;
  try {
    opts = gateway::parse_cli(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const gateway::UsageError& e) {
    print_error(e.what());
    return kExitUsage;
  }
  if (opts.help) {
    std::fputs(gateway::usage_text().c_str(), stdout);
    return 0;
  }
  if (opts.version) {
    std::puts("canopen-gateway " CANOPEN_GATEWAY_VERSION);
    return 0;
  }
  try {
    return run(opts);
  } catch (const std::exception& e) {
    print_error(e.what());
    return 1;
  }
}
