// canopen-gateway: opens the configured CAN networks and runs everything on
// one io_context. On each network the gateway is a CANopen device (NMT
// slave with boot-up and heartbeat, CiA 301 7.2.8/7.3; SDO server for its
// own object dictionary, 7.2.4) and watches the other nodes (NMT master's
// node tracking, EMCY consumer); it logs frames, node states, EMCYs and
// bus-state changes.
#include <csignal>
#include <cstdio>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include "canopen/eds/eds.hpp"
#include "canopen/network.hpp"
#include "canopen/nmt/slave.hpp"
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

// "node 5 TPDO1 6041h/00 Statusword=7 ..." for a decoded PDO; raw hex for an
// unclaimed one or when the mapping did not fit.
std::string pdo_text(const canopen::PdoEvent& ev) {
  char buf[48];
  std::string s;
  if (ev.node == 0) {
    std::snprintf(buf, sizeof buf, "unclaimed PDO %03Xh", static_cast<unsigned>(ev.cob_id));
    s = buf;
  } else {
    s = "node " + std::to_string(ev.node) + " TPDO" + std::to_string(ev.number);
  }
  for (const auto& v : ev.values) {
    std::snprintf(buf, sizeof buf, " %04Xh/%02X ", static_cast<unsigned>(v.index), static_cast<unsigned>(v.sub));
    s += buf + v.name + "=" + canopen::format_value(v.value);
  }
  if (ev.values.empty() || ev.error) {
    s += " raw ";
    for (auto b : ev.raw) {
      std::snprintf(buf, sizeof buf, "%02X", static_cast<unsigned>(b));
      s += buf;
    }
  }
  if (ev.error) s += " (" + *ev.error + ")";
  return s;
}

int run(const gateway::CliOptions& opts) {
  gateway::Logger log(opts.log_level.value_or(gateway::LogLevel::Info));

  // Device descriptions of the remote nodes, loaded before anything opens so
  // a bad file is a configuration error (exit 2) naming file and line.
  std::vector<std::pair<std::uint8_t, canopen::od::ObjectDictionary>> remote_nodes;
  for (const auto& e : opts.eds) {
    const auto node = static_cast<std::uint8_t>(e.node);
    try {
      auto desc = canopen::eds::load_device_description(e.file, node);
      for (const auto& w : desc.warnings) log.debug("node " + std::to_string(node) + " EDS: " + w);
      remote_nodes.emplace_back(node, std::move(desc.od));
    } catch (const canopen::eds::EdsError& err) {
      print_error(err.what());
      return kExitUsage;
    }
  }

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
  std::deque<canopen::nmt::NmtSlave> nmt_slaves;
  std::deque<canopen::Network> networks;
  std::deque<canopen::socketcan::ServiceDriver> drivers;

  for (std::size_t i = 0; i < channels.size(); ++i) {
    auto& ch = *channels[i];
    const std::string prefix = "net " + std::to_string(i + 1) + " " + std::string(ch.name());
    auto& od = dictionaries.emplace_back(
        canopen::od::make_gateway_dictionary(static_cast<std::uint8_t>(opts.node_id.value_or(127)), identity));
    canopen::sdo::ServerConfig sdo_cfg;
    sdo_cfg.node_id = static_cast<std::uint8_t>(opts.node_id.value_or(127));
    auto& server = sdo_servers.emplace_back(od, sdo_cfg, [&ch](const canopen::can::Frame& f) { ch.send(f); });
    auto sink = [&ch](const canopen::can::Frame& f) { ch.send(f); };
    auto& slave = nmt_slaves.emplace_back(
        od, static_cast<std::uint8_t>(opts.node_id.value_or(127)), sink,
        canopen::nmt::SlaveCallbacks{
            {}, {},
            [&log, prefix](canopen::NmtState now_state, canopen::NmtState before) {
              log.info(prefix + " own node " + std::string(canopen::to_string(before)) + " -> " +
                       std::string(canopen::to_string(now_state)));
              log.flush();
            },
            {}});
    // The other nodes: one numbered event stream per network (seq, timestamp).
    auto& network = networks.emplace_back(od, sink, [&log, prefix](const canopen::Event& ev) {
      if (const auto* s = std::get_if<canopen::NodeStateEvent>(&ev.body)) {
        static constexpr const char* kCause[] = {"boot-up", "heartbeat", "node guarding", "lost", "recovered"};
        std::string msg = prefix + " node " + std::to_string(s->node) + " " +
                          (s->state ? std::string(canopen::to_string(*s->state)) : std::string("lost")) + " (" +
                          kCause[static_cast<int>(s->cause)] + ")";
        log.log(s->cause == canopen::NodeStateEvent::Cause::Lost ? gateway::LogLevel::Warn : gateway::LogLevel::Info,
                msg);
        log.flush();  // may come from a timer (lost), not only from a frame batch
      } else if (const auto* h = std::get_if<canopen::HeartbeatEvent>(&ev.body)) {
        if (log.enabled(gateway::LogLevel::Trace))
          log.trace(prefix + " node " + std::to_string(h->node) + " heartbeat " +
                    std::string(canopen::to_string(h->state)));
      } else if (const auto* e = std::get_if<canopen::EmcyEvent>(&ev.body)) {
        char code[32];
        std::snprintf(code, sizeof code, "%04Xh, error register %02Xh", e->error_code, e->error_register);
        log.warn(prefix + " node " + std::to_string(e->node) + " EMCY " + code + ": " + e->description);
      } else if (const auto* p = std::get_if<canopen::PdoEvent>(&ev.body)) {
        // Unclaimed PDOs are only bus traffic nobody described; decoded ones are the point.
        const auto level = p->node == 0 ? gateway::LogLevel::Debug
                           : p->error   ? gateway::LogLevel::Warn
                                        : gateway::LogLevel::Info;
        if (log.enabled(level)) log.log(level, prefix + " " + pdo_text(*p));
      }
    });
    for (const auto& [node, dict] : remote_nodes) {
      for (const auto& problem : network.add_node(node, dict))
        log.warn(prefix + " node " + std::to_string(node) + " PDO: " + problem);
    }
    auto& driver = drivers.emplace_back(io, ch);
    driver.add(server);
    driver.add(slave);
    driver.add(network);
    // Boot-up message (7.2.8.3.3) and, once 1017h is set, heartbeats.
    slave.start(canopen::SteadyClock::now());
    driver.poke();
    // A write to 1016h (e.g. over SDO) changes which heartbeats are consumed.
    od.observe(0x1016, [&log, prefix, &network, &driver](std::uint8_t) {
      network.configure_heartbeat_consumers();
      driver.poke();
      log.info(prefix + " heartbeat consumers reconfigured from 1016h");
    });
    driver.on_frames([&log, prefix](std::span<const canopen::can::Frame> frames) {
      if (log.enabled(gateway::LogLevel::Debug)) {
        for (const auto& f : frames) log.debug(prefix + " rx " + canopen::can::to_string(f));
      }
      log.flush();
    });
    ch.on_bus_event([&log, prefix, &network](const canopen::can::BusEvent& ev) {
      network.report(ev);  // bus changes are part of the network's event sequence
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
  }
  log.info("canopen-gateway started on " + std::to_string(channels.size()) + " network(s), node-ID " +
           std::to_string(opts.node_id.value_or(127)));
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
