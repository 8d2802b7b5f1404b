// Tests for stack/src/sdo/protocol.cpp: every SDO frame layout of CiA 301
// 7.2.4.3, both roles, byte for byte, and the block transfer CRC.
#include "canopen/sdo/protocol.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "unit/stack/sdo/sdo_test_support.hpp"

namespace canopen::sdo {
namespace {

using test::hex;

constexpr Multiplexer k1017{0x1017, 0x00};
constexpr Multiplexer k2001_02{0x2001, 0x02};

std::vector<std::uint8_t> bytes(std::initializer_list<std::uint8_t> b) { return b; }

// ---- expedited and normal initiate ---------------------------------------------------

TEST(SdoProtocol, ExpeditedInitiateDownloadWithSize) {
  // ccs=1, n=4-len, e=1, s=1: 2F (1 byte), 2B (2), 27 (3), 23 (4).
  EXPECT_EQ(initiate_download_expedited(k1017, bytes({0xE8, 0x03})), hex("2B 17 10 00 E8 03 00 00"));
  EXPECT_EQ(initiate_download_expedited(k2001_02, bytes({0x11})), hex("2F 01 20 02 11 00 00 00"));
  EXPECT_EQ(initiate_download_expedited(k2001_02, bytes({1, 2, 3})), hex("27 01 20 02 01 02 03 00"));
  EXPECT_EQ(initiate_download_expedited(k2001_02, bytes({1, 2, 3, 4})), hex("23 01 20 02 01 02 03 04"));
}

TEST(SdoProtocol, ExpeditedInitiateDownloadWithoutSize) {
  // e=1, s=0: n is 0, the data size is unspecified.
  EXPECT_EQ(initiate_download_expedited(k1017, bytes({0xE8, 0x03}), false), hex("22 17 10 00 E8 03 00 00"));
  const Initiate in = parse_initiate(hex("22 17 10 00 E8 03 00 00"));
  EXPECT_TRUE(in.expedited);
  EXPECT_FALSE(in.size_indicated);
  EXPECT_EQ(in.size, 4U);
  EXPECT_EQ(in.mux, k1017);
}

TEST(SdoProtocol, NormalInitiateDownload) {
  EXPECT_EQ(initiate_download_normal(k2001_02, 0x01020304U), hex("21 01 20 02 04 03 02 01"));
  EXPECT_EQ(initiate_download_normal(k2001_02, std::nullopt), hex("20 01 20 02 00 00 00 00"));
  const Initiate in = parse_initiate(hex("21 01 20 02 04 03 02 01"));
  EXPECT_FALSE(in.expedited);
  EXPECT_TRUE(in.size_indicated);
  EXPECT_EQ(in.size, 0x01020304U);
  EXPECT_EQ(parse_initiate(hex("20 01 20 02")).size, 0U);
}

TEST(SdoProtocol, InitiateDownloadResponse) {
  EXPECT_EQ(initiate_download_response(k1017), hex("60 17 10 00 00 00 00 00"));
  EXPECT_EQ(command_bits(hex("60")), static_cast<std::uint8_t>(ServerCommand::InitiateDownload));
}

TEST(SdoProtocol, InitiateUploadRequestAndResponses) {
  EXPECT_EQ(initiate_upload_request({0x1000, 0}), hex("40 00 10 00 00 00 00 00"));
  // scs=2: 43 (4 bytes), 47 (3), 4B (2), 4F (1), 42 (expedited, no size), 41 (normal, size), 40 (normal, none).
  EXPECT_EQ(initiate_upload_response_expedited({0x1000, 0}, bytes({0x92, 0x01, 0x02, 0x00})),
            hex("43 00 10 00 92 01 02 00"));
  EXPECT_EQ(initiate_upload_response_expedited(k1017, bytes({1, 2, 3})), hex("47 17 10 00 01 02 03 00"));
  EXPECT_EQ(initiate_upload_response_expedited(k1017, bytes({0xE8, 0x03})), hex("4B 17 10 00 E8 03 00 00"));
  EXPECT_EQ(initiate_upload_response_expedited(k1017, bytes({0x7F})), hex("4F 17 10 00 7F 00 00 00"));
  EXPECT_EQ(initiate_upload_response_expedited(k1017, bytes({0xE8, 0x03}), false), hex("42 17 10 00 E8 03 00 00"));
  EXPECT_EQ(initiate_upload_response_normal(k2001_02, 12U), hex("41 01 20 02 0C 00 00 00"));
  EXPECT_EQ(initiate_upload_response_normal(k2001_02, std::nullopt), hex("40 01 20 02 00 00 00 00"));

  const Initiate e = parse_initiate(hex("4B 17 10 00 E8 03 00 00"));
  EXPECT_TRUE(e.expedited);
  EXPECT_TRUE(e.size_indicated);
  EXPECT_EQ(e.size, 2U);
  const Initiate n = parse_initiate(hex("41 01 20 02 0C 00 00 00"));
  EXPECT_FALSE(n.expedited);
  EXPECT_EQ(n.size, 12U);
  EXPECT_EQ(n.mux, k2001_02);
}

// ---- segments ------------------------------------------------------------------------------

TEST(SdoProtocol, DownloadSegments) {
  // ccs=0 | t | n | c
  EXPECT_EQ(download_segment_request(false, bytes({1, 2, 3, 4, 5, 6, 7}), false), hex("00 01 02 03 04 05 06 07"));
  EXPECT_EQ(download_segment_request(true, bytes({1, 2, 3, 4, 5, 6, 7}), false), hex("10 01 02 03 04 05 06 07"));
  // t=1, 3 bytes (n=4), last: 10 | 08 | 01 = 19.
  EXPECT_EQ(download_segment_request(true, bytes({1, 2, 3}), true), hex("19 01 02 03 00 00 00 00"));
  // Empty last segment (0-byte transfer): n=7, c=1.
  EXPECT_EQ(download_segment_request(false, {}, true), hex("0F 00 00 00 00 00 00 00"));
  // Responses: scs=1 | t.
  EXPECT_EQ(download_segment_response(false), hex("20 00 00 00 00 00 00 00"));
  EXPECT_EQ(download_segment_response(true), hex("30 00 00 00 00 00 00 00"));

  const Segment s = parse_segment(hex("19 01 02 03"));
  EXPECT_TRUE(s.toggle);
  EXPECT_TRUE(s.last);
  EXPECT_EQ(s.size, 3U);
  const Segment full = parse_segment(hex("00 01 02 03 04 05 06 07"));
  EXPECT_FALSE(full.toggle);
  EXPECT_FALSE(full.last);
  EXPECT_EQ(full.size, 7U);
}

TEST(SdoProtocol, UploadSegments) {
  EXPECT_EQ(upload_segment_request(false), hex("60 00 00 00 00 00 00 00"));
  EXPECT_EQ(upload_segment_request(true), hex("70 00 00 00 00 00 00 00"));
  // scs=0 | t | n | c: "orld!" is 5 bytes, n=2, t=1, c=1 -> 15.
  EXPECT_EQ(upload_segment_response(true, bytes({'o', 'r', 'l', 'd', '!'}), true), hex("15 6F 72 6C 64 21 00 00"));
  EXPECT_EQ(upload_segment_response(false, bytes({1, 2, 3, 4, 5, 6, 7}), false), hex("00 01 02 03 04 05 06 07"));
  EXPECT_EQ(upload_segment_response(false, bytes({1, 2, 3, 4, 5, 6, 7}), true), hex("01 01 02 03 04 05 06 07"));
  EXPECT_TRUE(toggle_bit(hex("70")));
  EXPECT_FALSE(toggle_bit(hex("60")));
}

// ---- block download ---------------------------------------------------------------------------

TEST(SdoProtocol, BlockDownloadInitiate) {
  // ccs=6 | cc(2) | s(1) | cs=0
  EXPECT_EQ(block_download_initiate(k2001_02, true, 0x00000385U), hex("C6 01 20 02 85 03 00 00"));
  EXPECT_EQ(block_download_initiate(k2001_02, false, 0x00000385U), hex("C2 01 20 02 85 03 00 00"));
  EXPECT_EQ(block_download_initiate(k2001_02, true, std::nullopt), hex("C4 01 20 02 00 00 00 00"));
  EXPECT_EQ(block_download_initiate(k2001_02, false, std::nullopt), hex("C0 01 20 02 00 00 00 00"));
  const BlockInitiate in = parse_block_initiate(hex("C6 01 20 02 85 03 00 00"));
  EXPECT_TRUE(in.crc);
  EXPECT_TRUE(in.size_indicated);
  EXPECT_EQ(in.size, 0x385U);
  EXPECT_EQ(in.mux, k2001_02);
  // Server: scs=5 | sc(2) | ss=0, blksize in byte 4.
  EXPECT_EQ(block_download_initiate_response(k2001_02, true, 127), hex("A4 01 20 02 7F 00 00 00"));
  EXPECT_EQ(block_download_initiate_response(k2001_02, false, 16), hex("A0 01 20 02 10 00 00 00"));
  EXPECT_TRUE(crc_bit(hex("A4")));
  EXPECT_EQ(block_sub_command(hex("A4")), static_cast<std::uint8_t>(BlockDownloadServerSub::Initiate));
}

TEST(SdoProtocol, SubBlockSegments) {
  // c(7) | seqno(6..0)
  EXPECT_EQ(block_segment(1, bytes({1, 2, 3, 4, 5, 6, 7}), false), hex("01 01 02 03 04 05 06 07"));
  EXPECT_EQ(block_segment(127, bytes({1, 2, 3, 4, 5, 6, 7}), false), hex("7F 01 02 03 04 05 06 07"));
  EXPECT_EQ(block_segment(5, bytes({0xAA, 0xBB}), true), hex("85 AA BB 00 00 00 00 00"));
  const BlockSegment s = parse_block_segment(hex("85 AA BB"));
  EXPECT_EQ(s.seqno, 5U);
  EXPECT_TRUE(s.last);
  const BlockSegment m = parse_block_segment(hex("7F"));
  EXPECT_EQ(m.seqno, 127U);
  EXPECT_FALSE(m.last);
}

TEST(SdoProtocol, BlockDownloadAckAndEnd) {
  // Server ack: scs=5 ss=2, ackseq, blksize.
  EXPECT_EQ(block_download_ack(127, 127), hex("A2 7F 7F 00 00 00 00 00"));
  EXPECT_EQ(block_download_ack(3, 16), hex("A2 03 10 00 00 00 00 00"));
  const BlockAck a = parse_block_ack(hex("A2 03 10"));
  EXPECT_EQ(a.ackseq, 3U);
  EXPECT_EQ(a.blksize, 16U);
  EXPECT_EQ(block_sub_command(hex("A2")), static_cast<std::uint8_t>(BlockDownloadServerSub::Ack));
  // Client end: ccs=6 | n(4..2) | cs=1, CRC little-endian.
  EXPECT_EQ(block_download_end(0, 0x31C3), hex("C1 C3 31 00 00 00 00 00"));
  EXPECT_EQ(block_download_end(3, 0x1234), hex("CD 34 12 00 00 00 00 00"));
  EXPECT_EQ(block_download_end(7, 0), hex("DD 00 00 00 00 00 00 00"));
  const BlockEnd e = parse_block_end(hex("CD 34 12"));
  EXPECT_EQ(e.unused, 3U);
  EXPECT_EQ(e.crc, 0x1234U);
  // Server end response: scs=5 ss=1.
  EXPECT_EQ(block_download_end_response(), hex("A1 00 00 00 00 00 00 00"));
}

TEST(SdoProtocol, DistinctAckBlockSize) {
  // First ack, a full ack, or a different ack: blksize unchanged.
  EXPECT_EQ(distinct_ack_blksize(std::nullopt, 3, 127, 127), 127U);
  EXPECT_EQ(distinct_ack_blksize(BlockAck{127, 127}, 127, 127, 127), 127U);
  EXPECT_EQ(distinct_ack_blksize(BlockAck{2, 127}, 3, 127, 127), 127U);
  // The same partial ack again: toggle between max and max - 1.
  EXPECT_EQ(distinct_ack_blksize(BlockAck{3, 127}, 3, 127, 127), 126U);
  EXPECT_EQ(distinct_ack_blksize(BlockAck{3, 126}, 3, 126, 127), 127U);
  EXPECT_EQ(distinct_ack_blksize(BlockAck{0, 1}, 0, 1, 1), 1U);  // no choice
}

// ---- block upload ---------------------------------------------------------------------------------

TEST(SdoProtocol, BlockUploadInitiateAndStart) {
  // Client: ccs=5 | cc(2) | cs=0, blksize, pst.
  EXPECT_EQ(block_upload_initiate(k2001_02, true, 127, 0), hex("A4 01 20 02 7F 00 00 00"));
  EXPECT_EQ(block_upload_initiate(k2001_02, false, 32, 64), hex("A0 01 20 02 20 40 00 00"));
  // Server: scs=6 | sc(2) | s(1) | ss=0, size.
  EXPECT_EQ(block_upload_initiate_response(k2001_02, true, 0x00100000U), hex("C6 01 20 02 00 00 10 00"));
  EXPECT_EQ(block_upload_initiate_response(k2001_02, false, std::nullopt), hex("C0 01 20 02 00 00 00 00"));
  // Client start: ccs=5 cs=3.
  EXPECT_EQ(block_upload_start(), hex("A3 00 00 00 00 00 00 00"));
  EXPECT_EQ(block_sub_command(hex("A3")), static_cast<std::uint8_t>(BlockUploadClientSub::Start));
}

TEST(SdoProtocol, BlockUploadAckAndEnd) {
  // Client ack: ccs=5 cs=2, ackseq, blksize.
  EXPECT_EQ(block_upload_ack(0, 127), hex("A2 00 7F 00 00 00 00 00"));
  EXPECT_EQ(block_upload_ack(12, 20), hex("A2 0C 14 00 00 00 00 00"));
  // Server end: scs=6 | n | ss=1.
  EXPECT_EQ(block_upload_end(2, 0xBEEF), hex("C9 EF BE 00 00 00 00 00"));
  EXPECT_EQ(parse_block_end(hex("C9 EF BE")).unused, 2U);
  // Client end response: ccs=5 cs=1.
  EXPECT_EQ(block_upload_end_response(), hex("A1 00 00 00 00 00 00 00"));
}

// ---- abort -------------------------------------------------------------------------------------------

TEST(SdoProtocol, AbortTransfer) {
  EXPECT_EQ(abort_transfer({0x1000, 0}, 0x06020000U), hex("80 00 10 00 00 00 02 06"));
  EXPECT_EQ(abort_transfer(k2001_02, 0x05040000U), hex("80 01 20 02 00 00 04 05"));
  EXPECT_EQ(abort_code(hex("80 01 20 02 00 00 04 05")), 0x05040000U);
  EXPECT_EQ(multiplexer(hex("80 01 20 02")), k2001_02);
  EXPECT_EQ(command_bits(hex("80")), static_cast<std::uint8_t>(ClientCommand::Abort));
  EXPECT_EQ(command_bits(hex("80")), static_cast<std::uint8_t>(ServerCommand::Abort));
}

TEST(SdoProtocol, MakeFrameIsClassicEightBytes) {
  const can::Frame f = make_frame(0x605, hex("40 00 10 00"));
  EXPECT_EQ(f.id, 0x605U);
  EXPECT_EQ(f.len, 8U);
  EXPECT_FALSE(f.extended());
  EXPECT_FALSE(f.fd());
  EXPECT_TRUE(f.valid());
  EXPECT_EQ(can::to_string(f), "605#4000100000000000");
}

// ---- CRC (7.2.4.3.16) ------------------------------------------------------------------------------

TEST(SdoProtocol, CrcCheckValue) {
  constexpr std::string_view kCheck = "123456789";
  const std::vector<std::uint8_t> data(kCheck.begin(), kCheck.end());
  EXPECT_EQ(crc16(data), 0x31C3U);
}

TEST(SdoProtocol, CrcOfNothingIsTheInitialValue) { EXPECT_EQ(crc16({}), 0x0000U); }

TEST(SdoProtocol, CrcContinuesOverPieces) {
  const Bytes data = test::pattern(1000);
  const std::uint16_t whole = crc16(data);
  std::uint16_t crc = 0;
  for (std::size_t at = 0; at < data.size(); at += 7) {
    crc = crc16(std::span(data).subspan(at, std::min<std::size_t>(7, data.size() - at)), crc);
  }
  EXPECT_EQ(crc, whole);
}

TEST(SdoProtocol, CrcDetectsSingleBitErrors) {
  Bytes data = test::pattern(64);
  const std::uint16_t good = crc16(data);
  for (std::size_t bit = 0; bit < data.size() * 8; bit += 13) {
    data[bit / 8] = static_cast<std::uint8_t>(data[bit / 8] ^ (1U << (bit % 8)));
    EXPECT_NE(crc16(data), good) << "bit " << bit;
    data[bit / 8] = static_cast<std::uint8_t>(data[bit / 8] ^ (1U << (bit % 8)));
  }
}

}  // namespace
}  // namespace canopen::sdo
