#include "canopen/cob_id.hpp"

#include <algorithm>

namespace canopen {

std::uint32_t can_id_of(std::uint32_t cob_id) {
  return (cob_id & kCobIdFrame) != 0 ? (cob_id & can::kMaxExtendedId) : (cob_id & can::kMaxStandardId);
}

bool matches_cob_id(const can::Frame& f, std::uint32_t cob_id) {
  if (f.remote() || f.extended() != ((cob_id & kCobIdFrame) != 0)) return false;
  return f.id == can_id_of(cob_id);
}

can::Frame frame_for_cob_id(std::uint32_t cob_id, const std::uint8_t* bytes, std::uint8_t len) {
  can::Frame f;
  f.id = can_id_of(cob_id);
  f.set(can::FrameFlag::Extended, (cob_id & kCobIdFrame) != 0);
  f.len = std::min<std::uint8_t>(len, static_cast<std::uint8_t>(can::kMaxClassicLength));
  std::copy_n(bytes, f.len, f.data.begin());
  return f;
}

}  // namespace canopen
