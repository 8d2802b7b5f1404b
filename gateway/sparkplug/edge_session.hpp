// The Sparkplug B 3.0 edge node (contract "Sparkplug B"; facts A.3-A.8),
// sans-I/O: no sockets, timers, clocks or threads. It sits on "an MQTT
// connection" that its owner runs (the wiring: its own client id, clean
// start, MQTT 3.1.1 or 5); the owner feeds it what happened and carries out
// the Outgoing messages it appends, in order.
//
//   connect_params(now)         before every CONNECT attempt: the next bdSeq
//                               (BdSeqStore, durable) and the Will (NDEATH,
//                               QoS 1, not retained) to put in that CONNECT
//   connected(out, now)         CONNACK accepted: SUBSCRIBEs (NCMD, DCMD,
//                               STATE of the Primary Host), then the births
//                               unless a Primary Host has to say online first
//   lost()                      the connection is gone (the broker publishes
//                               the Will)
//   received(out, topic, payload, now)
//                               an incoming PUBLISH: NCMD/DCMD rebirth is
//                               handled here; other commands are returned
//   stop(out, now)              a clean stop: NDEATH, then DISCONNECT
//
// and the CANopen side, whenever it happens (connected or not):
//   set_node_metrics / device_online / device_lost / node_data / device_data
//
// Guarantees (spec ch5/ch6): NBIRTH (seq 0, the bdSeq of this connection's
// Will, `bdSeq`, `Node Control/Rebirth` false and unaliased) and then every
// known device's DBIRTH before any NDATA/DDATA/DDEATH; one seq counter
// 0..255 over all messages but NDEATH; a rebirth (NCMD) repeats the birth
// sequence with the same bdSeq; a device seen while births are pending is
// born with the others; values changed while offline show in the next
// birth. Every message it publishes is QoS 0, not retained, except NDEATH
// (QoS 1).
//
// There is no timer: the Primary Host wait has no timeout in the spec, and
// nothing else here waits. `now` is UTC milliseconds since 1970 (Sparkplug
// timestamps), taken by the owner from its wall clock.
//
// Thread safety: none; one owner thread.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sparkplug/bdseq_store.hpp"
#include "sparkplug/payload.hpp"

namespace gateway::sparkplug {

inline constexpr std::string_view kNamespace = "spBv1.0";
inline constexpr std::string_view kBdSeq = "bdSeq";
inline constexpr std::string_view kNodeRebirth = "Node Control/Rebirth";
inline constexpr std::string_view kDeviceRebirth = "Device Control/Rebirth";

// What the owner must do, in this order.
struct Outgoing {
  enum class Kind : std::uint8_t {
    Publish,     // topic, payload, qos, retain
    Subscribe,   // topic (a filter), qos
    Disconnect,  // a clean DISCONNECT; on MQTT 5 with reason 0x04 "Disconnect
                 // with Will Message" (spec ch5 intentional disconnect)
  };
  Kind kind = Kind::Publish;
  std::string topic;
  std::string payload;
  std::uint8_t qos = 0;
  bool retain = false;
};

// One changed value of a known metric: its position in the list given to
// set_node_metrics / device_online.
struct Update {
  std::size_t metric = 0;
  Value value;
  std::uint64_t timestamp = 0;  // UTC ms (the CAN frame's)
};

// A command for the owner (item 4 of the issue: writes through the request
// core): every metric resolved to the device's (or node's) metric, with its
// value converted to that metric's type. Rebirth requests never get here.
struct WriteCommand {
  std::string device;  // "" for NCMD
  struct Item {
    std::size_t metric = 0;  // position in the device's (node's) metrics
    Value value;
  };
  std::vector<Item> items;
  // Metrics that were unknown, or whose value did not fit their type (to be
  // logged; the spec has no command response).
  std::vector<std::string> refused;
  // A Rebirth was asked (of `device`, or of the node: every device) and
  // Options::owner_reads_rebirths is set: the owner reads the devices'
  // values again and calls device_online() for each DBIRTH.
  bool rebirth = false;
};

class EdgeSession {
 public:
  struct Options {
    std::string group_id;      // G: no '+', '/', '#'
    std::string edge_node_id;  // E: the same
    // sparkplug.primary-host-id; "" = none (births right after CONNECT).
    std::string primary_host_id;
    // An NCMD/DCMD Rebirth: the session sends the NBIRTH (node) and leaves
    // the DBIRTHs to the owner, which reads the values again first and
    // calls device_online() (WriteCommand::rebirth). false: the DBIRTHs go
    // out at once with the values kept.
    bool owner_reads_rebirths = false;
  };
  struct ConnectParams {
    std::uint8_t bd_seq = 0;
    std::string will_topic;    // spBv1.0/G/NDEATH/E
    std::string will_payload;  // Payload with only the bdSeq metric (Int64)
    std::uint8_t will_qos = 1;
    bool will_retain = false;
    bool clean_start = true;   // and MQTT 5 Session Expiry Interval 0
    std::string store_note;    // BdSeqStore::Next::note / error, for the log
  };
  enum class State : std::uint8_t {
    Offline,          // no connection
    WaitingForHost,   // connected; the Primary Host has not said online
    Born,             // connected; NBIRTH and every DBIRTH sent
    Stopping,         // NDEATH and DISCONNECT handed out; waiting for lost()
  };

  // store MUST outlive the session. Throws std::invalid_argument for ids
  // with '+', '/' or '#' or empty ones (spec ch4).
  EdgeSession(Options opts, BdSeqStore& store);

  // --- the MQTT connection ------------------------------------------------
  // `now`: ms since the epoch, the Will's (NDEATH's) timestamp.
  ConnectParams connect_params(std::uint64_t now);
  void connected(std::vector<Outgoing>& out, std::uint64_t now);
  void lost();
  // Handles a PUBLISH on one of the subscribed topics. Returns the
  // non-rebirth command metrics of an NCMD/DCMD, if any.
  std::optional<WriteCommand> received(std::vector<Outgoing>& out, std::string_view topic, std::string_view payload,
                                       std::uint64_t now);
  // The whole birth sequence again (NBIRTH seq 0, same bdSeq, every
  // DBIRTH), as an NCMD rebirth does, when born; nothing otherwise. For the
  // owner after it had to drop DATA (a seq gap the host cannot repair).
  void rebirth(std::vector<Outgoing>& out, std::uint64_t now);
  // Intentional disconnect: NDEATH (same bdSeq as the Will) and DISCONNECT.
  // Nothing when not connected.
  void stop(std::vector<Outgoing>& out, std::uint64_t now);

  // --- the node's and devices' metrics ------------------------------------
  // The edge node's own metrics beyond bdSeq and Node Control/Rebirth
  // (which the session adds); per network `Network <N>/Bus State`. Takes
  // effect at the next NBIRTH (a rebirth, if born now).
  void set_node_metrics(std::vector<Metric> metrics, std::vector<Outgoing>& out, std::uint64_t now);
  // A device is heard (again), or its metric set changed: DBIRTH now if
  // born, else with the next births. Its metrics as a whole (values current).
  // False (and nothing done) for an id that is empty or holds '+', '/' or '#'.
  bool device_online(std::vector<Outgoing>& out, std::string device_id, std::vector<Metric> metrics,
                     std::uint64_t now);
  // The device is lost: DDEATH if it was born in this session. Its metrics
  // are kept, for a later device_online() to replace.
  void device_lost(std::vector<Outgoing>& out, std::string_view device_id, std::uint64_t now);
  // Changed values: NDATA/DDATA with exactly these metrics when born (and
  // the device online); otherwise only kept for the next birth. Unknown
  // metric positions are skipped.
  void node_data(std::vector<Outgoing>& out, std::span<const Update> updates, std::uint64_t now);
  void device_data(std::vector<Outgoing>& out, std::string_view device_id, std::span<const Update> updates,
                   std::uint64_t now);

  // --- state ---------------------------------------------------------------
  State state() const { return state_; }
  std::optional<std::uint8_t> bd_seq() const { return bd_seq_; }
  std::uint8_t next_seq() const { return seq_; }
  std::optional<std::uint64_t> last_rebirth() const { return last_rebirth_; }  // UTC ms of the latest NBIRTH
  bool host_online() const { return host_online_; }
  const std::string& topic_prefix() const { return prefix_; }  // "spBv1.0/G/"

 private:
  struct Device {
    std::string id;
    std::vector<Metric> metrics;
    bool online = false;
    bool born = false;  // DBIRTH sent in this session and no DDEATH since
  };

  std::string node_topic(std::string_view type) const;
  std::string device_topic(std::string_view type, std::string_view device) const;
  // NBIRTH, then every online device's DBIRTH unless with_devices is false
  // (those devices are unborn until device_online()).
  void births(std::vector<Outgoing>& out, std::uint64_t now, bool with_devices = true);
  void dbirth(std::vector<Outgoing>& out, Device& d, std::uint64_t now);
  std::string ndeath_payload(std::uint64_t now) const;
  std::uint8_t take_seq();
  void publish(std::vector<Outgoing>& out, std::string topic, std::string payload, std::uint8_t qos = 0);
  void end_session(std::vector<Outgoing>& out, std::uint64_t now);
  void handle_state(std::vector<Outgoing>& out, std::string_view payload, std::uint64_t now);
  std::optional<WriteCommand> handle_command(std::vector<Outgoing>& out, const Command& cmd, Device* device,
                                             std::uint64_t now);
  Device* find(std::string_view id);

  Options opts_;
  BdSeqStore& store_;
  std::string prefix_;  // spBv1.0/G/
  State state_ = State::Offline;
  std::optional<std::uint8_t> bd_seq_;
  std::uint8_t seq_ = 0;  // the next message's seq
  std::optional<std::uint64_t> last_rebirth_;
  std::vector<Metric> node_metrics_;
  std::vector<Device> devices_;
  // Primary Host: online as last seen, and the timestamp of the latest
  // STATE accepted (kept across connections: older ones are stale).
  bool host_online_ = false;
  std::optional<std::uint64_t> host_timestamp_;
};

}  // namespace gateway::sparkplug
