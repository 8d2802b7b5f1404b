// Why a maintenance transfer (DCF read-back, DCF apply, program download)
// could not start. These come back from the start calls themselves, never
// through a completion handler.
#pragma once

#include <cstdint>
#include <system_error>

namespace canopen::master {

enum class TransferError : std::uint8_t {
  BadNode = 1,         // node-ID not 1..127
  Busy,                // a transfer is already running for the node (REST: 409)
  BadProgramNumber,    // program number not 1..254 (sub-index of 1F50h/1F51h)
  EmptyImage,          // a program image of 0 bytes
  NothingToTransfer,   // the description has no object to read / the DCF no value to write
  // Not a start error: a program download's 1F56h was not the expected
  // identification (ProgramDownloadReport::error, step ReadIdentification).
  WrongIdentification,
};
const std::error_category& transfer_error_category();
std::error_code make_error_code(TransferError e);

}  // namespace canopen::master

template <>
struct std::is_error_code_enum<canopen::master::TransferError> : std::true_type {};
