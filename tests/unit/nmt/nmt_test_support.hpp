// Helpers shared by the NMT tests: frames recorded as their can-utils text
// form ("77F#7F", "705#R1") so expectations read like a candump.
#pragma once

#include <string>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/nmt/nmt.hpp"

namespace canopen::nmt::test {

struct FrameLog {
  std::vector<std::string> frames;
  FrameSink sink() {
    return [this](const can::Frame& f) { frames.push_back(can::to_string(f)); };
  }
  // Returns and forgets what was logged.
  std::vector<std::string> take() {
    std::vector<std::string> out;
    out.swap(frames);
    return out;
  }
};

inline can::Frame parse(const std::string& text) { return can::parse_frame(text).value(); }

}  // namespace canopen::nmt::test
