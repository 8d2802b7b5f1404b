// COB-ID helpers shared by the EMCY, SYNC and TIME services (CiA 301
// 7.2.5-7.2.7) and whoever reads their COB-ID entries (1005h, 1012h, 1014h).
#pragma once

#include <cstdint>

#include "canopen/can/frame.hpp"

namespace canopen {

// COB-ID bits shared by 1005h, 1012h, 1014h and 1028h.
inline constexpr std::uint32_t kCobIdBit31 = 1U << 31;  // 1014h/1028h: invalid; 1012h: consume
inline constexpr std::uint32_t kCobIdBit30 = 1U << 30;  // 1005h: generate; 1012h: produce
inline constexpr std::uint32_t kCobIdFrame = 1U << 29;  // 29-bit CAN-ID

// The CAN identifier a COB-ID selects (11 or 29 bits, per bit 29).
std::uint32_t can_id_of(std::uint32_t cob_id);
// Whether `f` is a data frame with the identifier and format `cob_id` selects.
bool matches_cob_id(const can::Frame& f, std::uint32_t cob_id);
// A data frame with the identifier and format of `cob_id` carrying `bytes`.
can::Frame frame_for_cob_id(std::uint32_t cob_id, const std::uint8_t* bytes, std::uint8_t len);

}  // namespace canopen
