// Tests for stack/src/socketcan/codec.cpp: conversion between the kernel's
// struct can_frame / canfd_frame and can::Frame, error-frame decoding and
// recvmsg() control-message parsing. No sockets: the kernel structures are
// built by hand.
#include "canopen/socketcan/codec.hpp"
#include "support/frames.hpp"

#include <gtest/gtest.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <stdexcept>
#include <vector>

namespace canopen::socketcan {
namespace {

using can::Frame;
using can::FrameFlag;

canfd_frame zeroed() {
  canfd_frame raw;
  std::memset(&raw, 0, sizeof raw);
  return raw;
}

canfd_frame garbage() {
  canfd_frame raw;
  std::memset(&raw, 0xCC, sizeof raw);
  return raw;
}

// Payload counting from 0x40, unlike the default, so codec tests use
// different bytes than frame tests.
Frame fd_frame(std::uint32_t id, std::size_t len, bool extended, bool brs, bool esi) {
  return test::fd_frame(id, len, extended, brs, esi, 0x40);
}

// ---- sizes the kernel uses -------------------------------------------------

TEST(SocketCanCodec, MtusMatchKernelAbi) {
  EXPECT_EQ(CAN_MTU, 16U);
  EXPECT_EQ(CANFD_MTU, 72U);
  EXPECT_EQ(sizeof(can_frame), CAN_MTU);
  EXPECT_EQ(sizeof(canfd_frame), CANFD_MTU);
}

// ---- encode ------------------------------------------------------------------

TEST(SocketCanCodec, EncodeClassicStandardFrame) {
  canfd_frame raw = garbage();
  const Frame f = Frame::standard(0x123, {0xDE, 0xAD, 0xBE, 0xEF});
  ASSERT_EQ(encode(f, raw), CAN_MTU);
  EXPECT_EQ(raw.can_id, 0x123U);
  EXPECT_EQ(raw.len, 4);
  EXPECT_EQ(raw.flags, 0);
  EXPECT_EQ(raw.__res0, 0);
  EXPECT_EQ(raw.__res1, 0);
  const std::array<std::uint8_t, 8> want{0xDE, 0xAD, 0xBE, 0xEF, 0, 0, 0, 0};
  EXPECT_EQ(std::memcmp(raw.data, want.data(), want.size()), 0) << "unused bytes must be zero";
}

TEST(SocketCanCodec, EncodedClassicFrameHasCanFrameLayout) {
  // The first CAN_MTU bytes are written as a struct can_frame.
  canfd_frame raw = garbage();
  const Frame f = Frame::standard(0x7FF, {1, 2, 3, 4, 5, 6, 7, 8});
  const std::size_t n = encode(f, raw);
  ASSERT_EQ(n, CAN_MTU);
  can_frame cf;
  std::memcpy(&cf, &raw, n);
  EXPECT_EQ(cf.can_id, 0x7FFU);
  EXPECT_EQ(cf.len, 8);
  for (std::uint8_t i = 0; i < 8; ++i) EXPECT_EQ(cf.data[i], i + 1);
}

TEST(SocketCanCodec, EncodeExtendedSetsEffFlag) {
  canfd_frame raw = garbage();
  const std::array<std::uint8_t, 1> b{0x42};
  encode(Frame::extended_id(0x1FFFFFFF, b), raw);
  EXPECT_EQ(raw.can_id, 0x1FFFFFFFU | CAN_EFF_FLAG);
  EXPECT_EQ(raw.can_id & CAN_RTR_FLAG, 0U);
  EXPECT_EQ(raw.can_id & CAN_ERR_FLAG, 0U);

  encode(Frame::extended_id(0x5, b), raw);
  EXPECT_EQ(raw.can_id, 0x5U | CAN_EFF_FLAG) << "extended frames with small ids stay extended";
}

TEST(SocketCanCodec, EncodeRemoteFrameSetsRtrFlagAndDlc) {
  canfd_frame raw = garbage();
  Frame f = Frame::rtr(0x701, 1);
  f.data[0] = 0x99;  // stale byte must not be sent
  ASSERT_EQ(encode(f, raw), CAN_MTU);
  EXPECT_EQ(raw.can_id, 0x701U | CAN_RTR_FLAG);
  EXPECT_EQ(raw.len, 1);
  EXPECT_EQ(raw.data[0], 0);

  encode(Frame::rtr(0x12345678, 8, true), raw);
  EXPECT_EQ(raw.can_id, 0x12345678U | CAN_EFF_FLAG | CAN_RTR_FLAG);
  EXPECT_EQ(raw.len, 8);
}

TEST(SocketCanCodec, EncodeFdFrameUsesCanFdMtuAndFlags) {
  canfd_frame raw = garbage();
  const Frame f = fd_frame(0x123, 64, false, false, false);
  ASSERT_EQ(encode(f, raw), CANFD_MTU);
  EXPECT_EQ(raw.can_id, 0x123U);
  EXPECT_EQ(raw.len, 64);
  EXPECT_EQ(raw.flags, CANFD_FDF);
  for (std::size_t i = 0; i < 64; ++i) EXPECT_EQ(raw.data[i], 0x40 + i) << i;
}

TEST(SocketCanCodec, EncodeFdBrsAndEsiFlags) {
  canfd_frame raw = zeroed();
  encode(fd_frame(0x123, 12, false, true, false), raw);
  EXPECT_EQ(raw.flags, CANFD_FDF | CANFD_BRS);
  encode(fd_frame(0x123, 12, false, false, true), raw);
  EXPECT_EQ(raw.flags, CANFD_FDF | CANFD_ESI);
  encode(fd_frame(0x1ABCDEF0, 48, true, true, true), raw);
  EXPECT_EQ(raw.flags, CANFD_FDF | CANFD_BRS | CANFD_ESI);
  EXPECT_EQ(raw.can_id, 0x1ABCDEF0U | CAN_EFF_FLAG);
}

TEST(SocketCanCodec, EncodeShortFdFrameStillUsesCanFdMtu) {
  canfd_frame raw = zeroed();
  EXPECT_EQ(encode(fd_frame(0x100, 0, false, false, false), raw), CANFD_MTU);
  EXPECT_EQ(encode(fd_frame(0x100, 8, false, true, false), raw), CANFD_MTU);
}

// ---- decode ------------------------------------------------------------------

TEST(SocketCanCodec, DecodeClassicStandardFrame) {
  canfd_frame raw = zeroed();
  raw.can_id = 0x181;
  raw.len = 3;
  raw.data[0] = 0x11;
  raw.data[1] = 0x22;
  raw.data[2] = 0x33;
  const Decoded d = decode(raw, CAN_MTU);
  ASSERT_EQ(d.kind, RawKind::Data);
  EXPECT_EQ(d.frame, Frame::standard(0x181, {0x11, 0x22, 0x33}));
}

TEST(SocketCanCodec, DecodeExtendedFrameMasksFlagBits) {
  canfd_frame raw = zeroed();
  raw.can_id = 0x18FF50E5U | CAN_EFF_FLAG;
  raw.len = 0;
  const Decoded d = decode(raw, CAN_MTU);
  ASSERT_EQ(d.kind, RawKind::Data);
  EXPECT_TRUE(d.frame.extended());
  EXPECT_EQ(d.frame.id, 0x18FF50E5U);
  EXPECT_TRUE(d.frame.valid());
}

TEST(SocketCanCodec, DecodeRemoteFrame) {
  canfd_frame raw = zeroed();
  raw.can_id = 0x701U | CAN_RTR_FLAG;
  raw.len = 1;
  const Decoded d = decode(raw, CAN_MTU);
  ASSERT_EQ(d.kind, RawKind::Data);
  EXPECT_TRUE(d.frame.remote());
  EXPECT_EQ(d.frame.len, 1);
  EXPECT_EQ(d.frame.id, 0x701U);
  EXPECT_EQ(d.frame, Frame::rtr(0x701, 1));
}

TEST(SocketCanCodec, DecodeFdFrameWithFlags) {
  canfd_frame raw = zeroed();
  raw.can_id = 0x123;
  raw.len = 16;
  raw.flags = static_cast<std::uint8_t>(CANFD_FDF | CANFD_BRS | CANFD_ESI);
  for (std::uint8_t i = 0; i < 16; ++i) raw.data[i] = static_cast<std::uint8_t>(0xF0 - i);
  const Decoded d = decode(raw, CANFD_MTU);
  ASSERT_EQ(d.kind, RawKind::Data);
  EXPECT_TRUE(d.frame.fd());
  EXPECT_TRUE(d.frame.has(FrameFlag::BitRateSwitch));
  EXPECT_TRUE(d.frame.has(FrameFlag::ErrorStateIndicator));
  ASSERT_EQ(d.frame.len, 16);
  for (std::uint8_t i = 0; i < 16; ++i) EXPECT_EQ(d.frame.data[i], 0xF0 - i);
  EXPECT_TRUE(d.frame.valid());
}

TEST(SocketCanCodec, DecodeFdFrameWithoutBrs) {
  canfd_frame raw = zeroed();
  raw.can_id = 0x123;
  raw.len = 2;
  raw.flags = CANFD_FDF;
  const Decoded d = decode(raw, CANFD_MTU);
  ASSERT_EQ(d.kind, RawKind::Data);
  EXPECT_TRUE(d.frame.fd());
  EXPECT_FALSE(d.frame.has(FrameFlag::BitRateSwitch));
  EXPECT_FALSE(d.frame.has(FrameFlag::ErrorStateIndicator));
}

TEST(SocketCanCodec, DecodeClassicFrameIgnoresFdFlagBytes) {
  canfd_frame raw = zeroed();
  raw.can_id = 0x100;
  raw.len = 1;
  raw.flags = CANFD_BRS;  // __pad in struct can_frame: meaningless for CAN_MTU
  const Decoded d = decode(raw, CAN_MTU);
  ASSERT_EQ(d.kind, RawKind::Data);
  EXPECT_FALSE(d.frame.fd());
  EXPECT_FALSE(d.frame.has(FrameFlag::BitRateSwitch));
  EXPECT_TRUE(d.frame.valid());
}

TEST(SocketCanCodec, DecodeRejectsUnexpectedByteCounts) {
  const canfd_frame raw = zeroed();
  for (std::size_t n : {0U, 1U, 8U, 15U, 17U, 64U, 71U, 73U, 128U}) {
    EXPECT_EQ(decode(raw, n).kind, RawKind::Invalid) << n;
  }
}

TEST(SocketCanCodec, DecodeRejectsOverlongLengths) {
  canfd_frame raw = zeroed();
  raw.can_id = 0x100;
  raw.len = 9;
  EXPECT_EQ(decode(raw, CAN_MTU).kind, RawKind::Invalid);
  raw.len = 8;
  EXPECT_EQ(decode(raw, CAN_MTU).kind, RawKind::Data);
  raw.flags = CANFD_FDF;
  raw.len = 65;
  EXPECT_EQ(decode(raw, CANFD_MTU).kind, RawKind::Invalid);
  raw.len = 64;
  EXPECT_EQ(decode(raw, CANFD_MTU).kind, RawKind::Data);
}

TEST(SocketCanCodec, ErrorFlagMakesErrorKind) {
  canfd_frame raw = zeroed();
  raw.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  raw.len = CAN_ERR_DLC;
  const Decoded d = decode(raw, CAN_MTU);
  EXPECT_EQ(d.kind, RawKind::Error);
  EXPECT_TRUE(d.error.bus_off);
}

// ---- round trips -------------------------------------------------------------

TEST(SocketCanCodec, EncodeThenDecodeReproducesFrame) {
  std::vector<Frame> frames;
  for (std::uint32_t id : {0x000U, 0x080U, 0x181U, 0x7FFU}) {
    for (std::uint8_t len = 0; len <= 8; ++len) {
      std::vector<std::uint8_t> b(len);
      for (std::uint8_t i = 0; i < len; ++i) b[i] = static_cast<std::uint8_t>(id + i * 17U);
      frames.push_back(Frame::standard(id, b));
    }
    for (std::uint8_t dlc = 0; dlc <= 8; ++dlc) frames.push_back(Frame::rtr(id, dlc));
  }
  for (std::uint32_t id : {0x0U, 0x800U, 0x12345678U, 0x1FFFFFFFU}) {
    const std::array<std::uint8_t, 8> b{1, 2, 3, 4, 5, 6, 7, 8};
    frames.push_back(Frame::extended_id(id, b));
    frames.push_back(Frame::rtr(id, 2, true));
  }
  for (std::size_t len : {0U, 1U, 8U, 12U, 16U, 20U, 24U, 32U, 48U, 64U}) {
    for (int fl = 0; fl < 4; ++fl) {
      frames.push_back(fd_frame(0x7FF, len, false, (fl & 1) != 0, (fl & 2) != 0));
      frames.push_back(fd_frame(0x1FFFFFFF, len, true, (fl & 1) != 0, (fl & 2) != 0));
    }
  }
  for (const Frame& f : frames) {
    ASSERT_TRUE(f.valid()) << can::to_string(f);
    canfd_frame raw = garbage();
    const std::size_t n = encode(f, raw);
    EXPECT_EQ(n, f.fd() ? CANFD_MTU : CAN_MTU) << can::to_string(f);
    const Decoded d = decode(raw, n);
    ASSERT_EQ(d.kind, RawKind::Data) << can::to_string(f);
    EXPECT_EQ(d.frame, f) << can::to_string(f);
  }
}

TEST(SocketCanCodec, DecodeThenEncodeReproducesKernelBytes) {
  canfd_frame in = zeroed();
  in.can_id = 0x0CFE6CEEU | CAN_EFF_FLAG;
  in.len = 8;
  for (std::uint8_t i = 0; i < 8; ++i) in.data[i] = static_cast<std::uint8_t>(0xA0 + i);
  const Decoded d = decode(in, CAN_MTU);
  ASSERT_EQ(d.kind, RawKind::Data);
  canfd_frame out = garbage();
  ASSERT_EQ(encode(d.frame, out), CAN_MTU);
  EXPECT_EQ(std::memcmp(&in, &out, CAN_MTU), 0);

  canfd_frame fd_in = zeroed();
  fd_in.can_id = 0x321;
  fd_in.len = 32;
  fd_in.flags = static_cast<std::uint8_t>(CANFD_FDF | CANFD_BRS);
  for (std::uint8_t i = 0; i < 32; ++i) fd_in.data[i] = i;
  const Decoded fd = decode(fd_in, CANFD_MTU);
  ASSERT_EQ(fd.kind, RawKind::Data);
  canfd_frame fd_out = garbage();
  ASSERT_EQ(encode(fd.frame, fd_out), CANFD_MTU);
  EXPECT_EQ(std::memcmp(&fd_in, &fd_out, CANFD_MTU), 0);
}

// ---- error frames ------------------------------------------------------------

canfd_frame error_frame(canid_t classes) {
  canfd_frame raw = zeroed();
  raw.can_id = CAN_ERR_FLAG | classes;
  raw.len = CAN_ERR_DLC;
  return raw;
}

TEST(SocketCanCodec, DecodeErrorBusOffAndRestart) {
  EXPECT_TRUE(decode_error(error_frame(CAN_ERR_BUSOFF)).bus_off);
  EXPECT_FALSE(decode_error(error_frame(CAN_ERR_BUSOFF)).restarted);
  EXPECT_TRUE(decode_error(error_frame(CAN_ERR_RESTARTED)).restarted);
  EXPECT_FALSE(decode_error(error_frame(CAN_ERR_RESTARTED)).bus_off);
}

TEST(SocketCanCodec, DecodeErrorControllerStates) {
  struct Case {
    std::uint8_t bits;
    bool rx_warning, tx_warning, rx_passive, tx_passive, active, rx_overflow, tx_overflow;
  };
  const Case cases[] = {
      {CAN_ERR_CRTL_RX_WARNING, true, false, false, false, false, false, false},
      {CAN_ERR_CRTL_TX_WARNING, false, true, false, false, false, false, false},
      {CAN_ERR_CRTL_RX_PASSIVE, false, false, true, false, false, false, false},
      {CAN_ERR_CRTL_TX_PASSIVE, false, false, false, true, false, false, false},
      {CAN_ERR_CRTL_ACTIVE, false, false, false, false, true, false, false},
      {CAN_ERR_CRTL_RX_OVERFLOW, false, false, false, false, false, true, false},
      {CAN_ERR_CRTL_TX_OVERFLOW, false, false, false, false, false, false, true},
  };
  for (const Case& c : cases) {
    canfd_frame raw = error_frame(CAN_ERR_CRTL);
    raw.data[1] = c.bits;
    const auto e = decode_error(raw);
    SCOPED_TRACE(static_cast<int>(c.bits));
    EXPECT_TRUE(e.controller);
    EXPECT_EQ(e.rx_warning, c.rx_warning);
    EXPECT_EQ(e.tx_warning, c.tx_warning);
    EXPECT_EQ(e.rx_passive, c.rx_passive);
    EXPECT_EQ(e.tx_passive, c.tx_passive);
    EXPECT_EQ(e.back_to_active, c.active);
    EXPECT_EQ(e.rx_overflow, c.rx_overflow);
    EXPECT_EQ(e.tx_overflow, c.tx_overflow);
    EXPECT_FALSE(e.bus_off);
  }
}

TEST(SocketCanCodec, DecodeErrorIgnoresControllerByteWithoutControllerClass) {
  canfd_frame raw = error_frame(CAN_ERR_PROT);
  raw.data[1] = CAN_ERR_CRTL_RX_PASSIVE;
  const auto e = decode_error(raw);
  EXPECT_FALSE(e.controller);
  EXPECT_FALSE(e.rx_passive);
  EXPECT_TRUE(e.protocol_error);
}

TEST(SocketCanCodec, DecodeErrorProtocolClasses) {
  for (canid_t cls : {CAN_ERR_PROT, CAN_ERR_ACK, CAN_ERR_BUSERROR}) {
    EXPECT_TRUE(decode_error(error_frame(cls)).protocol_error) << cls;
  }
  // Losing arbitration is how CAN resolves contention, not an error.
  EXPECT_FALSE(decode_error(error_frame(CAN_ERR_LOSTARB)).protocol_error);
  EXPECT_FALSE(decode_error(error_frame(CAN_ERR_BUSOFF)).protocol_error);
  EXPECT_FALSE(decode_error(error_frame(CAN_ERR_CRTL)).protocol_error);
}

TEST(SocketCanCodec, DecodeErrorCountersOnlyWithCntClass) {
  canfd_frame raw = error_frame(CAN_ERR_CRTL | CAN_ERR_CNT);
  raw.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  raw.data[6] = 130;
  raw.data[7] = 7;
  auto e = decode_error(raw);
  EXPECT_TRUE(e.has_counters);
  EXPECT_EQ(e.tx_error_counter, 130);
  EXPECT_EQ(e.rx_error_counter, 7);
  EXPECT_TRUE(e.tx_passive);

  raw.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  e = decode_error(raw);
  EXPECT_FALSE(e.has_counters);
  EXPECT_EQ(e.tx_error_counter, 0);
  EXPECT_EQ(e.rx_error_counter, 0);
}

TEST(SocketCanCodec, DecodeErrorSeveralClassesAtOnce) {
  canfd_frame raw = error_frame(CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_PROT);
  raw.data[1] = CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_WARNING;
  const auto e = decode_error(raw);
  EXPECT_TRUE(e.bus_off);
  EXPECT_TRUE(e.protocol_error);
  EXPECT_TRUE(e.tx_passive);
  EXPECT_TRUE(e.rx_warning);
  EXPECT_FALSE(e.rx_passive);
}

TEST(SocketCanCodec, DecodedErrorFrameDrivesBusStateTracker) {
  can::BusStateTracker t;
  t.on_link_up();
  canfd_frame raw = error_frame(CAN_ERR_CRTL | CAN_ERR_CNT);
  raw.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  raw.data[6] = 128;
  const Decoded d = decode(raw, CAN_MTU);
  ASSERT_EQ(d.kind, RawKind::Error);
  const auto ev = t.on_error_frame(d.error);
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->state, can::BusState::ErrorPassive);
  EXPECT_EQ(ev->tx_error_counter, 128);
}

// ---- control messages ----------------------------------------------------------

// CMSG_* are C macros with C casts.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wcast-align"
#pragma GCC diagnostic ignored "-Wsign-conversion"

struct Cmsg {
  int level;
  int type;
  std::vector<std::uint8_t> data;
  std::size_t len_override = 0;  // cmsg_len to claim instead of CMSG_LEN(data)
};

// Builds a control buffer the way the kernel fills it, and a msghdr over it.
class ControlBuffer {
 public:
  explicit ControlBuffer(const std::vector<Cmsg>& msgs) {
    std::size_t total = 0;
    for (const auto& m : msgs) total += CMSG_SPACE(m.data.size());
    storage_.assign(total / sizeof(cmsghdr) + 2, cmsghdr{});
    msg_.msg_control = storage_.data();
    msg_.msg_controllen = storage_.size() * sizeof(cmsghdr);
    cmsghdr* c = CMSG_FIRSTHDR(&msg_);
    for (const auto& m : msgs) {
      if (c == nullptr) throw std::logic_error("control buffer too small");
      c->cmsg_level = m.level;
      c->cmsg_type = m.type;
      c->cmsg_len = m.len_override != 0 ? m.len_override : CMSG_LEN(m.data.size());
      std::memcpy(CMSG_DATA(c), m.data.data(), m.data.size());
      c = CMSG_NXTHDR(&msg_, c);
    }
    msg_.msg_controllen = total;
  }
  const msghdr& msg() const { return msg_; }

 private:
  std::vector<cmsghdr> storage_;
  msghdr msg_{};
};

template <typename T>
std::vector<std::uint8_t> bytes_of(const T& v) {
  std::vector<std::uint8_t> out(sizeof v);
  std::memcpy(out.data(), &v, sizeof v);
  return out;
}

Cmsg timestamp_msg(std::time_t sec, long nsec) {
  timespec ts{};
  ts.tv_sec = sec;
  ts.tv_nsec = nsec;
  return {SOL_SOCKET, SCM_TIMESTAMPNS, bytes_of(ts)};
}

Cmsg drops_msg(std::uint32_t n) { return {SOL_SOCKET, SO_RXQ_OVFL, bytes_of(n)}; }

Frame::Clock::time_point at(std::int64_t sec, std::int64_t nsec) {
  return Frame::Clock::time_point(
      std::chrono::duration_cast<Frame::Clock::duration>(std::chrono::seconds(sec) + std::chrono::nanoseconds(nsec)));
}

TEST(SocketCanControl, NoControlMessagesGiveNothing) {
  msghdr msg{};
  const RxMeta m = parse_control(msg);
  EXPECT_FALSE(m.timestamp);
  EXPECT_FALSE(m.drop_count);
}

TEST(SocketCanControl, ParsesTimestampNs) {
  ControlBuffer buf({timestamp_msg(1'700'000'000, 123'456'789)});
  const RxMeta m = parse_control(buf.msg());
  ASSERT_TRUE(m.timestamp);
  EXPECT_EQ(*m.timestamp, at(1'700'000'000, 123'456'789));
  EXPECT_FALSE(m.drop_count);
}

TEST(SocketCanControl, ParsesDropCounter) {
  ControlBuffer buf({drops_msg(42)});
  const RxMeta m = parse_control(buf.msg());
  ASSERT_TRUE(m.drop_count);
  EXPECT_EQ(*m.drop_count, 42U);
  EXPECT_FALSE(m.timestamp);
}

TEST(SocketCanControl, ParsesBothInKernelOrder) {
  ControlBuffer buf({timestamp_msg(1'600'000'000, 999'999'999), drops_msg(0xFFFFFFFFU)});
  const RxMeta m = parse_control(buf.msg());
  ASSERT_TRUE(m.timestamp);
  ASSERT_TRUE(m.drop_count);
  EXPECT_EQ(*m.timestamp, at(1'600'000'000, 999'999'999));
  EXPECT_EQ(*m.drop_count, 0xFFFFFFFFU);
}

TEST(SocketCanControl, ParsesBothInReverseOrder) {
  ControlBuffer buf({drops_msg(3), timestamp_msg(5, 1)});
  const RxMeta m = parse_control(buf.msg());
  ASSERT_TRUE(m.timestamp);
  ASSERT_TRUE(m.drop_count);
  EXPECT_EQ(*m.timestamp, at(5, 1));
  EXPECT_EQ(*m.drop_count, 3U);
}

TEST(SocketCanControl, ControlBufferSizeHoldsBothMessages) {
  ControlBuffer buf({timestamp_msg(1, 2), drops_msg(3)});
  EXPECT_LE(buf.msg().msg_controllen, kControlBufferSize);
}

TEST(SocketCanControl, IgnoresOtherLevelsAndTypes) {
  ControlBuffer buf({
      {SOL_CAN_RAW, SCM_TIMESTAMPNS, bytes_of(timespec{1, 2})},
      {SOL_SOCKET, SCM_RIGHTS, bytes_of(std::int32_t{5})},
      drops_msg(9),
  });
  const RxMeta m = parse_control(buf.msg());
  EXPECT_FALSE(m.timestamp);
  ASSERT_TRUE(m.drop_count);
  EXPECT_EQ(*m.drop_count, 9U);
}

TEST(SocketCanControl, IgnoresTruncatedMessages) {
  Cmsg short_ts = timestamp_msg(1, 2);
  short_ts.len_override = CMSG_LEN(sizeof(timespec) - 1);
  Cmsg short_drops = drops_msg(7);
  short_drops.len_override = CMSG_LEN(sizeof(std::uint16_t));
  ControlBuffer buf({short_ts, short_drops});
  const RxMeta m = parse_control(buf.msg());
  EXPECT_FALSE(m.timestamp);
  EXPECT_FALSE(m.drop_count);
}

#pragma GCC diagnostic pop

}  // namespace
}  // namespace canopen::socketcan
