// Frame builders and a frame recorder shared by unit tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

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

// Frames recorded as their can-utils text form ("77F#7F", "705#R1",
// "7E5#0401000000000000") so expectations read like a candump.
struct FrameLog {
  std::vector<std::string> frames;
  std::function<void(const can::Frame&)> sink() {
    return [this](const can::Frame& f) { frames.push_back(can::to_string(f)); };
  }
  // Returns and forgets what was logged.
  std::vector<std::string> take() {
    std::vector<std::string> out;
    out.swap(frames);
    return out;
  }
};

// A frame from its can-utils text; the text MUST be valid.
inline can::Frame parse(const std::string& text) { return can::parse_frame(text).value(); }

}  // namespace canopen::test
