#include "app/network_unit.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/socketcan/channel.hpp"
#include "sim/asio_memory_bus.hpp"
#include "sim/simulator.hpp"

#ifndef CANOPEN_GATEWAY_VERSION
#define CANOPEN_GATEWAY_VERSION "0.0.0"
#endif

namespace gateway {

NetworkLink::NetworkLink() = default;
NetworkLink::NetworkLink(NetworkLink&&) noexcept = default;
NetworkLink& NetworkLink::operator=(NetworkLink&&) noexcept = default;
NetworkLink::~NetworkLink() = default;

void NetworkLink::start_simulation() {
  if (simulator) simulator->start();
}

void NetworkLink::stop_simulation() {
  if (simulator) simulator->stop();
}

bool NetworkLink::set_simulated_link(bool up) {
  if (!memory_gateway) return false;
  memory_gateway->set_link_up(up);
  return true;
}

canopen::can::MemoryBus* NetworkLink::simulated_bus() { return memory_bus ? &memory_bus->bus() : nullptr; }

namespace {

using canopen::can::Frame;

// heartbeat-consumer-ms with a time: a 1016h entry (auto and 0 have none).
bool consumed(const NodeConfig& c) { return c.heartbeat_consumer && c.heartbeat_consumer->count() > 0; }

}  // namespace

canopen::od::GatewayIdentity own_identity(const OwnIdentity& configured, const std::string& version) {
  canopen::od::GatewayIdentity id;
  id.device_type = configured.device_type;
  id.vendor_id = configured.vendor_id;
  id.product_code = kOwnProductCode;
  id.serial = configured.serial.value_or(0);
  id.software_version = version;
  unsigned major = 0, minor = 0;
  if (std::sscanf(version.c_str(), "%u.%u", &major, &minor) == 2)
    id.revision = (std::min(major, 0xFFFFu) << 16) | std::min(minor, 0xFFFFu);
  return id;
}

NetworkUnit::NetworkUnit(boost::asio::io_context& io, std::uint32_t net_number, NetworkConfig config,
                         std::map<std::uint8_t, canopen::eds::DeviceDescription> descs, NetworkLink opened,
                         Logger& logger, const std::string& config_source)
    : number(net_number),
      cfg(std::move(config)),
      label("net " + std::to_string(net_number) + " " + (cfg.simulated ? std::string("demo") : cfg.interface)),
      log(logger),
      link(std::move(opened)),
      descriptions(std::move(descs)) {
  trace::TraceSettings ts;
  ts.interface = cfg.simulated ? "demo" + std::to_string(net_number) : cfg.interface;
  ts.own_node_id = cfg.node_id;
  ts.bitrate = cfg.bitrate;
  ts.capture = {std::chrono::seconds(cfg.capture.ring_seconds), static_cast<std::size_t>(cfg.capture.max_bytes)};
  tap = std::make_shared<trace::NetworkTrace>(std::move(ts), std::chrono::steady_clock::now());
  tapped = std::make_unique<trace::TappedChannel>(*link.channel, *tap);
  channel = tapped.get();
  // The gateway's own node: its dictionary says what it produces.
  canopen::od::GatewayIdentity identity = own_identity(cfg.identity, CANOPEN_GATEWAY_VERSION);
  canopen::od::GatewayDictionaryOptions od_options;
  // 1010h "save" / 1011h "load" (7.5.2.13/14): the power-on values a reset of
  // the own node returns to, for the life of the process (a restart is a
  // power-on: the configuration gives the values again).
  od_options.on_store = [this](std::uint8_t sub) {
    return local ? local->device().store_parameters(sub) : make_error_code(canopen::SdoAbort::CannotStoreDeviceState);
  };
  od_options.on_restore = [this](std::uint8_t sub) {
    return local ? local->device().restore_default_parameters(sub)
                 : make_error_code(canopen::SdoAbort::CannotStoreDeviceState);
  };
  std::size_t consumers = 0;
  for (const auto& node : cfg.nodes) consumers += consumed(node) ? 1 : 0;
  od_options.heartbeat_consumers = static_cast<std::uint8_t>(std::clamp<std::size_t>(consumers, 8, 127));
  own_od.emplace(canopen::od::make_gateway_dictionary(cfg.node_id, identity, od_options));
  auto& od = *own_od;
  using canopen::DataType;
  using canopen::Value;
  auto set = [&](std::uint16_t index, std::uint8_t sub, Value v, const char* what) {
    if (auto ec = od.write(index, sub, canopen::encode(v)))
      throw ConfigError(config_source + ": " + label + ": " + what + ": " + ec.message());
  };
  set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, static_cast<std::uint64_t>(cfg.heartbeat_producer.count())),
      "heartbeat-ms");
  std::uint8_t slot = 1;
  for (const auto& node : cfg.nodes) {
    if (!consumed(node)) continue;
    set(0x1016, slot++,
        Value::of_unsigned(DataType::Unsigned32, std::uint64_t{node.id} << 16 |
                                                     static_cast<std::uint64_t>(node.heartbeat_consumer->count())),
        "heartbeat-consumer-ms");
  }
  if (cfg.sync.window.count() > 0)
    set(0x1007, 0, Value::of_unsigned(DataType::Unsigned32, static_cast<std::uint64_t>(cfg.sync.window.count())),
        "sync.window-us");
  if (cfg.sync.period.count() > 0) {
    set(0x1006, 0, Value::of_unsigned(DataType::Unsigned32, static_cast<std::uint64_t>(cfg.sync.period.count())),
        "sync.period-us");
    if (cfg.sync.counter_overflow != 0)
      set(0x1019, 0, Value::of_unsigned(DataType::Unsigned8, cfg.sync.counter_overflow), "sync.counter-overflow");
    set(0x1005, 0, Value::of_unsigned(DataType::Unsigned32, 0x40000080), "sync");  // bit 30: this node produces
  }
  if (cfg.time.produce) set(0x1012, 0, Value::of_unsigned(DataType::Unsigned32, 0x40000100), "time.produce");

  // Both sides send on the channel; what one side must hear of the other
  // (LocalNode::master_hears/hears) is delivered locally, later, by the
  // driver: a socket does not receive its own frames.
  canopen::DeviceConfig dev_cfg;
  dev_cfg.node_id = cfg.node_id;
  dev_cfg.time_period = std::chrono::duration_cast<canopen::Duration>(cfg.time.period);
  dev_cfg.unix_ms = [] {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  canopen::DeviceCallbacks dev_cb;
  dev_cb.on_state_change = [this](canopen::NmtState now_state, canopen::NmtState before) {
    log.info(label + " own node " + std::string(canopen::to_string(before)) + " -> " +
             std::string(canopen::to_string(now_state)));
    log.flush();
  };
  // CiA 301 7.2.8.2.2.1: the master that guards the own node stopped (or
  // came back). LocalNode has sent EMCY 8130h (or its reset), which the
  // event stream carries as the own node's EMCY; this is the log line.
  dev_cb.on_life_guarding = [this](canopen::nmt::LifeGuardingEvent e) {
    if (e == canopen::nmt::LifeGuardingEvent::Occurred) {
      const auto life = local ? local->device().nmt().life_time() : canopen::Duration::zero();
      log.warn(label + " own node: life guarding event: no guarding request from the NMT master for " +
               std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(life).count()) +
               " ms (100Ch x 100Dh); EMCY 8130h sent");
    } else {
      log.info(label + " own node: guarded again by the NMT master; EMCY 8130h reset");
    }
    log.flush();
  };
  // A reset communication of the own node returns 1016h to its power-on
  // values (the start-up configuration): the consumers of nodes changed at
  // run time are part of the gateway's configuration, so they come back.
  dev_cb.on_reset_communication = [this] {
    for (const auto& node : cfg.nodes)
      if (overlay_files.contains(node.id)) set_consumer_entry(node);
  };
  local = std::make_unique<canopen::LocalNode>(
      od, dev_cfg, [this](const Frame& f) { channel->send(f); },
      [this](const Frame& f) {
        if (driver) driver->deliver_locally(f, network.get());
      },
      dev_cb);

  network = std::make_unique<canopen::Network>(
      od,
      [this](const Frame& f) {
        channel->send(f);
        if (driver && local->hears(f)) driver->deliver_locally(f, local.get());
      },
      [this](const canopen::Event& ev) {
        if (const auto* s = std::get_if<canopen::NodeStateEvent>(&ev.body)) local->on_node_state(*s, now());
        if (on_event) on_event(ev);
      });
  for (const auto& node : cfg.nodes) set_up_node(node);

  driver = std::make_unique<canopen::socketcan::ServiceDriver>(io, *channel);
  driver->add(*local);
  driver->add(*network);
  // A write to the own 1016h (e.g. over SDO) changes which heartbeats are consumed.
  od.observe(0x1016, [this](std::uint8_t) {
    network->configure_heartbeat_consumers();
    log.info(label + " heartbeat consumers reconfigured from 1016h");
  });
  driver->on_frames([this](std::span<const Frame> frames) {
    if (log.enabled(LogLevel::Debug)) {
      for (const auto& f : frames) log.debug(label + " rx " + canopen::can::to_string(f));
    }
    log.flush();
  });
  channel->on_bus_event([this](const canopen::can::BusEvent& ev) {
    network->report(ev);  // bus changes are part of the network's event sequence
    local->on_bus_event(ev, now());
    if (on_bus_event) on_bus_event(ev);
  });
}

void NetworkUnit::set_up_node(const NodeConfig& node) {
  auto it = descriptions.find(node.id);
  if (it != descriptions.end()) {
    for (const auto& problem : network->add_node(node.id, it->second.od))
      log.warn(label + " node " + std::to_string(node.id) + " PDO: " + problem);
  }
  // heartbeat-consumer-ms auto: watched with the node's own 1017h (or a
  // period learnt from its heartbeats); 0: not watched at all.
  if (!node.heartbeat_consumer) {
    network->nmt().set_auto_watch(
        node.id, true,
        it != descriptions.end() ? canopen::nmt::producer_heartbeat_time(it->second.od) : canopen::Duration::zero());
  } else if (node.heartbeat_consumer->count() == 0) {
    network->nmt().set_auto_watch(node.id, false);
  }
  if (node.guarding.guard_time.count() > 0) {
    network->nmt().set_node_guarding(node.id, node.guarding.guard_time, node.guarding.life_time_factor, now());
  }
  // Reading the PDO configuration needs the description (types, names).
  const bool read_pdo = it != descriptions.end() &&
                        (node.boot && node.boot->read_pdo_config ? *node.boot->read_pdo_config : cfg.read_pdo_config);
  if (node.boot) {
    canopen::master::NodeBootConfig boot;
    if (it != descriptions.end()) {
      boot = canopen::master::boot_config_from_dcf(it->second);
      if (!node.boot->configure) boot.dcf = nullptr;
      if (!node.boot->check_identity) boot.device_type = boot.vendor_id = boot.product_code = boot.revision =
          boot.serial = std::nullopt;
    }
    boot.start = node.boot->start;
    network->configure_boot(node.id, boot, read_pdo);
  } else if (read_pdo) {
    // Only watched, but its PDOs are read at each boot-up: no checks, no DCF, no start.
    canopen::master::NodeBootConfig watch_only;
    watch_only.start = false;
    network->configure_boot(node.id, watch_only, true);
  }
}

std::string NetworkUnit::cannot_apply(const NodeConfig& node) const {
  if (node.id == cfg.node_id)
    return "node " + std::to_string(node.id) + " is the gateway's own node-ID on " + label;
  if (!consumed(node)) return {};
  const auto& od = *own_od;
  const auto entries = od.get_unsigned(0x1016, 0).value_or(0);
  for (std::uint8_t sub = 1; sub <= entries; ++sub) {
    const auto v = od.get_unsigned(0x1016, sub).value_or(0);
    const auto id = (v >> 16) & 0xFF;
    if (id == node.id || id == 0 || (v & 0xFFFF) == 0) return {};  // its own entry, or an unused one
  }
  return "heartbeat-consumer-ms: the gateway's 1016h has no free entry (" + std::to_string(entries) +
         " in use); restart the gateway to have it sized for the configured nodes";
}

void NetworkUnit::set_consumer_entry(const NodeConfig& node) {
  auto& od = *own_od;
  const auto entries = od.get_unsigned(0x1016, 0).value_or(0);
  std::uint8_t own = 0, free = 0;
  for (std::uint8_t sub = 1; sub <= entries; ++sub) {
    const auto v = od.get_unsigned(0x1016, sub).value_or(0);
    const auto id = (v >> 16) & 0xFF;
    if (id == node.id && own == 0) own = sub;
    if ((id == 0 || (v & 0xFFFF) == 0) && free == 0) free = sub;
  }
  using canopen::DataType;
  using canopen::Value;
  std::uint64_t value = 0;
  if (consumed(node)) value = std::uint64_t{node.id} << 16 | static_cast<std::uint64_t>(node.heartbeat_consumer->count());
  const std::uint8_t sub = own != 0 ? own : value != 0 ? free : 0;
  if (sub == 0) return;  // nothing to clear, or no room (cannot_apply() said so first)
  // The 1016h observer reconfigures the consumers (Network::configure_heartbeat_consumers).
  if (auto ec = od.write(0x1016, sub, canopen::encode(Value::of_unsigned(DataType::Unsigned32, value))))
    log.warn(label + " node " + std::to_string(node.id) + ": 1016h sub " + std::to_string(sub) + ": " + ec.message());
}

void NetworkUnit::apply_node(const NodeConfig& node, std::optional<canopen::eds::DeviceDescription> description) {
  const std::uint8_t id = node.id;
  // What the node had goes: its description (kept alive, see
  // retired_descriptions), decoding, RPDOs, boot-up configuration, guarding.
  if (auto old = descriptions.extract(id)) retired_descriptions.push_back(std::move(old));
  network->remove_node(id);
  network->nmt().set_node_guarding(id, canopen::Duration::zero(), 0, now());
  network->nmt().set_auto_watch(id, true);
  if (description) descriptions.emplace(id, std::move(*description));
  set_consumer_entry(node);
  set_up_node(node);
  auto it = std::find_if(cfg.nodes.begin(), cfg.nodes.end(), [id](const NodeConfig& n) { return n.id == id; });
  if (it != cfg.nodes.end()) *it = node;
  else cfg.nodes.push_back(node);
}

void NetworkUnit::remove_node(std::uint8_t id) {
  NodeConfig none;
  none.id = id;
  apply_node(none, std::nullopt);  // nothing configured: watched as any node heard
  std::erase_if(cfg.nodes, [id](const NodeConfig& n) { return n.id == id; });
}

NetworkUnit::~NetworkUnit() = default;

void NetworkUnit::boot_at_start() {
  if (cfg.boot_at_start != NetworkConfig::BootAtStart::ResetCommunication) return;
  std::string sent;
  for (const auto& node : cfg.nodes) {
    if (!node.boot) continue;
    network->send_nmt(canopen::NmtCommand::ResetCommunication, node.id);
    sent += (sent.empty() ? "" : ", ") + std::to_string(node.id);
  }
  if (!sent.empty()) log.info(label + " boot at start: NMT reset-communication to node " + sent);
}

}  // namespace gateway
