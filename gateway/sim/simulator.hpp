// Simulated CANopen nodes for demos and tests: each node is a canopen::Device
// on the dictionary of an EDS file, bound to a can::Channel (SocketCAN or an
// AsioMemoryBus channel) through a ServiceDriver on the io_context.
//
// What a node does:
//   - boot-up, heartbeat (1017h set from SimulatorOptions::heartbeat),
//     reacts to NMT (PDOs only while operational; reset node/communication
//     restore the EDS values and boot again);
//   - SDO server over its whole dictionary;
//   - every tpdo_period, while operational, writes plausible new values to
//     the objects its TPDOs map (a CiA 402 drive: position ramp, velocity,
//     torque; a CiA 401 module: digital inputs toggling, analog inputs as a
//     slow sine; otherwise a counter / sine / toggle per type, within the
//     object's limits); the writes are TPDO events, so the transmission
//     types decide when frames go out;
//   - an EMCY every emcy_period (raised, then reset at the next period), and
//     raise_emcy() on command;
//   - with sync_period set, the first node added produces SYNC (1005h bit
//     30, 1006h), so synchronous TPDOs flow.
// Nodes added to one Simulator hear each other's frames as on a real bus.
//
// Each important event is reported as one line ("node 5 boot-up",
// "node 5 state operational", "node 5 emcy 3210", "node 5 rpdo 1
// Controlword=15") through the line callback.
//
// Thread safety: io_context thread only. The channel must outlive the
// Simulator; call stop() (or destroy it) before the channel closes.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include "canopen/can/channel.hpp"
#include "canopen/device.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/socketcan/service_driver.hpp"

namespace canopen::sim {

struct SimulatorOptions {
  std::chrono::milliseconds heartbeat{1000};     // 1017h of every node; 0 = none
  std::chrono::milliseconds tpdo_period{100};    // value updates; 0 = values never change
  std::chrono::milliseconds emcy_period{0};      // 0 = EMCY only on command
  std::chrono::milliseconds sync_period{0};      // 0 = no SYNC producer
  bool auto_start = false;                       // go operational by itself after boot-up
};

class Simulator {
 public:
  using LineHandler = std::function<void(std::string_view line)>;

  Simulator(boost::asio::io_context& io, can::Channel& channel, SimulatorOptions options, LineHandler on_line = {});
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Loads the EDS with $NODEID = node. Throws eds::EdsError for a bad file,
  // std::invalid_argument for a bad or duplicate node-ID. Before start().
  void add_node(std::uint8_t node, const std::filesystem::path& eds);
  void add_node(std::uint8_t node, eds::DeviceDescription description);

  // Power-on of every node (boot-up) and the timers.
  void start();
  // Cancels timers and unbinds the nodes from the channel; idempotent.
  void stop();

  // Raises EMCY `code` on the node now; false for an unknown node or a code
  // already present.
  bool raise_emcy(std::uint8_t node, std::uint16_t code);
  Device* device(std::uint8_t node);
  // The node's current dictionary values become the ones its resets
  // restore, as if stored in non-volatile memory: a device whose
  // configuration (e.g. PDO mapping) differs from its EDS. False for an
  // unknown node.
  bool store(std::uint8_t node);
  std::size_t size() const { return nodes_.size(); }

 private:
  struct Node;
  void say(const std::string& line);
  void tick_values();
  void tick_emcy();
  void arm_values();
  void arm_emcy();
  void loopback(const Node* from, const can::Frame& f);
  void restore(Node& n, std::uint16_t first, std::uint16_t last);

  boost::asio::io_context& io_;
  can::Channel& channel_;
  SimulatorOptions opt_;
  LineHandler on_line_;
  socketcan::ServiceDriver driver_;
  std::map<std::uint8_t, std::unique_ptr<Node>> nodes_;
  boost::asio::steady_timer value_timer_;
  boost::asio::steady_timer emcy_timer_;
  TimePoint started_{};
  std::chrono::steady_clock::time_point value_due_{};  // due time of the next value tick
  std::uint64_t ticks_ = 0;
  // Frames one simulated node sent, for the others (the channel does not
  // echo our own frames); drained from the io_context.
  std::deque<std::pair<const Node*, can::Frame>> local_;
  bool draining_posted_ = false;
  bool running_ = false;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace canopen::sim
