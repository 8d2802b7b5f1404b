// Bus load from frame sizes and the bit rate (ISO 11898-1 frame layout,
// worst-case stuffing; see bus_load.hpp).
#include "trace/bus_load.hpp"

#include <gtest/gtest.h>

namespace gateway::trace {
namespace {

using canopen::can::Frame;
using namespace std::chrono_literals;

TEST(BusLoad, FrameBitsPerIso11898) {
  // base frame: 47 + 8n bits + floor((34 + 8n - 1) / 4) stuff bits
  EXPECT_EQ(frame_bits(*canopen::can::parse_frame("080#")), 47u + 8u);
  EXPECT_EQ(frame_bits(*canopen::can::parse_frame("185#0102030405060708")), 47u + 64u + 24u);
  // extended: 67 + 8n + floor((54 + 8n - 1) / 4)
  EXPECT_EQ(frame_bits(*canopen::can::parse_frame("12345678#0102030405060708")), 67u + 64u + 29u);
  // a remote frame carries no data whatever its DLC
  EXPECT_EQ(frame_bits(*canopen::can::parse_frame("705#R1")), 47u + 8u);
}

// 500 frames/s of 8 bytes (135 bits) at 125 kbit/s: 67500 / 125000 = 54 %.
TEST(BusLoad, KnownStreamGivesItsShareOfTheBitRate) {
  const auto start = std::chrono::steady_clock::time_point(1000s);
  BusLoad load(125000, start);
  const auto f = *canopen::can::parse_frame("185#0102030405060708");
  auto t = start;
  for (int i = 0; i < 500 * 12; ++i) {  // 12 s
    t = start + std::chrono::microseconds(2000) * i;
    load.add(f, t);
  }
  const auto now = start + 12s;
  EXPECT_NEAR(*load.percent(1s, now), 54.0, 0.6);
  EXPECT_NEAR(*load.percent(10s, now), 54.0, 0.6);
  // 3 s of silence: the 1 s window is empty, the 10 s window 7/10 of it.
  EXPECT_NEAR(*load.percent(1s, now + 3s), 0.0, 0.01);
  EXPECT_NEAR(*load.percent(10s, now + 3s), 54.0 * 0.7, 0.6);
  EXPECT_NEAR(*load.percent(10s, now + 30s), 0.0, 0.01);
}

// Before a window has passed, the load is over the time since the start,
// not diluted by time that never was.
TEST(BusLoad, YoungMeterUsesItsAge) {
  const auto start = std::chrono::steady_clock::time_point(5s);
  BusLoad load(125000, start);
  const auto f = *canopen::can::parse_frame("185#0102030405060708");
  for (int i = 0; i < 1000; ++i) load.add(f, start + std::chrono::microseconds(2000) * i);  // 2 s
  EXPECT_NEAR(*load.percent(10s, start + 2s), 54.0, 1.0);
}

// A steady clock under 10 s old (a gateway started right after boot, as in
// user-mode Linux): the 10 s window reaches before the clock's epoch, and
// those buckets must not alias the ones that hold the frames (they did, and
// counted each frame twice).
TEST(BusLoad, MeterStartedInTheClocksFirstSecondsCountsEachFrameOnce) {
  const auto start = std::chrono::steady_clock::time_point(500ms);
  BusLoad load(125000, start);
  const auto f = *canopen::can::parse_frame("185#0102030405060708");
  for (int i = 0; i < 500; ++i) load.add(f, start + std::chrono::microseconds(2000) * i);  // 1 s
  EXPECT_NEAR(*load.percent(10s, start + 1s), 54.0, 1.0);
  EXPECT_NEAR(*load.percent(1s, start + 1s), 54.0, 1.0);
}

TEST(BusLoad, UnknownBitRateIsNoNumber) {
  BusLoad load(0, std::chrono::steady_clock::time_point{});
  load.add(Frame{}, std::chrono::steady_clock::time_point(1s));
  EXPECT_FALSE(load.percent(1s, std::chrono::steady_clock::time_point(1s)));
}

}  // namespace
}  // namespace gateway::trace
