#include "canopen/events.hpp"

namespace canopen {

std::string_view to_string(NmtState s) {
  switch (s) {
    case NmtState::Initialising: return "initialising";
    case NmtState::Stopped: return "stopped";
    case NmtState::Operational: return "operational";
    case NmtState::PreOperational: return "pre-operational";
  }
  return "unknown";
}

std::optional<NmtState> nmt_state_from_byte(std::uint8_t b) {
  switch (b & 0x7F) {
    case 0x00: return NmtState::Initialising;
    case 0x04: return NmtState::Stopped;
    case 0x05: return NmtState::Operational;
    case 0x7F: return NmtState::PreOperational;
    default: return std::nullopt;
  }
}

}  // namespace canopen
