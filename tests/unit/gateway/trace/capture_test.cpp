// The capture ring (bounded by seconds and bytes, oldest first) and the two
// file forms: candump -L lines (can-utils' log format, so canplayer replays
// them) and pcapng with LINKTYPE_CAN_SOCKETCAN (227), checked byte for byte
// and read back by a second implementation (tests/tools/pcapng_read.py).
#include "trace/capture.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace gateway::trace {
namespace {

using canopen::can::Frame;
using namespace std::chrono_literals;

WallTime at_ns(std::int64_t ns) { return WallTime(std::chrono::duration_cast<WallTime::duration>(std::chrono::nanoseconds(ns))); }

Traced traced(const char* text, std::int64_t ns, Direction d = Direction::Rx) {
  Traced t{*canopen::can::parse_frame(text), d};
  t.frame.timestamp = at_ns(ns);
  return t;
}

std::string hex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (char ch : bytes) {
    const auto c = static_cast<unsigned char>(ch);
    s.push_back(digits[c >> 4]);
    s.push_back(digits[c & 15]);
  }
  return s;
}

// candump -L: "(seconds.microseconds) interface frame", 3 or 8 id digits,
// R with the DLC when non-zero, CAN FD as ##<flags>.
TEST(CandumpLine, AsCandumpLogWritesIt) {
  EXPECT_EQ(candump_line(traced("123#DEADBEEF", 1700000000123456789), "vcan0"),
            "(1700000000.123456) vcan0 123#DEADBEEF\n");
  EXPECT_EQ(candump_line(traced("12345678#01", 5000001), "can1"), "(0000000000.005000) can1 12345678#01\n");
  EXPECT_EQ(candump_line(traced("705#R1", 1700000000000000000), "vcan0"), "(1700000000.000000) vcan0 705#R1\n");
  EXPECT_EQ(candump_line(traced("080#", 1700000000000001000, Direction::Tx), "vcan0"),
            "(1700000000.000001) vcan0 080#\n");
  EXPECT_EQ(candump_line(traced("123##1AABB", 1700000000000000000), "vcan0"), "(1700000000.000000) vcan0 123##5AABB\n");
}

// pcapng: SHB (byte-order magic 1A2B3C4Dh, version 1.0, section length -1),
// IDB (link type 227, snaplen 72, if_name, if_tsresol 9), EPB (interface 0,
// 64-bit ns timestamp, the 16-byte struct can_frame with can_id big-endian,
// epb_flags 1 = inbound).
TEST(Pcapng, BlocksByteExact) {
  EXPECT_EQ(hex(pcapng::section_header("")),
            "0a0d0d0a20000000"
            "4d3c2b1a01000000ffffffffffffffff00000000"
            "20000000");
  EXPECT_EQ(hex(pcapng::interface_description("vcan0")),
            "010000002c000000"
            "e300000048000000"
            "020005007663616e30000000"
            "0900010009000000"
            "00000000"
            "2c000000");
  EXPECT_EQ(hex(pcapng::enhanced_packet(traced("123#DEADBEEF", 1700000000123456789))),
            "060000003c000000"
            "00000000fe9c971715cd853d1000000010000000"
            "0000012304000000deadbeef00000000"
            "0200040001000000"
            "00000000"
            "3c000000");
  // Extended id and RTR set their flags in can_id; sent = outbound (2).
  const auto ext = hex(pcapng::enhanced_packet(traced("12345678#R2", 0, Direction::Tx)));
  EXPECT_NE(ext.find("d234567802000000"), std::string::npos) << ext;
  EXPECT_NE(ext.find("0200040002000000"), std::string::npos) << ext;
}

// A second implementation reads what the writer wrote: same frames, times,
// directions, as candump would print them.
TEST(Pcapng, ReadBackByAnIndependentReader) {
  std::vector<Traced> frames = {traced("000#0100", 1700000000000000000, Direction::Tx),
                                traced("705#05", 1700000000000250000),
                                traced("605#4018100100000000", 1700000000001000000, Direction::Tx),
                                traced("585#4318100178563412", 1700000000001500999),
                                traced("1ABCDEF0#0102", 1700000000002000000),
                                traced("705#R1", 1700000000003000000, Direction::Tx),
                                traced("123##1000102030405060708090A0B", 1700000000004000000)};
  const auto dir = std::filesystem::temp_directory_path() / ("pcapng_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "capture.pcapng";
  {
    std::ofstream out(file, std::ios::binary);
    out << pcapng::file(frames, "vcan0", "canopen-gateway test");
  }
  const std::string cmd = "python3 " CANOPEN_SOURCE_DIR "/tests/tools/pcapng_read.py " + file.string() + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string output;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) output += buf;
  const int rc = ::pclose(p);
  std::filesystem::remove_all(dir);
  ASSERT_EQ(rc, 0) << output;
  std::string expected;
  for (const auto& t : frames) {
    auto line = candump_line(t, "vcan0");
    line.pop_back();
    expected += line + (t.dir == Direction::Rx ? " rx\n" : " tx\n");
  }
  EXPECT_EQ(output, expected);
}

// The ring keeps ring-seconds before its newest frame, oldest dropped first.
TEST(CaptureRing, KeepsTheLastSecondsOldestFirst) {
  CaptureRing ring({10s, 1u << 20});
  for (int i = 0; i < 100; ++i) ring.add(traced("185#01", std::int64_t{i} * 1'000'000'000 / 2));  // 2 per second
  // newest at 49.5 s: kept from 39.5 s on = 21 frames
  ASSERT_EQ(ring.size(), 21u);
  const auto all = ring.since(WallTime{});
  EXPECT_EQ(all.front().frame.timestamp, at_ns(39'500'000'000));
  EXPECT_EQ(all.back().frame.timestamp, at_ns(49'500'000'000));
  EXPECT_EQ(ring.since(at_ns(45'000'000'000)).size(), 10u);
}

// Under load (more frames than max-bytes holds), memory stays within
// max-bytes and the newest frames are the ones kept.
TEST(CaptureRing, BoundedByBytesUnderLoad) {
  const std::size_t max = 64 * 1024;
  CaptureRing ring({60s, max});
  const std::size_t per = CaptureRing::record_bytes(Frame{});
  const std::int64_t n = 200000;
  for (std::int64_t i = 0; i < n; ++i) {
    auto t = traced("185#0102030405060708", 1'000'000'000 + i * 1000);
    t.frame.data[0] = static_cast<std::uint8_t>(i);
    ring.add(t);
    ASSERT_LE(ring.bytes(), max);
  }
  EXPECT_EQ(ring.size(), max / per);
  EXPECT_EQ(ring.dropped_for_bytes(), static_cast<std::uint64_t>(n) - max / per);
  const auto kept = ring.since(WallTime{});
  EXPECT_EQ(kept.back().frame.timestamp, at_ns(1'000'000'000 + (n - 1) * 1000));
  EXPECT_EQ(kept.front().frame.timestamp, at_ns(1'000'000'000 + (n - static_cast<std::int64_t>(kept.size())) * 1000));
  EXPECT_EQ(kept.back().frame.data[0], static_cast<std::uint8_t>(n - 1));
  // CAN FD payloads survive the ring and count their bytes.
  CaptureRing fd({60s, max});
  fd.add(traced("123##1000102030405060708090A0B", 1));
  EXPECT_EQ(fd.bytes(), per + 64);
  EXPECT_EQ(fd.since(WallTime{}).front().frame, *canopen::can::parse_frame("123##1000102030405060708090A0B"));
}

TEST(CaptureRing, ZeroSecondsKeepsNothing) {
  CaptureRing ring({0s, 1u << 20});
  ring.add(traced("185#01", 1));
  EXPECT_EQ(ring.size(), 0u);
}

}  // namespace
}  // namespace gateway::trace
