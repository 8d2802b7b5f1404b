// Stack-level events: what the CANopen services report to the gateway
// (CiA 301 services seen from the NMT master's side). Each service emits
// event bodies with the receive timestamp of the frame that caused them;
// the network that owns the services stamps each with a per-network
// sequence number (Event::seq) before handing it on, so a consumer sees
// gaps.
//
// Plain values; no thread affinity.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <system_error>
#include <variant>
#include <vector>

#include "canopen/can/bus_state.hpp"
#include "canopen/can/frame.hpp"
#include "canopen/types.hpp"

namespace canopen {

// NMT states as carried in heartbeat / node guarding messages (7.2.8.3.2).
enum class NmtState : std::uint8_t {
  Initialising = 0x00,  // boot-up message
  Stopped = 0x04,
  Operational = 0x05,
  PreOperational = 0x7F,
};
std::string_view to_string(NmtState s);  // "initialising", "stopped", "operational", "pre-operational"
std::optional<NmtState> nmt_state_from_byte(std::uint8_t b);  // ignores the toggle bit 7

// NMT node control commands (7.2.8.3.1): command specifier values.
enum class NmtCommand : std::uint8_t {
  Start = 0x01,
  Stop = 0x02,
  EnterPreOperational = 0x80,
  ResetNode = 0x81,
  ResetCommunication = 0x82,
};

struct NodeStateEvent {
  enum class Cause : std::uint8_t { BootUp, Heartbeat, NodeGuarding, Lost, Recovered };
  std::uint8_t node = 0;
  std::optional<NmtState> state;     // nullopt for Lost
  std::optional<NmtState> previous;  // nullopt when the node was unknown
  Cause cause = Cause::Heartbeat;
};

struct HeartbeatEvent {
  std::uint8_t node = 0;
  NmtState state = NmtState::PreOperational;
};

struct EmcyEvent {
  std::uint8_t node = 0;
  std::uint16_t error_code = 0;  // 0000h: error reset / no error
  std::uint8_t error_register = 0;
  std::array<std::uint8_t, 5> manufacturer{};
  std::string description;  // text of the error code class (7.2.7.1, table 21)
};

struct MappedValue {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::string name;
  Value value;
};

// Addressing of a PdoEvent decoded from an MPDO (7.2.3.4.1).
struct MpdoInfo {
  bool destination_mode = false;  // true: DAM (address = consumer, 0 = all); false: SAM (address = producer)
  std::uint8_t address = 0;
  std::uint16_t index = 0;  // multiplexer as sent
  std::uint8_t sub = 0;
  // SAM matched by a dispatcher list entry (1FD0h-1FFFh): the local object it goes to.
  std::optional<std::uint16_t> local_index;
  std::optional<std::uint8_t> local_sub;
};

struct PdoEvent {
  std::uint8_t node = 0;        // 0 when no configured node claims the COB-ID
  std::uint16_t number = 0;     // TPDO number of the node, 1-based; 0 when unclaimed
  std::uint32_t cob_id = 0;
  Bytes raw;
  std::vector<MappedValue> values;
  std::optional<std::string> error;  // e.g. length does not match the mapping
  std::optional<MpdoInfo> mpdo;      // set when the frame was an MPDO
};

struct SyncEvent {
  std::optional<std::uint8_t> counter;
};

struct TimeEvent {
  TimeOfDay time;
};

// Boot-up configuration of a node (in the spirit of CiA 302), one event per step.
// 1000h and 1018h sub 1-4 as read from a device (sub 2-4 are optional in
// CiA 301 7.5.2.26; 0 when the device does not have them).
struct DeviceIdentity {
  std::uint32_t device_type = 0;
  std::uint32_t vendor_id = 0;
  std::uint32_t product_code = 0;
  std::uint32_t revision = 0;
  std::uint32_t serial = 0;
};

struct BootConfigEvent {
  enum class Step : std::uint8_t { Identify, CheckIdentity, Configure, Start, Done, Failed };
  std::uint8_t node = 0;
  Step step = Step::Identify;
  std::error_code error;  // SDO abort or timeout when the step failed
  std::string detail;
  std::optional<DeviceIdentity> identity;  // CheckIdentity: what the device answered
};

// Progress and result of a long transfer to or from one node (contract
// "Remote configuration and maintenance", events of kind `transfer`): a
// program download (CiA 302-3, 1F50h) counts bytes, a DCF read-back or
// apply counts objects. Running events report progress (at least at the
// start and at the end of the data phase); exactly one Done or Failed ends
// each transfer.
struct TransferEvent {
  enum class Operation : std::uint8_t { ProgramDownload, DcfRead, DcfApply };
  enum class Status : std::uint8_t { Running, Done, Failed };
  std::uint8_t node = 0;
  Operation operation = Operation::ProgramDownload;
  Status status = Status::Running;
  std::uint64_t done = 0;   // bytes (ProgramDownload) or objects (DCF) so far
  std::uint64_t total = 0;  // of as many
  std::error_code error;    // Failed: the SDO abort or local error
  std::string detail;       // the step ("clear program", "1F50h sub 1", ...) or why it failed
};

using EventBody = std::variant<NodeStateEvent, HeartbeatEvent, EmcyEvent, PdoEvent, SyncEvent, TimeEvent,
                               BootConfigEvent, can::BusEvent, TransferEvent>;

struct Event {
  std::uint64_t seq = 0;                         // per network, +1 per event
  can::Frame::Clock::time_point timestamp{};     // receive time of the causing frame
  EventBody body;
};

}  // namespace canopen
