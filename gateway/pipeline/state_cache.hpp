// What the gateway knows now about every network and node, kept from the
// event stream: NMT state, heartbeat age, boot-ups, identity, EMCYs and the
// latest value of every mapped object. REST (node list, node details) and
// the dashboard's first paint are served from here, never by asking the bus.
//
// Thread safety: none; io_context thread only.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "canopen/can/bus_state.hpp"
#include "canopen/events.hpp"

namespace gateway {

using WallTime = canopen::can::Frame::Clock::time_point;

struct CachedValue {
  std::string name;
  canopen::Value value;
  WallTime timestamp{};
  std::uint16_t tpdo = 0;  // which TPDO carried it last
};

struct CachedEmcy {
  canopen::EmcyEvent emcy;
  WallTime timestamp{};
  std::uint64_t seq = 0;
};

struct Identity {
  std::uint32_t device_type = 0;  // 1000h
  std::uint32_t vendor_id = 0;    // 1018h sub 1..4
  std::uint32_t product_code = 0;
  std::uint32_t revision = 0;
  std::uint32_t serial = 0;
};

struct NodeInfo {
  std::uint8_t id = 0;
  std::string name;         // from the configuration
  bool configured = false;  // listed in the configuration (else only heard)
  std::optional<canopen::NmtState> state;  // nullopt: unknown or lost
  bool lost = false;
  std::optional<WallTime> last_heartbeat;
  std::optional<WallTime> last_seen;
  std::uint32_t boot_count = 0;
  std::optional<Identity> identity;
  std::uint64_t emcy_count = 0;        // every EMCY, resets included
  std::uint64_t emcy_error_count = 0;  // EMCYs reporting an error (code not 0000h "error reset or no error")
  std::deque<CachedEmcy> emcys;  // newest first, bounded
  // The last EMCY since the node's last boot-up (a boot-up clears it: the
  // device starts without the errors it had). An error is active while its
  // code is not 0000h or its error register (1001h) is not 0.
  std::optional<CachedEmcy> last_emcy;
  std::map<std::pair<std::uint16_t, std::uint8_t>, CachedValue> values;
  std::map<std::uint16_t, canopen::Bytes> tpdo_raw;  // latest raw bytes per TPDO number
  std::optional<canopen::BootConfigEvent> boot;      // last boot-configuration step
};

struct NetworkInfo {
  std::uint32_t number = 0;
  std::string interface;
  bool simulated = false;
  canopen::can::BusState bus = canopen::can::BusState::ErrorActive;
  std::optional<canopen::can::BusEvent> last_bus_event;
  std::uint64_t last_seq = 0;
  std::uint64_t events = 0;
  std::uint64_t sync_count = 0;
  std::optional<std::uint8_t> last_sync_counter;
  std::map<std::uint8_t, NodeInfo> nodes;
};

class StateCache {
 public:
  explicit StateCache(std::size_t emcy_history = 32) : emcy_history_(emcy_history) {}

  // Registers a network (numbered from 1) and its configured nodes.
  NetworkInfo& add_network(std::uint32_t number, std::string interface, bool simulated);
  void add_configured_node(std::uint32_t network, std::uint8_t node, std::string name);
  // The node is no longer configured (run-time configuration removed it);
  // what was heard of it stays.
  void unconfigure_node(std::uint32_t network, std::uint8_t node);

  // Events of an unregistered network are ignored.
  void apply(std::uint32_t network, const canopen::Event& ev);
  // Identity read during boot-up configuration (or by an SDO read).
  void set_identity(std::uint32_t network, std::uint8_t node, const Identity& id);

  const NetworkInfo* network(std::uint32_t number) const;
  const NodeInfo* node(std::uint32_t network, std::uint8_t node) const;
  const std::map<std::uint32_t, NetworkInfo>& networks() const { return networks_; }

 private:
  NodeInfo& node_ref(NetworkInfo& net, std::uint8_t node);

  std::size_t emcy_history_;
  std::map<std::uint32_t, NetworkInfo> networks_;
};

}  // namespace gateway
