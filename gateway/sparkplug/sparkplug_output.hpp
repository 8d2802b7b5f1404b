// The CANopen side of the Sparkplug B edge node (contract "Sparkplug B"):
// stack events of every network become device births, deaths and data on
// the EdgeSession, and NCMD/DCMD writes become request-core commands. The
// MQTT side (connection, Will, NCMD/DCMD topics) is the EdgeClient's; this
// class only calls EdgeSession and hands what it appended to `send`.
//
//   start()                  the edge node's metrics: `Network <N>/Bus State`
//                            (String, canopen::can::to_string) per network
//   on_event(net, ev)        every stack event of every network:
//     boot-up, or a heartbeat / guarding answer of a node not online, or
//     its recovery -> its model is built anew (DeviceModel: the PDOs in use
//     now, so a changed PDO configuration shows in this birth), its
//     `sparkplug-metrics` objects are read by SDO through the request core
//     one after the other (caller "sparkplug:birth", role viewer; a failed
//     read leaves that metric null and is logged), then DBIRTH;
//     a boot configuration that ends (BootConfigEvent Done, e.g. the PDO
//     configuration read from the device) with another metric set -> the
//     same again;
//     lost -> DDEATH; an NMT state change -> DDATA `Node/State`;
//     a TPDO -> DDATA of the metrics that changed, EMCY -> DDATA of the
//     EMCY metrics, each stamped with the frame's time; a bus state change
//     -> NDATA.
//   node_changed(net, node, listed)  the node's settings or EDS/DCF changed
//     at run time (PUT .../config, .../eds): its `sparkplug-metrics` become
//     `listed`, and a device that is online (or being born) is born anew
//     at once as above (model from the new EDS, the listed objects read,
//     DBIRTH); an offline one with its next boot-up. Its device id stays
//     what it was (a renamed node keeps its id until the next start).
//   on_command(cmd)          an NCMD/DCMD write the EdgeSession returned:
//     with sparkplug.commands-role none it is ignored (logged); otherwise
//     its items go to the request core as that role (caller
//     "sparkplug:dcmd"; DeviceModel::writes_for: the values for one RPDO as
//     one RPDO write, other objects by SDO download), which checks and
//     audits each; a success shows in a DDATA (an RPDO's every mapped
//     value as sent, an SDO write's value), a refusal changes nothing and
//     is logged.
//
// Thread safety: io thread only. The EdgeSession, the logger and what the
// functions refer to MUST outlive the output; request-core answers that
// arrive after it is gone are dropped.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "canopen/can/bus_state.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/events.hpp"
#include "canopen/pdo/remote_config.hpp"
#include "core/node_entry.hpp"
#include "core/request_core.hpp"
#include "log.hpp"
#include "sparkplug/device_model.hpp"
#include "sparkplug/edge_session.hpp"

namespace gateway {

class SparkplugOutput {
 public:
  // Carries out what an EdgeSession call appended (EdgeClient::send).
  using Send = std::function<void(std::vector<sparkplug::Outgoing>&)>;
  // The request core (RequestCore::execute).
  using Execute = std::function<void(core::Request, core::RequestCore::Done)>;

  struct Network {
    std::uint32_t number = 0;
    std::vector<NodeConfig> nodes;  // the configured nodes (name, sparkplug-metrics)
  };
  // Lookups into the running networks; each may return nullptr / nullopt.
  struct Sources {
    std::function<const canopen::eds::DeviceDescription*(std::uint32_t net, std::uint8_t node)> description;
    // canopen::Network::pdo_config(): the PDOs as the master uses them now.
    std::function<const canopen::pdo::RemotePdoTable*(std::uint32_t net)> pdo_table;
    std::function<std::optional<canopen::can::BusState>(std::uint32_t net)> bus_state;  // optional
    // UTC ms (EdgeClient::now_ms): for messages no frame caused. MUST be set.
    std::function<std::uint64_t()> now_ms;
  };
  struct Options {
    bool aliases = false;                 // sparkplug.aliases
    Role commands_role = Role::Operator;  // sparkplug.commands-role
  };

  // Device ids are fixed here (sparkplug::device_ids; fallbacks logged).
  SparkplugOutput(sparkplug::EdgeSession& edge, Send send, Execute execute, std::vector<Network> networks,
                  Sources sources, Options options, Logger& log);
  ~SparkplugOutput();
  SparkplugOutput(const SparkplugOutput&) = delete;
  SparkplugOutput& operator=(const SparkplugOutput&) = delete;

  void start();
  void on_event(std::uint32_t network, const canopen::Event& ev);
  void on_command(const sparkplug::WriteCommand& cmd);
  void node_changed(std::uint32_t network, std::uint8_t node, const std::vector<SparkplugObject>& listed);

  // The device id of a node ("" for a node never configured nor heard).
  std::string device_id(std::uint32_t network, std::uint8_t node) const;

 private:
  struct Device {
    std::uint32_t network = 0;
    std::uint8_t node = 0;
    std::string id;
    std::vector<SparkplugObject> listed;
    enum class Phase : std::uint8_t { Offline, Reading, Online } phase = Phase::Offline;
    std::optional<sparkplug::DeviceModel> model;
    std::uint64_t generation = 0;  // +1 per birth started or loss: stale SDO answers are dropped
    std::size_t unheard_reads = 0;  // objects without a value read for the birth under way
    std::optional<canopen::NmtState> state;
    std::vector<std::string> last_notes;  // logged once while they stay the same
  };

  Device* find(std::uint32_t network, std::uint8_t node);
  Device* find(std::string_view id);
  Device& device(std::uint32_t network, std::uint8_t node);  // creates one for a node not configured
  sparkplug::DeviceModel build(Device& d);
  void begin_birth(Device& d);
  // Objects without a value read for one DBIRTH, besides sparkplug-metrics.
  static constexpr std::size_t kMaxUnheardReads = 64;
  void read_next(Device& d, std::uint64_t generation, std::size_t from);
  void finish_birth(Device& d);
  void data(Device& d, const std::vector<sparkplug::Update>& updates, std::uint64_t now);
  void on_state(Device& d, const canopen::NodeStateEvent& s, std::uint64_t ts);
  void on_written(Device& d, sparkplug::ObjectRef ref, const core::Result& result);
  std::uint64_t stamp(const canopen::Event& ev) const;

  sparkplug::EdgeSession& edge_;
  Send send_;
  Execute execute_;
  std::vector<Network> networks_;
  Sources sources_;
  Options options_;
  Logger& log_;
  std::deque<Device> devices_;  // stable addresses: callbacks keep Device*
  std::map<std::pair<std::uint32_t, std::uint8_t>, Device*> by_node_;
  std::vector<std::string> bus_state_;  // per network (index network-1): the value last sent
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace gateway
