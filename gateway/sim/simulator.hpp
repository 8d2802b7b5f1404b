// Simulated CANopen nodes for demos and tests: each node is a canopen::Device
// on the dictionary of an EDS file, bound to a can::Channel (SocketCAN or an
// AsioMemoryBus channel) through a ServiceDriver on the io_context.
//
// What a node does:
//   - boot-up, heartbeat (1017h set from SimulatorOptions::heartbeat),
//     reacts to NMT (PDOs only while operational; reset node/communication
//     restore the EDS values and boot again);
//   - SDO server over its whole dictionary; 1010h "save" / 1011h "load"
//     change what its resets restore (sim/device_objects.hpp), and where
//     its EDS has them, the CiA 302-3 program objects 1F50h/1F51h/1F56h/
//     1F57h keep a downloaded image (in memory) across resets;
//   - every tpdo_period, while operational, writes plausible new values to
//     the objects its TPDOs map (a CiA 402 drive: position ramp, velocity,
//     torque; a CiA 401 module: digital inputs toggling, analog inputs as a
//     slow sine; otherwise a counter / sine / toggle per type, within the
//     object's limits); the writes are TPDO events, so the transmission
//     types decide when frames go out;
//   - an EMCY every emcy_period (raised, then reset at the next period), and
//     raise_emcy() on command;
//   - with sync_period set, the first node added produces SYNC (1005h bit
//     30, 1006h), so synchronous TPDOs flow;
//   - LSS slave (CiA 305, canopen/lss/slave.hpp) with the LSS address of
//     its 1018h; an EDS serial number of 0 is replaced by one of the
//     simulator's (53000000h + node-ID; 55000000h + n for the n-th
//     unconfigured device) so no two simulated devices share an address.
//     A new node-ID given by LSS becomes active at the device's next NMT
//     reset communication: it then boots with it (FFh: it goes silent,
//     unconfigured). add_unconfigured_node() adds a device that starts
//     without a node-ID: no boot-up, no heartbeat, only LSS, until a master
//     gives it one and switches it back to waiting; then it boots with it
//     like any other node.
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
#include <vector>

#include "canopen/can/channel.hpp"
#include "canopen/device.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/lss/slave.hpp"
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
  // The description of a device at a node-ID ($NODEID resolved with it).
  using Describe = std::function<eds::DeviceDescription(std::uint8_t node)>;

  Simulator(boost::asio::io_context& io, can::Channel& channel, SimulatorOptions options, LineHandler on_line = {});
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Loads the EDS with $NODEID = node. Throws eds::EdsError for a bad file,
  // std::invalid_argument for a bad or duplicate node-ID. Before start().
  void add_node(std::uint8_t node, const std::filesystem::path& eds);
  // A description without a Describe cannot be reloaded for another
  // node-ID: after an LSS node-ID change the device keeps its dictionary
  // (COB-IDs of PDOs/EMCY as at the old node-ID).
  void add_node(std::uint8_t node, eds::DeviceDescription description);
  void add_node(std::uint8_t node, Describe describe);
  // A device that starts unconfigured (node-ID FFh, see top). Throws like
  // add_node(). Before start().
  void add_unconfigured_node(const std::filesystem::path& eds);
  void add_unconfigured_node(Describe describe);

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
  // Devices with a node-ID.
  std::size_t size() const { return nodes_.size(); }
  // Devices waiting for a node-ID (LSS).
  std::size_t unconfigured() const { return waiting_.size(); }
  // The LSS slave of the device with this active node-ID; nullptr if none.
  lss::LssSlave* lss(std::uint8_t node);

 private:
  struct Node;
  // Feeds every device's LSS slave (one service on the driver for all).
  struct LssPort {
    Simulator* sim;
    void on_frame(const can::Frame& f, TimePoint now);
    void on_time(TimePoint) {}
    TimePoint next_deadline() const { return TimePoint::max(); }
  };
  std::unique_ptr<Node> make_node(std::uint8_t node, eds::DeviceDescription description, Describe describe);
  // (Re)builds the Device of `n` at node-ID `node` from `description`.
  void build_device(Node& n, std::uint8_t node, eds::DeviceDescription description);
  void make_lss(Node& n, std::uint8_t node_id);
  // After an LSS node-ID change: the device at its new node-ID (booted), or
  // unconfigured. Runs from the io_context, outside the driver's loops.
  void rehome(Node* n, std::uint8_t new_id);
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
  std::vector<std::unique_ptr<Node>> waiting_;  // unconfigured: LSS only
  std::uint32_t unconfigured_added_ = 0;
  LssPort lss_port_{this};
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
