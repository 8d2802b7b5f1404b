// LSS errors as an std::error_code category: what went wrong locally (no
// answer, nothing unconfigured, a scan that did not converge, a full queue)
// and what a slave answered (CiA 305 error codes of configure node-ID,
// configure bit timing and store configuration; facts C.1).
//
// A slave's answer is coded as (cs << 8) | error byte, so the service and
// the CiA value are both kept: slave_error_byte() gives the CiA value back
// (e.g. for the ASCII interface). For error FFh (manufacturer-specific) the
// slave's specific byte is in the Error's detail text, not in the code.
#pragma once

#include <cstdint>
#include <optional>
#include <system_error>

namespace canopen::lss {

enum class LssError : int {
  Timeout = 1,              // a confirmed service got no answer within the timeout
  NoUnconfiguredSlave = 2,  // fastscan / assign-all: nobody answered the reset
  ScanFailed = 3,           // fastscan did not converge after its restarts (see master.hpp)
  QueueFull = 4,            // too many services waiting
  Cancelled = 5,            // cancel_all() before the service finished
  NoFreeNodeId = 6,         // assign-all ran out of node-IDs while a device still answered
  // Answers of slaves: (cs << 8) | CiA 305 error code.
  NodeIdOutOfRange = 0x1101,
  NodeIdManufacturer = 0x11FF,
  BitTimingNotSupported = 0x1301,
  BitTimingManufacturer = 0x13FF,
  StoreNotSupported = 0x1701,
  StoreMediaAccess = 0x1702,
  StoreManufacturer = 0x17FF,
};

const std::error_category& lss_category();

inline std::error_code make_error_code(LssError e) { return {static_cast<int>(e), lss_category()}; }
// The code of a slave's error answer to `command` (11h, 13h or 17h); codes
// CiA 305 reserves keep their value and read "reserved error code".
inline std::error_code slave_error(std::uint8_t command, std::uint8_t error) {
  return {(static_cast<int>(command) << 8) | error, lss_category()};
}
// The CiA 305 error byte of a slave's answer; nullopt for anything else.
std::optional<std::uint8_t> slave_error_byte(std::error_code ec);

}  // namespace canopen::lss

template <>
struct std::is_error_code_enum<canopen::lss::LssError> : std::true_type {};
