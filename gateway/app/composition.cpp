#include "composition.hpp"

#include <string>
#include <utility>

#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/link_monitor.hpp"
#include "demo_devices.hpp"
#include "sim/asio_memory_bus.hpp"
#include "sim/simulator.hpp"

namespace gateway {

Composition::Composition() = default;
Composition::Composition(Composition&&) noexcept = default;
Composition& Composition::operator=(Composition&&) noexcept = default;
Composition::~Composition() = default;

namespace {

// The nodes' EDS/DCF (the demo's own for a simulated network); the node
// list of a simulated network becomes the demo's.
std::map<std::uint8_t, canopen::eds::DeviceDescription> load_descriptions(NetworkConfig& cfg, const std::string& label,
                                                                         Logger& log) {
  std::map<std::uint8_t, canopen::eds::DeviceDescription> out;
  if (cfg.simulated) cfg.nodes = demo_node_configs();
  for (const auto& node : cfg.nodes) {
    if (node.eds.empty() && !cfg.simulated) continue;
    try {
      auto desc = cfg.simulated ? demo_description(node.id) : canopen::eds::load_device_description(node.eds, node.id);
      if (!desc.warnings.empty()) {
        log.info(label + " node " + std::to_string(node.id) + ": " + std::to_string(desc.warnings.size()) +
                 " warning(s) reading " + node.eds + " (accepted; `canopen-eds check " + node.eds +
                 "` lists them, as does --log-level debug)");
      }
      for (const auto& w : desc.warnings) log.debug(label + " node " + std::to_string(node.id) + " EDS: " + w);
      out.emplace(node.id, std::move(desc));
    } catch (const canopen::eds::EdsError& e) {
      throw ConfigError(e.what());
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
  for (const auto& node : cfg.nodes) link.simulator->add_node(node.id, demo_description(node.id));
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
    auto descriptions = load_descriptions(cfg, label, log);
    NetworkLink link;
    if (cfg.simulated) {
      link = open_simulated(io, cfg, label, log);
    } else {
      if (!c.monitor) c.monitor = canopen::socketcan::LinkMonitor::create(io);
      link.socket = canopen::socketcan::SocketCanChannel::open(io, cfg.interface, c.monitor);
      link.channel = link.socket.get();
    }
    auto unit = std::make_unique<NetworkUnit>(io, number, std::move(cfg), std::move(descriptions), std::move(link), log,
                                              config.source);
    if (unit->channel->state() == canopen::can::BusState::Down) log.warn(unit->label + " is down; waiting for it to come up");
    c.units.push_back(std::move(unit));
  }
  return c;
}

}  // namespace gateway
