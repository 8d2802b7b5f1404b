// One CANopen node as a Sparkplug B device (contract "Sparkplug B"): which
// metrics it has, how stack events change them, and how an NCMD/DCMD write
// becomes a request-core command. Sans-I/O: no sockets, clocks or threads;
// the owner (app/sparkplug_output) feeds events and carries out what comes
// back.
//
// Metrics, in this order:
//   1. every object mapped into the node's TPDOs, then RPDOs, in use now
//      (RemotePdoTable: the EDS/DCF, then what was read from or written to
//      the device; a PDO disabled by COB-ID bit 31, an MPDO and dummy
//      entries map nothing);
//   2. the node's `sparkplug-metrics` objects (no sub: every sub-object of a
//      record/array, sub 0 of a variable), read by SDO for the birth;
//   3. `Node/State` (String, canopen::to_string(NmtState)),
//      `EMCY/Error Code` (UInt16), `EMCY/Error Register` (UInt8),
//      `EMCY/Description` (String).
// `Device Control/Rebirth` is not in the list: EdgeSession adds it to every
// DBIRTH itself. An object appears once, however often it is mapped.
//
// Names: `<object name>` for a VAR/DOMAIN, `<object name>/<sub name>` for a
// sub of a RECORD/ARRAY. A '/' inside an EDS name becomes '-' (it would
// make a folder level), control characters are dropped, spaces trimmed; an
// empty object name is "2301h", an empty sub name "sub 1". Names that the
// EDS gives to more than one object (compared without ASCII case, spec ch5
// case sensitivity), or that equal a fixed metric's, get " 2301h" (VAR) or
// " 2301h sub 1" appended, every one of them: so a name depends only on the
// EDS, not on which objects are mapped now. Objects missing from the EDS
// are named like empty names and typed DOMAIN (Bytes).
//
// Aliases (sparkplug.aliases): alias = network << 32 | node << 24 |
// index << 8 | sub for object metrics; the fixed metrics use index 0 and
// sub 1..4 (Node/State, EMCY/Error Code, EMCY/Error Register,
// EMCY/Description); the edge node's `Network <N>/Bus State` is N << 32
// (node 0, which no device has). Unique over the edge node, the same for
// the same configuration. bdSeq and the Rebirth metrics stay unaliased.
//
// Thread safety: none (plain values; one owner thread).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "canopen/eds/eds.hpp"
#include "canopen/events.hpp"
#include "canopen/pdo/remote_config.hpp"
#include "config/config.hpp"
#include "core/request.hpp"
#include "sparkplug/edge_session.hpp"
#include "sparkplug/payload.hpp"

namespace gateway::sparkplug {

inline constexpr std::string_view kNodeState = "Node/State";
inline constexpr std::string_view kEmcyErrorCode = "EMCY/Error Code";
inline constexpr std::string_view kEmcyErrorRegister = "EMCY/Error Register";
inline constexpr std::string_view kEmcyDescription = "EMCY/Description";

// A CANopen node on one network, for device ids.
struct NodeName {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  std::string name;  // configured `name`, "" = none
};
struct DeviceIds {
  std::vector<std::string> ids;    // parallel to the input
  std::vector<std::string> notes;  // each fallback and why (for the log)
};
// Device id per node: its name, else `net<N>-node<M>`. A name that is not a
// valid topic level (holds '+', '/' or '#') or that several nodes share
// falls back to `net<N>-node<M>` (all of the sharers), with a note.
DeviceIds device_ids(std::span<const NodeName> nodes);

// The edge node's alias of `Network <N>/Bus State`.
std::uint64_t bus_state_alias(std::uint32_t network);
std::string bus_state_name(std::uint32_t network);  // "Network 1/Bus State"

// A stack value as a Sparkplug value of datatype_of(v.type): us as UTF-8, a
// vs that is not UTF-8 read as Latin-1, t as DateTime (UTC ms), td as Int64
// ms, os/d as Bytes.
Value to_sparkplug(const canopen::Value& v);
// A Sparkplug value (as typed_value() gave it for datatype_of(type)) as a
// stack value of `type`, read by the REST/MQTT contract's rules for `type`
// (canopen/literal.hpp), range-checked (i24 in an Int32, ...). Error: the reason.
std::variant<canopen::Value, std::string> typed_for(const Value& v, canopen::DataType type);

class DeviceModel {
 public:
  // What a metric stands for.
  enum class Kind : std::uint8_t { Object, NodeState, EmcyErrorCode, EmcyErrorRegister, EmcyDescription };
  struct Source {
    Kind kind = Kind::Object;
    canopen::DataType type = canopen::DataType::Domain;  // the object's (Object only)
    std::uint16_t tpdo = 0;   // the first TPDO mapping it (0: none)
    std::uint16_t rpdo = 0;   // the first RPDO mapping it (0: none): writes go out as that RPDO
    bool listed = false;      // in sparkplug-metrics: read by SDO for the birth
    bool writable = true;     // by SDO: not ro/const in the EDS
    bool readable = false;    // by SDO: in the EDS and not wo (read for a DBIRTH while it has no value)
  };

  struct Input {
    std::uint32_t network = 0;
    std::uint8_t node = 0;
    std::string device_id;  // from device_ids()
    // The node's EDS/DCF; nullptr = none (then `pdos`' description of the
    // node, if any, names and types the mapped objects).
    const canopen::eds::DeviceDescription* description = nullptr;
    const canopen::pdo::RemotePdoTable* pdos = nullptr;  // nullptr = no PDOs
    std::span<const SparkplugObject> listed;
    bool aliases = false;
  };
  // Never throws on what a vendor file holds; what it left out or changed
  // is in notes().
  static DeviceModel build(const Input& in);

  std::uint32_t network() const { return network_; }
  std::uint8_t node() const { return node_; }
  const std::string& device_id() const { return device_id_; }
  // The metrics with their current values (null until known): what a
  // DBIRTH carries.
  const std::vector<Metric>& metrics() const { return metrics_; }
  const std::vector<Source>& sources() const { return sources_; }
  // Objects left out and names changed, one line each ("TPDO2 maps 2301h
  // sub 1, which the EDS does not describe: left out").
  const std::vector<std::string>& notes() const { return notes_; }
  std::optional<std::size_t> find(ObjectRef object) const;
  std::size_t fixed(Kind kind) const;  // position of a fixed metric

  // Values of the same metrics (same object or name) taken from an older
  // model of the node, so a rebirth shows what is known.
  void carry_values(const DeviceModel& older);

  // Each call keeps the new values and returns the updates of the metrics
  // whose value changed (a first value always counts), stamped `timestamp`
  // (UTC ms). Values for objects that are not metrics are ignored.
  std::vector<Update> on_values(std::span<const canopen::MappedValue> values, std::uint64_t timestamp);
  std::vector<Update> on_value(ObjectRef object, const canopen::Value& value, std::uint64_t timestamp);
  std::vector<Update> on_state(canopen::NmtState state, std::uint64_t timestamp);
  std::vector<Update> on_emcy(const canopen::EmcyEvent& emcy, std::uint64_t timestamp);

  // An NCMD/DCMD write of metric `item.metric` as the command that carries it
  // out: an RPDO-mapped object -> RpdoWrite of that RPDO with
  // {"values":[{"index","subIndex","value"}]} (the transmitter keeps the
  // other mapped values as last sent); any other object -> SdoWrite typed
  // from the EDS. Refused with the reason: the fixed metrics, unknown
  // positions, a value that does not fit the object's type or EDS limits.
  std::variant<core::Command, std::string> command_for(const WriteCommand::Item& item) const;
  // The items of one NCMD/DCMD: as command_for, but the values for one RPDO
  // become one RpdoWrite (one frame; an object given twice: the last value).
  struct Writes {
    struct Write {
      core::Command command;
      std::vector<ObjectRef> objects;  // what it writes, in body order
    };
    std::vector<Write> writes;         // in the order of their first item
    std::vector<std::string> refused;  // one reason per refused item
  };
  Writes writes_for(std::span<const WriteCommand::Item> items) const;

 private:
  std::size_t add(Metric m, Source s);
  std::vector<Update> changed(std::size_t i, Value v, std::uint64_t timestamp);

  std::uint32_t network_ = 0;
  std::uint8_t node_ = 0;
  std::string device_id_;
  std::vector<Metric> metrics_;
  std::vector<Source> sources_;
  std::vector<std::string> notes_;
  // Limits of written values (EDS LowLimit/HighLimit), per metric.
  std::vector<std::optional<canopen::Value>> low_, high_;
};

}  // namespace gateway::sparkplug
