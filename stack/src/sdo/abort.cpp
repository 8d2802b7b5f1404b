#include "canopen/sdo/abort.hpp"

#include <string>

namespace canopen {

std::string_view sdo_abort_text(std::uint32_t code) {
  // CiA 301 table 22.
  switch (static_cast<SdoAbort>(code)) {
    case SdoAbort::ToggleNotAlternated: return "Toggle bit not alternated";
    case SdoAbort::Timeout: return "SDO protocol timed out";
    case SdoAbort::InvalidCommand: return "Client/server command specifier not valid or unknown";
    case SdoAbort::InvalidBlockSize: return "Invalid block size (block mode only)";
    case SdoAbort::InvalidSequenceNumber: return "Invalid sequence number (block mode only)";
    case SdoAbort::CrcError: return "CRC error (block mode only)";
    case SdoAbort::OutOfMemory: return "Out of memory";
    case SdoAbort::UnsupportedAccess: return "Unsupported access to an object";
    case SdoAbort::ReadOfWriteOnly: return "Attempt to read a write only object";
    case SdoAbort::WriteOfReadOnly: return "Attempt to write a read only object";
    case SdoAbort::NoSuchObject: return "Object does not exist in the object dictionary";
    case SdoAbort::NotMappable: return "Object cannot be mapped to the PDO";
    case SdoAbort::PdoLengthExceeded:
      return "The number and length of the objects to be mapped would exceed PDO length";
    case SdoAbort::ParameterIncompatible: return "General parameter incompatibility reason";
    case SdoAbort::DeviceIncompatible: return "General internal incompatibility in the device";
    case SdoAbort::HardwareError: return "Access failed due to a hardware error";
    case SdoAbort::LengthMismatch: return "Data type does not match, length of service parameter does not match";
    case SdoAbort::LengthTooHigh: return "Data type does not match, length of service parameter too high";
    case SdoAbort::LengthTooLow: return "Data type does not match, length of service parameter too low";
    case SdoAbort::NoSuchSubIndex: return "Sub-index does not exist";
    case SdoAbort::InvalidValue: return "Invalid value for parameter (download only)";
    case SdoAbort::ValueTooHigh: return "Value of parameter written too high (download only)";
    case SdoAbort::ValueTooLow: return "Value of parameter written too low (download only)";
    case SdoAbort::MaxBelowMin: return "Maximum value is less than minimum value";
    case SdoAbort::NoSdoConnection: return "Resource not available: SDO connection";
    case SdoAbort::GeneralError: return "General error";
    case SdoAbort::CannotStore: return "Data cannot be transferred or stored to the application";
    case SdoAbort::CannotStoreLocalControl:
      return "Data cannot be transferred or stored to the application because of local control";
    case SdoAbort::CannotStoreDeviceState:
      return "Data cannot be transferred or stored to the application because of the present device state";
    case SdoAbort::NoObjectDictionary:
      return "Object dictionary dynamic generation fails or no object dictionary is present";
    case SdoAbort::NoDataAvailable: return "No data available";
  }
  return "Reserved abort code";
}

namespace {

class SdoAbortCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "sdo-abort"; }
  std::string message(int value) const override {
    return std::string(sdo_abort_text(static_cast<std::uint32_t>(value)));
  }
};

}  // namespace

const std::error_category& sdo_abort_category() {
  static const SdoAbortCategory category;
  return category;
}

std::uint32_t to_abort_code(std::error_code ec) {
  if (ec.category() == sdo_abort_category()) return static_cast<std::uint32_t>(ec.value());
  return static_cast<std::uint32_t>(SdoAbort::GeneralError);
}

}  // namespace canopen
