// The devices of `canopen-gateway --demo`: EDS files built into the binary
// (deploy/eds/), so the demo needs no files, hardware or kernel CAN.
#pragma once

#include <cstdint>
#include <vector>

#include "canopen/eds/eds.hpp"
#include "config/config.hpp"

namespace gateway {

// Node 5: a CiA 402 drive; nodes 10 and 11: CiA 401 I/O modules. Each is
// watched by heartbeat, identified and started by the gateway at boot-up.
std::vector<NodeConfig> demo_node_configs();
// The description of a demo node. Throws std::out_of_range for another node.
canopen::eds::DeviceDescription demo_description(std::uint8_t node);
// The demo's new device: a CiA 401 I/O module that starts unconfigured
// (node-ID FFh, LSS only; CiA 305) until a master gives it a node-ID; its
// description at that node-ID. Not in demo_node_configs().
canopen::eds::DeviceDescription demo_new_device_description(std::uint8_t node);

}  // namespace gateway
