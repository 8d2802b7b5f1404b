#include "pipeline/state_cache.hpp"

#include <type_traits>
#include <variant>

namespace gateway {

NetworkInfo& StateCache::add_network(std::uint32_t number, std::string interface, bool simulated) {
  auto& net = networks_[number];
  net.number = number;
  net.interface = std::move(interface);
  net.simulated = simulated;
  return net;
}

void StateCache::add_configured_node(std::uint32_t network, std::uint8_t node, std::string name) {
  auto it = networks_.find(network);
  if (it == networks_.end()) return;
  auto& n = node_ref(it->second, node);
  n.configured = true;
  n.name = std::move(name);
}

void StateCache::unconfigure_node(std::uint32_t network, std::uint8_t node) {
  auto it = networks_.find(network);
  if (it == networks_.end()) return;
  auto n = it->second.nodes.find(node);
  if (n == it->second.nodes.end()) return;
  n->second.configured = false;
  n->second.name.clear();
}

NodeInfo& StateCache::node_ref(NetworkInfo& net, std::uint8_t node) {
  auto& n = net.nodes[node];
  n.id = node;
  return n;
}

void StateCache::set_identity(std::uint32_t network, std::uint8_t node, const Identity& id) {
  auto it = networks_.find(network);
  if (it == networks_.end()) return;
  node_ref(it->second, node).identity = id;
}

const NetworkInfo* StateCache::network(std::uint32_t number) const {
  auto it = networks_.find(number);
  return it == networks_.end() ? nullptr : &it->second;
}

const NodeInfo* StateCache::node(std::uint32_t network, std::uint8_t node) const {
  const auto* net = this->network(network);
  if (net == nullptr) return nullptr;
  auto it = net->nodes.find(node);
  return it == net->nodes.end() ? nullptr : &it->second;
}

void StateCache::apply(std::uint32_t network, const canopen::Event& ev) {
  auto it = networks_.find(network);
  if (it == networks_.end()) return;
  auto& net = it->second;
  net.last_seq = ev.seq;
  ++net.events;
  std::visit(
      [&](const auto& body) {
        using T = std::decay_t<decltype(body)>;
        if constexpr (std::is_same_v<T, canopen::NodeStateEvent>) {
          auto& n = node_ref(net, body.node);
          n.state = body.state;
          n.lost = body.cause == canopen::NodeStateEvent::Cause::Lost;
          if (!n.lost) n.last_seen = ev.timestamp;
          if (body.cause == canopen::NodeStateEvent::Cause::BootUp) {
            ++n.boot_count;
            n.last_emcy.reset();
          }
        } else if constexpr (std::is_same_v<T, canopen::HeartbeatEvent>) {
          auto& n = node_ref(net, body.node);
          n.last_heartbeat = ev.timestamp;
          n.last_seen = ev.timestamp;
          if (!n.lost) n.state = body.state;
        } else if constexpr (std::is_same_v<T, canopen::EmcyEvent>) {
          auto& n = node_ref(net, body.node);
          n.last_seen = ev.timestamp;
          ++n.emcy_count;
          if (body.error_code != 0) ++n.emcy_error_count;
          n.emcys.push_front(CachedEmcy{body, ev.timestamp, ev.seq});
          n.last_emcy = n.emcys.front();
          if (n.emcys.size() > emcy_history_) n.emcys.pop_back();
        } else if constexpr (std::is_same_v<T, canopen::PdoEvent>) {
          if (body.node == 0) return;  // unclaimed: nobody to attach it to
          auto& n = node_ref(net, body.node);
          n.last_seen = ev.timestamp;
          n.tpdo_raw[body.number] = body.raw;
          for (const auto& v : body.values) {
            auto& slot = n.values[{v.index, v.sub}];
            if (slot.name != v.name) slot.name = v.name;
            slot.value = v.value;
            slot.timestamp = ev.timestamp;
            slot.tpdo = body.number;
          }
        } else if constexpr (std::is_same_v<T, canopen::SyncEvent>) {
          ++net.sync_count;
          net.last_sync_counter = body.counter;
        } else if constexpr (std::is_same_v<T, canopen::BootConfigEvent>) {
          auto& n = node_ref(net, body.node);
          n.boot = body;
          if (body.identity)
            n.identity = Identity{body.identity->device_type, body.identity->vendor_id, body.identity->product_code,
                                  body.identity->revision, body.identity->serial};
        } else if constexpr (std::is_same_v<T, canopen::can::BusEvent>) {
          net.bus = body.state;
          net.last_bus_event = body;
        }
      },
      ev.body);
}

}  // namespace gateway
