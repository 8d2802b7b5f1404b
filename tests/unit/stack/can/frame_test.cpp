// Tests for stack/src/can/frame.cpp: the CAN/CAN FD frame value type and its
// cansend / candump -L text form.
#include "canopen/can/frame.hpp"
#include "support/frames.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace canopen::can {
namespace {

std::vector<std::uint8_t> counting_bytes(std::size_t n, std::uint8_t first = 0) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(first + i);
  return v;
}

using test::fd_frame;

// ---- FD lengths --------------------------------------------------------------

TEST(FdLength, LengthsUpToEightAreUnchanged) {
  for (std::size_t len = 0; len <= 8; ++len) {
    EXPECT_EQ(fd_round_up_length(len), len) << len;
    EXPECT_TRUE(is_valid_fd_length(len)) << len;
  }
}

TEST(FdLength, RoundsUpToNextDlcStep) {
  EXPECT_EQ(fd_round_up_length(9), 12U);
  EXPECT_EQ(fd_round_up_length(12), 12U);
  EXPECT_EQ(fd_round_up_length(13), 16U);
  EXPECT_EQ(fd_round_up_length(17), 20U);
  EXPECT_EQ(fd_round_up_length(21), 24U);
  EXPECT_EQ(fd_round_up_length(25), 32U);
  EXPECT_EQ(fd_round_up_length(33), 48U);
  EXPECT_EQ(fd_round_up_length(49), 64U);
  EXPECT_EQ(fd_round_up_length(64), 64U);
}

TEST(FdLength, OnlyTheDlcStepsAboveEightAreValid) {
  const std::array<std::size_t, 7> steps{12, 16, 20, 24, 32, 48, 64};
  for (std::size_t len = 9; len <= 70; ++len) {
    const bool is_step = std::find(steps.begin(), steps.end(), len) != steps.end();
    EXPECT_EQ(is_valid_fd_length(len), is_step) << len;
  }
}

// ---- Builders and validity ---------------------------------------------------

TEST(Frame, StandardBuilderCopiesPayload) {
  const Frame f = Frame::standard(0x181, {0x11, 0x22, 0x33});
  EXPECT_EQ(f.id, 0x181U);
  EXPECT_FALSE(f.extended());
  EXPECT_FALSE(f.remote());
  EXPECT_FALSE(f.fd());
  ASSERT_EQ(f.len, 3);
  EXPECT_EQ(f.data[0], 0x11);
  EXPECT_EQ(f.data[1], 0x22);
  EXPECT_EQ(f.data[2], 0x33);
  EXPECT_EQ(f.payload().size(), 3U);
  EXPECT_TRUE(f.valid());
}

TEST(Frame, ExtendedBuilderSetsExtendedFlag) {
  const std::array<std::uint8_t, 2> bytes{0xCA, 0xFE};
  const Frame f = Frame::extended_id(0x18FF50E5, bytes);
  EXPECT_TRUE(f.extended());
  EXPECT_EQ(f.id, 0x18FF50E5U);
  EXPECT_EQ(f.len, 2);
  EXPECT_TRUE(f.valid());
}

TEST(Frame, BuilderWithMoreThanEightBytesMakesFdFrame) {
  const auto bytes = counting_bytes(12);
  const Frame f = Frame::standard(0x123, bytes);
  EXPECT_TRUE(f.fd());
  EXPECT_EQ(f.len, 12);
  EXPECT_TRUE(f.valid());
}

TEST(Frame, BuilderWithNonFdLengthProducesInvalidFrame) {
  const auto bytes = counting_bytes(10);
  const Frame f = Frame::standard(0x123, bytes);
  EXPECT_FALSE(f.valid());
}

TEST(Frame, RtrBuilderCarriesDlcAndNoPayload) {
  const Frame f = Frame::rtr(0x701, 1);
  EXPECT_TRUE(f.remote());
  EXPECT_FALSE(f.extended());
  EXPECT_EQ(f.len, 1);
  EXPECT_TRUE(f.payload().empty());
  EXPECT_TRUE(f.valid());
  EXPECT_TRUE(Frame::rtr(0x1ABCDEF0, 8, true).extended());
}

TEST(Frame, StandardIdBoundaryIs7FF) {
  EXPECT_TRUE(Frame::standard(kMaxStandardId, {}).valid());
  EXPECT_FALSE(Frame::standard(kMaxStandardId + 1, {}).valid());
}

TEST(Frame, ExtendedIdBoundaryIs1FFFFFFF) {
  const std::array<std::uint8_t, 0> none{};
  EXPECT_TRUE(Frame::extended_id(kMaxExtendedId, none).valid());
  EXPECT_FALSE(Frame::extended_id(kMaxExtendedId + 1, none).valid());
  // A 29-bit id is fine in an extended frame, not in a standard one.
  EXPECT_TRUE(Frame::extended_id(0x800, none).valid());
  EXPECT_FALSE(Frame::standard(0x800, {}).valid());
}

TEST(Frame, ClassicLengthLimitIsEight) {
  Frame f = Frame::standard(0x100, {});
  f.len = 8;
  EXPECT_TRUE(f.valid());
  f.len = 9;
  EXPECT_FALSE(f.valid());
}

TEST(Frame, RemoteFrameDlcLimitIsEight) {
  EXPECT_TRUE(Frame::rtr(0x100, 8).valid());
  EXPECT_FALSE(Frame::rtr(0x100, 9).valid());
}

TEST(Frame, FdFrameLengthMustBeAnFdLength) {
  for (std::size_t len : {0U, 5U, 8U, 12U, 16U, 20U, 24U, 32U, 48U, 64U}) {
    EXPECT_TRUE(fd_frame(0x123, len).valid()) << len;
  }
  for (std::size_t len : {9U, 10U, 11U, 13U, 15U, 33U, 63U}) {
    EXPECT_FALSE(fd_frame(0x123, len).valid()) << len;
  }
}

TEST(Frame, RemoteFdFrameIsInvalid) {
  Frame f = fd_frame(0x123, 0);
  f.set(FrameFlag::Remote);
  EXPECT_FALSE(f.valid());
}

TEST(Frame, BrsOrEsiOnClassicFrameIsInvalid) {
  Frame brs = Frame::standard(0x123, {1});
  brs.set(FrameFlag::BitRateSwitch);
  EXPECT_FALSE(brs.valid());
  Frame esi = Frame::standard(0x123, {1});
  esi.set(FrameFlag::ErrorStateIndicator);
  EXPECT_FALSE(esi.valid());
  EXPECT_TRUE(fd_frame(0x123, 8, false, true, true).valid());
}

TEST(Frame, SetAndClearFlags) {
  Frame f;
  f.set(FrameFlag::Fd);
  f.set(FrameFlag::BitRateSwitch);
  EXPECT_TRUE(f.fd());
  EXPECT_TRUE(f.has(FrameFlag::BitRateSwitch));
  f.set(FrameFlag::Fd, false);
  EXPECT_FALSE(f.fd());
  EXPECT_TRUE(f.has(FrameFlag::BitRateSwitch));
}

TEST(Frame, EqualityIgnoresTimestampAndBytesBeyondLength) {
  Frame a = Frame::standard(0x123, {1, 2});
  Frame b = a;
  b.timestamp = Frame::Clock::now();
  b.data[5] = 0xEE;  // not part of the payload
  EXPECT_EQ(a, b);
  b.data[1] = 3;
  EXPECT_NE(a, b);
}

TEST(Frame, EqualityComparesIdFlagsAndLength) {
  const Frame a = Frame::standard(0x123, {1, 2});
  EXPECT_NE(a, Frame::standard(0x124, {1, 2}));
  EXPECT_NE(a, Frame::standard(0x123, {1, 2, 0}));
  const std::array<std::uint8_t, 2> bytes{1, 2};
  EXPECT_NE(a, Frame::extended_id(0x123, bytes));
}

TEST(Frame, RemoteFramesCompareByDlcNotData) {
  Frame a = Frame::rtr(0x123, 4);
  Frame b = Frame::rtr(0x123, 4);
  a.data[0] = 0x55;  // stale bytes are not part of a remote frame
  EXPECT_EQ(a, b);
  EXPECT_NE(a, Frame::rtr(0x123, 5));
}

// ---- Text form -----------------------------------------------------------

TEST(FrameText, ClassicStandardFrameToString) {
  EXPECT_EQ(to_string(Frame::standard(0x123, {0xDE, 0xAD, 0xBE, 0xEF})), "123#DEADBEEF");
  EXPECT_EQ(to_string(Frame::standard(0x001, {0x0A})), "001#0A");
  EXPECT_EQ(to_string(Frame::standard(0x7FF, {})), "7FF#");
}

TEST(FrameText, ExtendedFrameUsesEightIdDigits) {
  const std::array<std::uint8_t, 1> b{0x01};
  EXPECT_EQ(to_string(Frame::extended_id(0x12345678, b)), "12345678#01");
  // A small id in an extended frame is still printed with 8 digits.
  EXPECT_EQ(to_string(Frame::extended_id(0x123, b)), "00000123#01");
}

TEST(FrameText, RemoteFramesToString) {
  EXPECT_EQ(to_string(Frame::rtr(0x123, 0)), "123#R");
  EXPECT_EQ(to_string(Frame::rtr(0x123, 4)), "123#R4");
  EXPECT_EQ(to_string(Frame::rtr(0x12345678, 8, true)), "12345678#R8");
}

TEST(FrameText, FdFramesPrintFlagsNibbleWithFdfLikeCandump) {
  // candump -L prints the canfd_frame flags nibble: FDF (4) | ESI (2) | BRS (1).
  Frame f = fd_frame(0x123, 2);
  f.data[0] = 0xAA;
  f.data[1] = 0xBB;
  EXPECT_EQ(to_string(f), "123##4AABB");
  f.set(FrameFlag::BitRateSwitch);
  EXPECT_EQ(to_string(f), "123##5AABB");
  f.set(FrameFlag::ErrorStateIndicator);
  EXPECT_EQ(to_string(f), "123##7AABB");
  f.set(FrameFlag::BitRateSwitch, false);
  EXPECT_EQ(to_string(f), "123##6AABB");
}

TEST(FrameText, Fd64ByteFramePrintsAllBytes) {
  const Frame f = fd_frame(0x123, 64, false, true);
  const std::string s = to_string(f);
  EXPECT_EQ(s.size(), std::string("123##5").size() + 128);
  EXPECT_EQ(s.substr(0, 10), "123##5A0A1");
  EXPECT_EQ(s.substr(s.size() - 2), "DF");  // 0xA0 + 63
}

TEST(FrameText, ParseClassicStandard) {
  const auto f = parse_frame("123#DEADBEEF");
  ASSERT_TRUE(f);
  EXPECT_EQ(*f, Frame::standard(0x123, {0xDE, 0xAD, 0xBE, 0xEF}));
  EXPECT_FALSE(f->extended());
  EXPECT_FALSE(f->fd());
}

TEST(FrameText, ParseAcceptsLowerCaseHex) {
  const auto f = parse_frame("7ff#deadbeef");
  ASSERT_TRUE(f);
  EXPECT_EQ(*f, Frame::standard(0x7FF, {0xDE, 0xAD, 0xBE, 0xEF}));
}

TEST(FrameText, ParseEmptyPayload) {
  const auto f = parse_frame("123#");
  ASSERT_TRUE(f);
  EXPECT_EQ(f->len, 0);
  EXPECT_FALSE(f->remote());
}

TEST(FrameText, ParseDotSeparatedPayload) {
  const auto f = parse_frame("123#11.22.33");
  ASSERT_TRUE(f);
  EXPECT_EQ(*f, Frame::standard(0x123, {0x11, 0x22, 0x33}));
}

TEST(FrameText, ParseExtendedId) {
  const auto f = parse_frame("12345678#01");
  ASSERT_TRUE(f);
  EXPECT_TRUE(f->extended());
  EXPECT_EQ(f->id, 0x12345678U);
  const auto small = parse_frame("00000123#");
  ASSERT_TRUE(small);
  EXPECT_TRUE(small->extended());
  EXPECT_EQ(small->id, 0x123U);
}

TEST(FrameText, ParseRemoteFrames) {
  const auto r = parse_frame("12345678#R");
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->remote());
  EXPECT_TRUE(r->extended());
  EXPECT_EQ(r->len, 0);

  const auto r4 = parse_frame("123#R4");
  ASSERT_TRUE(r4);
  EXPECT_TRUE(r4->remote());
  EXPECT_EQ(r4->len, 4);
  EXPECT_EQ(*r4, Frame::rtr(0x123, 4));

  const auto r8 = parse_frame("123#R8");
  ASSERT_TRUE(r8);
  EXPECT_EQ(r8->len, 8);
}

TEST(FrameText, ParseFdFrameWithFlags) {
  const auto f = parse_frame("123##1AABB");
  ASSERT_TRUE(f);
  EXPECT_TRUE(f->fd());
  EXPECT_TRUE(f->has(FrameFlag::BitRateSwitch));
  EXPECT_FALSE(f->has(FrameFlag::ErrorStateIndicator));
  ASSERT_EQ(f->len, 2);
  EXPECT_EQ(f->data[0], 0xAA);
  EXPECT_EQ(f->data[1], 0xBB);

  const auto esi = parse_frame("123##2");
  ASSERT_TRUE(esi);
  EXPECT_TRUE(esi->fd());
  EXPECT_FALSE(esi->has(FrameFlag::BitRateSwitch));
  EXPECT_TRUE(esi->has(FrameFlag::ErrorStateIndicator));
  EXPECT_EQ(esi->len, 0);
}

TEST(FrameText, ParseFdFlagsWithOrWithoutFdfBitLikeCansend) {
  for (int fl = 0; fl < 4; ++fl) {
    const std::string hex = "0123456789ABCDEF";
    const auto without = parse_frame(std::string("123##") + hex[static_cast<std::size_t>(fl)] + "11");
    const auto with = parse_frame(std::string("123##") + hex[static_cast<std::size_t>(fl | 4)] + "11");
    ASSERT_TRUE(without) << fl;
    ASSERT_TRUE(with) << fl;
    EXPECT_EQ(*without, *with) << fl;
    EXPECT_TRUE(with->fd());
    EXPECT_EQ(with->has(FrameFlag::BitRateSwitch), (fl & 1) != 0);
    EXPECT_EQ(with->has(FrameFlag::ErrorStateIndicator), (fl & 2) != 0);
  }
}

TEST(FrameText, ParseFdFrameOf64Bytes) {
  const Frame want = fd_frame(0x7FF, 64, false, true);
  const auto f = parse_frame(to_string(want));
  ASSERT_TRUE(f);
  EXPECT_EQ(*f, want);
}

TEST(FrameText, ParseFdAcceptsOnlyFdLengths) {
  for (std::size_t len : {12U, 16U, 20U, 24U, 32U, 48U, 64U}) {
    const std::string text = "123##0" + std::string(2 * len, 'A');
    EXPECT_TRUE(parse_frame(text)) << len;
  }
  for (std::size_t len : {9U, 10U, 11U, 13U, 17U, 25U, 33U, 49U, 63U, 65U}) {
    const std::string text = "123##0" + std::string(2 * len, 'A');
    EXPECT_FALSE(parse_frame(text)) << len;
  }
}

TEST(FrameText, RejectsMalformedText) {
  const char* bad[] = {
      "",                   // empty
      "123",                // no '#'
      "#11",                // no id
      "12#11",              // 2 id digits
      "1234#11",            // 4 id digits
      "123456789#11",       // 9 id digits
      "12G#11",             // bad hex in id
      "123#1",              // odd digit count
      "123#123",            // odd digit count
      "123#GG",             // bad hex in data
      "123#11 22",          // space is not a separator
      "123#112233445566778899",  // 9 bytes classic
      "800#11",             // 11-bit id out of range
      "FFF#",               // 11-bit id out of range
      "20000000#11",        // 29-bit id out of range
      "FFFFFFFF#",          // 29-bit id out of range
      "123#R9",             // RTR length above 8
      "123#RA",             // RTR length above 8
      "123#R44",            // two length digits
      "123#RX",             // bad RTR length
      "123##",              // FD without flags digit
      "123##G11",           // bad FD flags digit
      "123##01",            // odd digit count in FD
  };
  for (const char* text : bad) EXPECT_FALSE(parse_frame(text)) << '"' << text << '"';
}

TEST(FrameText, AcceptsBoundaryIds) {
  EXPECT_TRUE(parse_frame("7FF#"));
  EXPECT_TRUE(parse_frame("000#"));
  EXPECT_TRUE(parse_frame("1FFFFFFF#"));
  EXPECT_TRUE(parse_frame("00000000#"));
}

TEST(FrameText, RoundTripsManyFrames) {
  std::vector<Frame> frames;
  for (std::uint32_t id : {0x000U, 0x001U, 0x080U, 0x181U, 0x600U, 0x77FU, 0x7FFU}) {
    for (std::size_t len = 0; len <= 8; ++len) {
      const auto b = counting_bytes(len, static_cast<std::uint8_t>(id));
      frames.push_back(Frame::standard(id, b));
    }
    for (std::uint8_t dlc = 0; dlc <= 8; ++dlc) frames.push_back(Frame::rtr(id, dlc));
  }
  for (std::uint32_t id : {0x0U, 0x7FFU, 0x800U, 0x12345678U, 0x1FFFFFFFU}) {
    for (std::size_t len : {0U, 1U, 8U}) {
      const auto b = counting_bytes(len, 0xF0);
      frames.push_back(Frame::extended_id(id, b));
    }
    frames.push_back(Frame::rtr(id, 3, true));
    for (std::size_t len : {0U, 1U, 7U, 8U, 12U, 16U, 20U, 24U, 32U, 48U, 64U}) {
      for (int fl = 0; fl < 4; ++fl) {
        frames.push_back(fd_frame(id, len, true, (fl & 1) != 0, (fl & 2) != 0));
        if (id <= kMaxStandardId) frames.push_back(fd_frame(id, len, false, (fl & 1) != 0, (fl & 2) != 0));
      }
    }
  }
  for (const Frame& f : frames) {
    ASSERT_TRUE(f.valid()) << to_string(f);
    const std::string text = to_string(f);
    const auto back = parse_frame(text);
    ASSERT_TRUE(back) << text;
    EXPECT_EQ(*back, f) << text;
    EXPECT_EQ(to_string(*back), text);
  }
}

}  // namespace
}  // namespace canopen::can
