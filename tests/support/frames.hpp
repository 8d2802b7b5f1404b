// Frame builders shared by unit tests.
#pragma once

#include <cstddef>
#include <cstdint>

#include "canopen/can/frame.hpp"

namespace canopen::test {

// A CAN FD frame of `len` bytes whose payload counts up from `first_byte`.
inline can::Frame fd_frame(std::uint32_t id, std::size_t len, bool extended = false, bool brs = false,
                           bool esi = false, std::uint8_t first_byte = 0xA0) {
  can::Frame f;
  f.id = id;
  f.set(can::FrameFlag::Extended, extended);
  f.set(can::FrameFlag::Fd);
  f.set(can::FrameFlag::BitRateSwitch, brs);
  f.set(can::FrameFlag::ErrorStateIndicator, esi);
  f.len = static_cast<std::uint8_t>(len);
  for (std::size_t i = 0; i < len; ++i) f.data[i] = static_cast<std::uint8_t>(first_byte + i);
  return f;
}

}  // namespace canopen::test
