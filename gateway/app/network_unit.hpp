// One CAN network of the gateway as one unit: its channel, the gateway's
// own CANopen device on it (canopen::LocalNode on the gateway dictionary),
// the master-side services watching the other nodes (canopen::Network),
// the ServiceDriver that feeds both from the channel and the io_context's
// clock, the nodes' EDS/DCF descriptions, and for the simulated demo bus
// the simulated devices. Built by the composition root (composition.hpp).
//
// The stack's services read no clock: what the unit hands them comes from
// now(), the one place the unit reads it.
//
// Thread safety: io_context thread only. The unit MUST outlive nothing that
// refers to it: App owns it and sets on_event/on_bus_event before start().
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <boost/asio/io_context.hpp>

#include "canopen/can/bus_state.hpp"
#include "canopen/can/channel.hpp"
#include "canopen/clock.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/events.hpp"
#include "canopen/local_node.hpp"
#include "canopen/network.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/socketcan/service_driver.hpp"
#include "config/config.hpp"
#include "log.hpp"
#include "app/seq_store.hpp"
#include "trace/network_trace.hpp"
#include "trace/tapped_channel.hpp"

namespace canopen::socketcan {
class SocketCanChannel;
}

namespace canopen::can {
class MemoryBus;
}

namespace canopen::sim {
class AsioMemoryBus;
class AsioMemoryChannel;
class Simulator;
}  // namespace canopen::sim

namespace gateway {

// A network's CAN side as the composition root opened it. The unit talks
// to `channel` only, whatever it is; the rest keeps it alive and serves
// the hooks of a simulated network (App::simulated_bus, simulator, ...).
struct NetworkLink {
  NetworkLink();
  NetworkLink(NetworkLink&&) noexcept;
  NetworkLink& operator=(NetworkLink&&) noexcept;
  ~NetworkLink();

  // A simulated network's devices start (boot-up, their producers) and
  // stop; nothing for a real network.
  void start_simulation();
  void stop_simulation();
  // A simulated network only: takes the gateway's side of the in-process
  // bus down or up, as an interface going down would. False for a real one.
  bool set_simulated_link(bool up);
  // A simulated network's in-process bus; nullptr for a real one.
  canopen::can::MemoryBus* simulated_bus();

  canopen::can::Channel* channel = nullptr;
  // A real network: the SocketCAN channel.
  std::shared_ptr<canopen::socketcan::SocketCanChannel> socket;
  // A simulated one: the in-process bus, the gateway's and the devices'
  // ends of it, and the simulated devices (destroyed in reverse order).
  std::unique_ptr<canopen::sim::AsioMemoryBus> memory_bus;
  std::unique_ptr<canopen::sim::AsioMemoryChannel> memory_gateway, memory_devices;
  std::unique_ptr<canopen::sim::Simulator> simulator;
};

// The own node's identity on a network (issue 28 item 4): 1000h, 1018h sub
// 1 and 4 as configured; 1018h sub 2 kOwnProductCode; sub 3 the program's
// `version` ("X.Y.Z") as (X << 16) | Y, CiA 301 7.5.2.20's major revision
// (CANopen behaviour) and minor revision; 100Ah the version itself.
inline constexpr std::uint32_t kOwnProductCode = 0x43475700;  // "CGW" and 00h
canopen::od::GatewayIdentity own_identity(const OwnIdentity& configured, const std::string& version);

struct NetworkUnit {
  // Builds the own dictionary from `cfg` (heartbeat, consumers, SYNC,
  // TIME), the LocalNode and the Network with every node's watching, boot
  // and PDO configuration, and binds them to link.channel. Throws
  // ConfigError when a configured value does not fit the dictionary.
  // `cfg.nodes` is the final node list (the demo's for a simulated bus);
  // `descriptions` the nodes' EDS/DCF, by node-ID.
  NetworkUnit(boost::asio::io_context& io, std::uint32_t number, NetworkConfig cfg,
              std::map<std::uint8_t, canopen::eds::DeviceDescription> descriptions, NetworkLink link, Logger& log,
              const std::string& config_source);
  ~NetworkUnit();
  NetworkUnit(const NetworkUnit&) = delete;
  NetworkUnit& operator=(const NetworkUnit&) = delete;

 private:
  // Watching, guarding, decoding and boot-up configuration of one node as
  // its settings say (the constructor's, and apply_node()'s after it).
  void set_up_node(const NodeConfig& node);
  // Writes node's 1016h entry (heartbeat-consumer-ms with a time), or clears it.
  void set_consumer_entry(const NodeConfig& node);

 public:

  // The time the unit gives the stack.
  static canopen::TimePoint now() { return canopen::SteadyClock::now(); }

  std::uint32_t number = 0;
  NetworkConfig cfg;
  std::string label;  // "net 1 vcan0"
  Logger& log;
  NetworkLink link;
  // The frame tap (issue 18): ring, bus load, trace clients. `channel` is
  // `tapped`, in front of link.channel, so every frame received and sent
  // passes the tap.
  std::shared_ptr<trace::NetworkTrace> tap;  // shared: trace clients hold it weakly
  std::unique_ptr<trace::TappedChannel> tapped;
  canopen::can::Channel* channel = nullptr;  // tapped, in front of link.channel
  std::optional<canopen::od::ObjectDictionary> own_od;
  std::unique_ptr<canopen::LocalNode> local;
  // std::map: stable addresses (the boot configurator keeps DCF pointers).
  std::map<std::uint8_t, canopen::eds::DeviceDescription> descriptions;
  // Descriptions replaced at run time, kept at their addresses for the life
  // of the unit: a boot-up sequence under way may still read its DCF.
  std::vector<std::map<std::uint8_t, canopen::eds::DeviceDescription>::node_type> retired_descriptions;

  // Run-time node configuration (issue 17; App's NodeSettings).
  // The nodes as the configuration file (or the demo) gives them, before
  // the state-dir overlay.
  std::vector<NodeConfig> file_nodes;
  // The nodes whose settings come from state-dir, and the file holding them.
  std::map<std::uint8_t, std::string> overlay_files;
  // Reads the EDS/DCF a node's settings name (its file, or the demo's built-in
  // one); throws canopen::eds::EdsError. Set by the composition root.
  std::function<canopen::eds::DeviceDescription(const NodeConfig&)> load_description;
  // Why `node` cannot be applied on this network ("" = it can): the own
  // node-ID, or no free 1016h entry for its heartbeat consumer.
  std::string cannot_apply(const NodeConfig& node) const;
  // Applies `node` at once, replacing what the node had (settings,
  // description, decoding, watching, 1016h entry, boot-up configuration;
  // the boot options act at its next boot-up). `description`: the node's
  // EDS/DCF (nullopt: none). cannot_apply() MUST have said "".
  void apply_node(const NodeConfig& node, std::optional<canopen::eds::DeviceDescription> description);
  // Forgets a node that only run-time configuration had added.
  void remove_node(std::uint8_t node);
  // At the gateway's start, after the own boot-up: boot: {at-start:
  // reset-communication} sends NMT reset-communication to each node with
  // boot: (their boot-ups then run the sequence); as-found sends nothing.
  void boot_at_start();
  std::unique_ptr<canopen::Network> network;
  std::unique_ptr<canopen::socketcan::ServiceDriver> driver;

  // Every event of the network's stream, after the own node took what it
  // needs of it (lost nodes: 8130h). Set by the App.
  std::function<void(const canopen::Event&)> on_event;
  // Every bus event of the channel, after the network reported it and the
  // own node raised its EMCYs. Set by the App.
  std::function<void(const canopen::can::BusEvent&)> on_bus_event;

  // The App's state per network.
  std::optional<SeqStore> seq;  // the event sequence across restarts (from start())
};

}  // namespace gateway
