// Stack events -> the gateway's outgoing messages (../shared/api-contract.md):
// each event is encoded once, into its MQTT topic, retained flag, proto3
// canonical JSON and protobuf binary (proto/canopen_gateway.proto), and the
// result is shared by MQTT, WebSocket and history.
//
// Topics (<gw> = EncodeContext::gateway_id, <net> and <node> decimal):
//   canopen/<gw>/status                      retained  GatewayStatus
//   canopen/<gw>/<net>/bus                   retained  BusStateEvent
//   canopen/<gw>/<net>/<node>/state          retained  NodeStateEvent (state "lost" when lost)
//   canopen/<gw>/<net>/<node>/heartbeat                HeartbeatEvent
//   canopen/<gw>/<net>/<node>/emcy                     EmcyEvent
//   canopen/<gw>/<net>/<node>/tpdo/<n>                 PdoEvent (n 1-based, decimal)
//   canopen/<gw>/<net>/pdo/<cobid>                     UnclaimedPdo; CAN-ID in uppercase
//                                                      hex, 3 digits for 11-bit IDs
//                                                      ("1A5"), 8 for 29-bit ones
//   canopen/<gw>/<net>/sync                            SyncEvent
//   canopen/<gw>/<net>/time                            TimeEvent
//   canopen/<gw>/<net>/<node>/boot                     BootConfigEvent
//   canopen/<gw>/<net>/<node>/transfer                 TransferEvent
//
// JSON equals, by value, what google::protobuf::util::MessageToJsonString
// prints for the same message with always_print_primitive_fields = true and
// the other options at their defaults (lowerCamelCase names, uint64 as
// strings, unset `optional` fields and sub-messages left out). It is written
// directly because that printer costs ~15 µs per PDO; number spelling may
// differ (reals are the shortest text that reads back to the same double).
// `binary` is SerializeToString of the message.
//
// EncodeContext needs no per-node data: a PdoEvent already names its node
// and TPDO number; one with node 0 or number 0 is an UnclaimedPdo.
//
// Thread safety: pure functions; call from any thread. The result is
// immutable.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/events.hpp"
#include "event_message.hpp"

namespace gateway {

struct EncodeContext {
  // MQTT topic level after "canopen"; must be a valid topic level (not
  // empty, no '/', '+', '#'), see valid_gateway_id().
  std::string gateway_id;
  // Whether PDO events get their binary protobuf payload (and its WebSocket
  // envelope); the JSON payload and envelope are always built. Building the
  // protobuf message is most of a PDO's encoding cost, so it is left out
  // when no consumer can want it (MQTT format JSON and no WebSocket client
  // asking for protobuf); EncodedEvent::binary is then empty. Other kinds,
  // rare, always have both.
  bool protobuf = true;
};

bool valid_gateway_id(std::string_view id);

// Encodes one stack event of network `network` (1-based).
EncodedEventPtr encode_event(const canopen::Event& ev, std::uint32_t network, const EncodeContext& ctx);

// Gateway-level status (canopen/<gw>/status, retained). `online = false`
// is the MQTT Will.
struct GatewayStatusInfo {
  bool online = true;
  std::string version;
  std::uint64_t uptime_ms = 0;
  std::uint8_t node_id = 127;          // the gateway's own CANopen node-ID
  std::vector<std::uint32_t> networks;  // configured network numbers
  std::chrono::system_clock::time_point timestamp{};
};
EncodedEventPtr encode_status(const GatewayStatusInfo& status, const EncodeContext& ctx);

// Topic builders (the same strings encode_event uses).
std::string node_topic(const EncodeContext& ctx, std::uint32_t network, std::uint8_t node, std::string_view leaf);
std::string network_topic(const EncodeContext& ctx, std::uint32_t network, std::string_view leaf);
// canopen/<gateway_id>/status: the retained status and the MQTT Will.
std::string status_topic(std::string_view gateway_id);
// "1A5" for 11-bit CAN-IDs, "1ABCDEF0" (8 digits) for 29-bit ones.
std::string cob_id_topic_level(std::uint32_t cob_id);

// The WebSocket frame of an event: proto EventEnvelope {kind, topic, <kind>:
// event}, built from the already encoded payloads without re-encoding.
std::string envelope_json(const EncodedEvent& ev);
std::string envelope_binary(const EncodedEvent& ev);

}  // namespace gateway
