#include "app/composition.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/link_monitor.hpp"
#include "app/demo_devices.hpp"
#include "app/node_overlay.hpp"
#include "sim/asio_memory_bus.hpp"
#include "sim/simulator.hpp"

namespace gateway {

Composition::Composition() = default;
Composition::Composition(Composition&&) noexcept = default;
Composition& Composition::operator=(Composition&&) noexcept = default;
Composition::~Composition() = default;

namespace {

// How a node's settings name its description: a file, or on a simulated
// network the demo's built-in one. Throws canopen::eds::EdsError.
canopen::eds::DeviceDescription read_description(const NetworkConfig& cfg, const NodeConfig& node) {
  if (cfg.simulated && node.eds == kBuiltInEds) {
    try {
      return demo_description(node.id);
    } catch (const std::out_of_range&) {
      throw canopen::eds::EdsError(std::string(kBuiltInEds), 0,
                                   "no built-in description for node " + std::to_string(node.id));
    }
  }
  return canopen::eds::load_device_description(node.eds, node.id);
}

struct Loaded {
  std::map<std::uint8_t, canopen::eds::DeviceDescription> descriptions;
  std::vector<NodeConfig> file_nodes;               // before the overlay
  std::map<std::uint8_t, std::string> overlay;      // node -> state-dir file
};

// The nodes' EDS/DCF; the node list of a simulated network becomes the
// demo's, then the state-dir overlay applies (node_overlay.hpp). A bad
// file named by the configuration is a configuration error; a bad one from
// the overlay is logged and the node keeps the configuration's settings.
Loaded load_descriptions(NetworkConfig& cfg, std::uint32_t number, const std::string& label,
                         const std::string& state_dir, Logger& log) {
  Loaded out;
  if (cfg.simulated) cfg.nodes = demo_node_configs();
  out.file_nodes = cfg.nodes;
  out.overlay = apply_node_overlay(state_dir, number, cfg, label, log);
  auto load = [&](const NodeConfig& node) {
    auto desc = read_description(cfg, node);
    if (!desc.warnings.empty()) {
      log.info(label + " node " + std::to_string(node.id) + ": " + std::to_string(desc.warnings.size()) +
               " warning(s) reading " + node.eds + " (accepted; `canopen-eds check " + node.eds +
               "` lists them, as does --log-level debug)");
    }
    for (const auto& w : desc.warnings) log.debug(label + " node " + std::to_string(node.id) + " EDS: " + w);
    // A value the file gives but nobody can read: in a DCF that entry is not
    // written at boot, which the person who made the DCF must hear about.
    for (const auto& w : desc.values_left_out) log.warn(label + " node " + std::to_string(node.id) + " EDS: " + w);
    out.descriptions.emplace(node.id, std::move(desc));
  };
  for (std::size_t i = 0; i < cfg.nodes.size(); ++i) {
    const NodeConfig node = cfg.nodes[i];
    if (node.eds.empty()) continue;
    try {
      load(node);
    } catch (const canopen::eds::EdsError& e) {
      if (!out.overlay.contains(node.id)) throw ConfigError(e.what());
      log.error(label + ": " + e.what() + " (named by " + out.overlay[node.id] + "): node " +
                std::to_string(node.id) + " keeps the configuration file's settings");
      out.overlay.erase(node.id);
      auto file = std::find_if(out.file_nodes.begin(), out.file_nodes.end(),
                               [&](const NodeConfig& n) { return n.id == node.id; });
      if (file == out.file_nodes.end()) {
        cfg.nodes.erase(cfg.nodes.begin() + static_cast<std::ptrdiff_t>(i--));
        continue;
      }
      cfg.nodes[i] = *file;
      if (file->eds.empty()) continue;
      try {
        load(*file);
      } catch (const canopen::eds::EdsError& e2) {
        throw ConfigError(e2.what());
      }
    }
  }
  return out;
}

// The in-process bus of a simulated network: the gateway's end is the
// unit's channel, the simulated devices sit on the other end.
NetworkLink open_simulated(boost::asio::io_context& io, const NetworkConfig& cfg, const std::string& label,
                           Logger& log) {
  NetworkLink link;
  link.memory_bus = std::make_unique<canopen::sim::AsioMemoryBus>(io);
  link.memory_gateway = link.memory_bus->attach("gateway");
  link.memory_devices = link.memory_bus->attach("devices");
  link.channel = link.memory_gateway.get();
  canopen::sim::SimulatorOptions so;
  so.heartbeat = cfg.simulation.heartbeat;
  so.tpdo_period = cfg.simulation.tpdo_period;
  so.emcy_period = cfg.simulation.emcy_period;
  link.simulator = std::make_unique<canopen::sim::Simulator>(
      io, *link.memory_devices, so,
      [&log, label](std::string_view line) { log.debug(label + " simulator: " + std::string(line)); });
  // The demo's devices, whatever run-time configuration made of their settings.
  for (const auto& node : demo_node_configs()) link.simulator->add_node(node.id, demo_description(node.id));
  // One more that waits unconfigured for LSS (CiA 305): the demo of commissioning.
  link.simulator->add_unconfigured_node(demo_new_device_description);
  return link;
}

}  // namespace

Composition compose_networks(boost::asio::io_context& io, const Config& config, Logger& log) {
  Composition c;
  for (std::size_t i = 0; i < config.networks.size(); ++i) {
    const auto number = static_cast<std::uint32_t>(i + 1);
    NetworkConfig cfg = config.networks[i];
    const std::string label = "net " + std::to_string(number) + " " + (cfg.simulated ? std::string("demo") : cfg.interface);
    // Device descriptions first: a bad file is a configuration error.
    auto loaded = load_descriptions(cfg, number, label, config.state_dir, log);
    NetworkLink link;
    if (cfg.simulated) {
      link = open_simulated(io, cfg, label, log);
    } else {
      if (!c.monitor) c.monitor = canopen::socketcan::LinkMonitor::create(io);
      link.socket = canopen::socketcan::SocketCanChannel::open(io, cfg.interface, c.monitor);
      link.channel = link.socket.get();
    }
    const NetworkConfig net_cfg = cfg;
    auto unit = std::make_unique<NetworkUnit>(io, number, std::move(cfg), std::move(loaded.descriptions),
                                              std::move(link), log, config.source);
    unit->file_nodes = std::move(loaded.file_nodes);
    unit->overlay_files = std::move(loaded.overlay);
    unit->load_description = [net_cfg](const NodeConfig& node) { return read_description(net_cfg, node); };
    if (unit->channel->state() == canopen::can::BusState::Down) log.warn(unit->label + " is down; waiting for it to come up");
    c.units.push_back(std::move(unit));
  }
  return c;
}

}  // namespace gateway
