// An event as it leaves the gateway: encoded once (JSON and protobuf) and
// shared, read-only, by every consumer (MQTT, WebSocket clients, history
// ring), so a fan-out to N consumers costs one encoding, not N.
//
// Thread safety: immutable after construction; share through EncodedEventPtr.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace gateway {

// What an event is about; also the WebSocket filter's "kind" and the last
// MQTT topic level(s) of ../shared/api-contract.md.
enum class EventKind : std::uint8_t {
  Status,        // canopen/<gw>/status (retained)
  Bus,           // canopen/<gw>/<net>/bus (retained)
  State,         // canopen/<gw>/<net>/<node>/state (retained)
  Heartbeat,     // canopen/<gw>/<net>/<node>/heartbeat
  Emcy,          // canopen/<gw>/<net>/<node>/emcy
  Tpdo,          // canopen/<gw>/<net>/<node>/tpdo/<n>
  UnclaimedPdo,  // canopen/<gw>/<net>/pdo/<cobid>
  Sync,          // canopen/<gw>/<net>/sync
  Time,          // canopen/<gw>/<net>/time
  BootConfig,    // canopen/<gw>/<net>/<node>/boot
  Transfer,      // canopen/<gw>/<net>/<node>/transfer
};
inline constexpr EventKind kLastEventKind = EventKind::Transfer;

// "status" "bus" "state" "heartbeat" "emcy" "tpdo" "pdo" "sync" "time" "boot" "transfer"
std::string_view to_string(EventKind k);
// Inverse of to_string; false when unknown.
bool event_kind_from_string(std::string_view s, EventKind& out);

struct EncodedEvent {
  EventKind kind = EventKind::Status;
  std::uint32_t network = 0;  // 1-based; 0 for gateway-level events (status)
  std::uint8_t node = 0;      // 0 when not about one node
  std::uint64_t seq = 0;      // per network, as in the payload
  std::string topic;          // full MQTT topic, e.g. "canopen/gw1/1/5/tpdo/1"
  bool retained = false;
  std::string json;    // proto3 canonical JSON of the message
  std::string binary;  // protobuf wire encoding of the same message; empty for a
                       // PDO encoded without protobuf (EncodeContext::protobuf)
  // The WebSocket frames: EventEnvelope {kind, topic, <kind>: message}, so a
  // client knows what each message is without parsing the topic.
  std::string ws_json;
  std::string ws_binary;
};

using EncodedEventPtr = std::shared_ptr<const EncodedEvent>;

}  // namespace gateway
