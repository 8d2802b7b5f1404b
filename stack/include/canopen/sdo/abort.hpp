// SDO abort codes (CiA 301 7.2.4.3.17, table 22) as an std::error_code
// category: the error value IS the CiA code, and message() is the
// standard's text, so an error_code can go straight into an abort frame or
// a REST problem document.
#pragma once

#include <cstdint>
#include <string_view>
#include <system_error>

namespace canopen {

enum class SdoAbort : std::uint32_t {
  ToggleNotAlternated = 0x05030000,
  Timeout = 0x05040000,
  InvalidCommand = 0x05040001,
  InvalidBlockSize = 0x05040002,
  InvalidSequenceNumber = 0x05040003,
  CrcError = 0x05040004,
  OutOfMemory = 0x05040005,
  UnsupportedAccess = 0x06010000,
  ReadOfWriteOnly = 0x06010001,
  WriteOfReadOnly = 0x06010002,
  NoSuchObject = 0x06020000,
  NotMappable = 0x06040041,
  PdoLengthExceeded = 0x06040042,
  ParameterIncompatible = 0x06040043,
  DeviceIncompatible = 0x06040047,
  HardwareError = 0x06060000,
  LengthMismatch = 0x06070010,
  LengthTooHigh = 0x06070012,
  LengthTooLow = 0x06070013,
  NoSuchSubIndex = 0x06090011,
  InvalidValue = 0x06090030,
  ValueTooHigh = 0x06090031,
  ValueTooLow = 0x06090032,
  MaxBelowMin = 0x06090036,
  NoSdoConnection = 0x060A0023,
  GeneralError = 0x08000000,
  CannotStore = 0x08000020,
  CannotStoreLocalControl = 0x08000021,
  CannotStoreDeviceState = 0x08000022,
  NoObjectDictionary = 0x08000023,
  NoDataAvailable = 0x08000024,
};

const std::error_category& sdo_abort_category();

inline std::error_code make_error_code(SdoAbort a) {
  return {static_cast<int>(static_cast<std::uint32_t>(a)), sdo_abort_category()};
}

// The standard's text for a code; "Reserved abort code" for unlisted ones.
std::string_view sdo_abort_text(std::uint32_t code);

// The CiA code of an error_code: its value when it is in the SDO abort
// category, GeneralError (0800 0000h) for anything else.
std::uint32_t to_abort_code(std::error_code ec);

}  // namespace canopen

template <>
struct std::is_error_code_enum<canopen::SdoAbort> : std::true_type {};
