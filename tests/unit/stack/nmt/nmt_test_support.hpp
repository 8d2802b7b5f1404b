// Helpers shared by the NMT tests: frames recorded as their can-utils text
// form ("77F#7F", "705#R1") so expectations read like a candump.
#pragma once

#include "canopen/nmt/nmt.hpp"
#include "support/frames.hpp"

namespace canopen::nmt::test {

using canopen::test::FrameLog;
using canopen::test::parse;

}  // namespace canopen::nmt::test
