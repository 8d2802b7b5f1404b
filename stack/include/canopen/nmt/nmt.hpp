// NMT frame formats shared by the NMT slave and master (CiA 301 7.2.8.3):
// node control on COB-ID 000h, error control (heartbeat, node guarding,
// boot-up) on 700h + node-ID.
//
// Plain functions and values; no thread affinity.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "canopen/can/frame.hpp"
#include "canopen/events.hpp"

namespace canopen::nmt {

// Where the NMT services put the frames they send.
using FrameSink = std::function<void(const can::Frame&)>;

inline constexpr std::uint32_t kNmtCobId = 0x000;
inline constexpr std::uint32_t kErrorControlBase = 0x700;
inline constexpr std::uint8_t kAllNodes = 0;  // node-ID 0 in a node control frame: every node
inline constexpr std::uint8_t kMaxNodeId = 127;
inline constexpr std::uint8_t kToggleBit = 0x80;

// Communication services whose availability depends on the NMT state
// (7.3.2.2.5, table 37; boot-up per 7.2.8.3.3).
enum class Service : std::uint8_t { Pdo, Sdo, Sync, Time, Emcy, NodeControl, ErrorControl, BootUp };

// Node control frame: 000h, 2 bytes: command specifier, node-ID (0 = all).
can::Frame make_command_frame(NmtCommand cs, std::uint8_t node);
// Error control frame: 700h + node, 1 byte: state in bits 0..6, toggle in bit 7.
can::Frame make_error_control_frame(std::uint8_t node, NmtState state, bool toggle = false);
// Boot-up: 700h + node, 1 byte 00h.
can::Frame make_boot_up_frame(std::uint8_t node);
// Node guarding request: remote frame on 700h + node with DLC 1.
can::Frame make_guard_request(std::uint8_t node);

// A decoded node control frame; nullopt unless COB-ID 000h, a classic data
// frame of exactly 2 bytes, a known command and node-ID 0..127.
struct CommandFrame {
  NmtCommand command;
  std::uint8_t node;
};
std::optional<CommandFrame> parse_command_frame(const can::Frame& f);

// Node-ID 1..127 of an error control COB-ID (701h..77Fh, standard frame), else nullopt.
std::optional<std::uint8_t> error_control_node(const can::Frame& f);

}  // namespace canopen::nmt
