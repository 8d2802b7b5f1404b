// One line of CANopen meaning per CAN frame, for the bus trace
// (GET /api/v1/networks/{net}/trace): which CiA 301 service a frame belongs
// to by its COB-ID in the predefined connection set (CiA 301 7.3.5), its
// node and a short summary, e.g. "NMT start all", "SYNC 5", "EMCY 5 3210h
// register 04h", "TPDO1 5", "SDO tx 5 upload 1018h:01", "HB 5 operational",
// "LSS switch state global configuration". Frames outside the set (and
// 29-bit ids) are "raw".
//
// SDO rx/tx are named from the gateway's point of view: the gateway is the
// SDO client of every other node, so 600h+N (client -> server N) is
// "SDO tx N" and 580h+N (server N -> client) is "SDO rx N"; for the
// gateway's own node-ID it is the server, and the names swap (600h+own is
// "SDO rx own"). The names follow the COB-IDs, not who sent the frame: a
// third-party client talking to node N is shown the same way.
//
// A block transfer's sub-block data frames cannot be told from commands by
// their bytes; SdoBlockTracker follows the block transfers on the bus so
// decode() names them "segment". Everything else is one pure function.
//
// Thread safety: none needed (pure functions; a tracker per network, used
// on one thread).
#pragma once

#include <bitset>
#include <cstdint>
#include <string>
#include <string_view>

#include "canopen/can/frame.hpp"

namespace gateway::trace {

// Which SDO channels (by server node-ID 1..127) are inside the sub-block
// phase of a block transfer: download (client sends segments on 600h+N)
// or upload (server sends segments on 580h+N).
struct SdoBlockState {
  std::bitset<128> download, upload;
};

struct DecodeContext {
  std::uint8_t own_node_id = 0;  // the gateway's node-ID on this network (0: none)
  SdoBlockState block;
};

// The summary of `f`; never empty.
std::string decode(const canopen::can::Frame& f, const DecodeContext& ctx);

// The same classification as structured fields, for clients that filter
// (the dashboard's trace view): a short stable token per service and the
// node a frame is about. Service tokens: "nmt", "sync", "time", "emcy",
// "tpdo", "rpdo", "sdo", "error-control" (heartbeat, boot-up, node
// guarding), "lss", "other" (what decode() calls "raw"). node: the node-ID
// in the COB-ID (EMCY, PDO, SDO, error control) or the one an NMT command
// addresses; 0 = none (broadcast NMT, SYNC, TIME, LSS, other).
struct Service {
  std::string_view service;  // static storage
  std::uint8_t node = 0;
};
Service classify(const canopen::can::Frame& f);

// Follows block transfers (CiA 301 7.2.4.3.9-15): call with every frame in
// bus order, after decode() of the same frame.
void track_sdo_block(const canopen::can::Frame& f, SdoBlockState& state);

}  // namespace gateway::trace
