#include "canopen/lss/error.hpp"

#include <string>

#include "canopen/lss/frames.hpp"

namespace canopen::lss {

namespace {

class Category final : public std::error_category {
 public:
  const char* name() const noexcept override { return "lss"; }
  std::string message(int value) const override {
    switch (static_cast<LssError>(value)) {
      case LssError::Timeout: return "no answer from an LSS slave within the timeout";
      case LssError::NoUnconfiguredSlave: return "no unconfigured LSS slave answered";
      case LssError::ScanFailed: return "LSS fastscan failed: no slave answered a verify step";
      case LssError::QueueFull: return "too many LSS services waiting";
      case LssError::Cancelled: return "LSS service cancelled";
      case LssError::NoFreeNodeId: return "no free node-ID left for an unconfigured LSS slave";
      case LssError::NodeIdOutOfRange: return "LSS slave: node-ID out of range";
      case LssError::NodeIdManufacturer: return "LSS slave: manufacturer-specific error (configure node-ID)";
      case LssError::BitTimingNotSupported: return "LSS slave: bit timing not supported";
      case LssError::BitTimingManufacturer: return "LSS slave: manufacturer-specific error (configure bit timing)";
      case LssError::StoreNotSupported: return "LSS slave: store configuration not supported";
      case LssError::StoreMediaAccess: return "LSS slave: storage media access error";
      case LssError::StoreManufacturer: return "LSS slave: manufacturer-specific error (store configuration)";
    }
    if (value > 0xFF) return "LSS slave: reserved error code " + std::to_string(value & 0xFF);
    return "unknown LSS error";
  }
};

}  // namespace

const std::error_category& lss_category() {
  static const Category category;
  return category;
}

std::optional<std::uint8_t> slave_error_byte(std::error_code ec) {
  if (ec.category() != lss_category() || ec.value() <= 0xFF) return std::nullopt;
  return static_cast<std::uint8_t>(ec.value() & 0xFF);
}

}  // namespace canopen::lss
