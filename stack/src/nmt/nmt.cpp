#include "canopen/nmt/nmt.hpp"

namespace canopen::nmt {

can::Frame make_command_frame(NmtCommand cs, std::uint8_t node) {
  return can::Frame::standard(kNmtCobId, {static_cast<std::uint8_t>(cs), node});
}

can::Frame make_error_control_frame(std::uint8_t node, NmtState state, bool toggle) {
  const auto b = static_cast<std::uint8_t>(static_cast<std::uint8_t>(state) | (toggle ? kToggleBit : 0U));
  return can::Frame::standard(kErrorControlBase + node, {b});
}

can::Frame make_boot_up_frame(std::uint8_t node) { return can::Frame::standard(kErrorControlBase + node, {0x00}); }

can::Frame make_guard_request(std::uint8_t node) { return can::Frame::rtr(kErrorControlBase + node, 1); }

std::optional<CommandFrame> parse_command_frame(const can::Frame& f) {
  if (f.id != kNmtCobId || f.extended() || f.remote() || f.fd() || f.len != 2) return std::nullopt;
  const std::uint8_t cs = f.data[0];
  const std::uint8_t node = f.data[1];
  if (node > kMaxNodeId) return std::nullopt;
  switch (static_cast<NmtCommand>(cs)) {
    case NmtCommand::Start:
    case NmtCommand::Stop:
    case NmtCommand::EnterPreOperational:
    case NmtCommand::ResetNode:
    case NmtCommand::ResetCommunication:
      return CommandFrame{static_cast<NmtCommand>(cs), node};
  }
  return std::nullopt;
}

std::optional<std::uint8_t> error_control_node(const can::Frame& f) {
  if (f.extended() || f.fd() || f.id <= kErrorControlBase || f.id > kErrorControlBase + kMaxNodeId) {
    return std::nullopt;
  }
  return static_cast<std::uint8_t>(f.id - kErrorControlBase);
}

}  // namespace canopen::nmt
