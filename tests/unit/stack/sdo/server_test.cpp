// Tests for stack/src/sdo/server.cpp: the SDO server driven with hand-made
// frames; every transfer mode and every abort path, each checked byte for
// byte.
#include "canopen/sdo/server.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "unit/stack/sdo/sdo_test_support.hpp"

namespace canopen::sdo {
namespace {

using namespace std::chrono_literals;
using test::hex;
using test::to_hex;

constexpr std::uint8_t kNode = 5;

class SdoServerTest : public ::testing::Test {
 protected:
  SdoServerTest() : od_(test::make_test_dictionary()) { make_server({}); }

  void make_server(ServerConfig cfg) {
    cfg.node_id = kNode;
    server_ = std::make_unique<SdoServer>(od_, cfg, [this](const can::Frame& f) { sent_.push_back(f); });
  }

  // Feeds one client frame.
  void rx(const Payload& p) { server_->on_frame(make_frame(0x600 + kNode, p), clock_.now()); }
  void rx(std::string_view text) { rx(hex(text)); }

  // The one frame the server sent since the last call, as hex.
  std::string tx() {
    EXPECT_EQ(sent_.size(), 1U) << "frames sent: " << sent_.size();
    if (sent_.empty()) return "(nothing)";
    EXPECT_EQ(sent_.front().id, 0x580U + kNode);
    EXPECT_EQ(sent_.front().len, 8U);
    const std::string s = to_hex(test::payload(sent_.front()));
    sent_.clear();
    return s;
  }
  // Everything sent since the last call, as hex, one frame per entry.
  std::vector<std::string> tx_all() {
    std::vector<std::string> out;
    for (const auto& f : sent_) out.push_back(to_hex(test::payload(f)));
    sent_.clear();
    return out;
  }
  bool silent() const { return sent_.empty(); }

  od::ObjectDictionary od_;
  FakeClock clock_;
  std::vector<can::Frame> sent_;
  std::unique_ptr<SdoServer> server_;
};

// ---- expedited ----------------------------------------------------------------------------

TEST_F(SdoServerTest, ExpeditedDownloadWritesAndConfirms) {
  rx("2B 17 10 00 E8 03 00 00");
  EXPECT_EQ(tx(), "60 17 10 00 00 00 00 00");
  EXPECT_EQ(od_.get_unsigned(test::kHeartbeat, 0), 1000U);
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
  EXPECT_EQ(server_->next_deadline(), TimePoint::max());
}

TEST_F(SdoServerTest, ExpeditedDownloadWithoutSizeTakesTheObjectsSize) {
  rx("22 17 10 00 D0 07 FF FF");  // e=1, s=0: 4 bytes sent, u16 takes 2
  EXPECT_EQ(tx(), "60 17 10 00 00 00 00 00");
  EXPECT_EQ(od_.get_unsigned(test::kHeartbeat, 0), 2000U);
}

TEST_F(SdoServerTest, ExpeditedUpload) {
  rx("40 00 10 00 00 00 00 00");
  EXPECT_EQ(tx(), "43 00 10 00 92 01 02 00");
  rx("40 17 10 00 00 00 00 00");
  EXPECT_EQ(tx(), "4B 17 10 00 00 00 00 00");
  rx("40 02 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "4F 02 20 00 0F 00 00 00");
}

// ---- segmented ------------------------------------------------------------------------------

TEST_F(SdoServerTest, SegmentedDownloadWritesOnlyAtTheEnd) {
  rx("21 00 20 00 0A 00 00 00");  // 10 bytes to the domain
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::DownloadSegment);
  rx("00 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "20 00 00 00 00 00 00 00");
  EXPECT_TRUE(test::domain_bytes(od_, test::kDomain).empty()) << "written before the last segment";
  rx("19 08 09 0A 00 00 00 00");  // t=1, n=4, c=1
  EXPECT_EQ(tx(), "30 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), (Bytes{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, SegmentedDownloadWithoutSizeIndication) {
  rx("20 00 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("07 01 02 03 04 00 00 00");  // t=0, n=3, c=1
  EXPECT_EQ(tx(), "20 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), (Bytes{1, 2, 3, 4}));
}

TEST_F(SdoServerTest, SegmentedDownloadOfNothing) {
  rx("21 00 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("0F 00 00 00 00 00 00 00");  // n=7, c=1
  EXPECT_EQ(tx(), "20 00 00 00 00 00 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, SegmentedUpload) {
  rx("40 01 20 00 00 00 00 00");  // "hello world!", 12 bytes
  EXPECT_EQ(tx(), "41 01 20 00 0C 00 00 00");
  rx("60 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "00 68 65 6C 6C 6F 20 77");
  rx("70 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "15 6F 72 6C 64 21 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, UploadOfAnEmptyObjectIsSegmented) {
  rx("40 00 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "41 00 20 00 00 00 00 00");
  rx("60 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "0F 00 00 00 00 00 00 00");
}

TEST_F(SdoServerTest, RepeatedSegmentIsIgnored) {
  // 7.2.4.3.2: a segment whose toggle bit did not alternate is ignored.
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("00 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "20 00 00 00 00 00 00 00");
  rx("00 01 02 03 04 05 06 07");
  EXPECT_TRUE(silent());
  rx("19 08 09 0A 00 00 00 00");
  EXPECT_EQ(tx(), "30 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain).size(), 10U);
}

TEST_F(SdoServerTest, RepeatedUploadSegmentRequestIsIgnored) {
  rx("40 01 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "41 01 20 00 0C 00 00 00");
  rx("60 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "00 68 65 6C 6C 6F 20 77");
  rx("60 00 00 00 00 00 00 00");
  EXPECT_TRUE(silent());
  rx("70 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "15 6F 72 6C 64 21 00 00");
}

// ---- aborts: protocol errors --------------------------------------------------------------------

TEST_F(SdoServerTest, WrongToggleInDownloadAborts05030000) {
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("00 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "20 00 00 00 00 00 00 00");
  rx("00 11 12 13 14 15 16 17");  // t=0 again, other data: not a repeat
  EXPECT_EQ(tx(), "80 00 20 00 00 00 03 05");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
  EXPECT_TRUE(test::domain_bytes(od_, test::kDomain).empty());
}

TEST_F(SdoServerTest, WrongToggleInUploadAborts05030000) {
  rx("40 01 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "41 01 20 00 0C 00 00 00");
  rx("70 00 00 00 00 00 00 00");  // first request must have t=0
  EXPECT_EQ(tx(), "80 01 20 00 00 00 03 05");
}

TEST_F(SdoServerTest, TimeoutAbortsAfterExactlyTheConfiguredTime) {
  const TimePoint start = clock_.now();
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  EXPECT_EQ(server_->next_deadline(), start + 1s);
  clock_.advance(1s - 1ns);
  server_->on_time(clock_.now());
  EXPECT_TRUE(silent());
  clock_.advance(1ns);
  server_->on_time(clock_.now());
  EXPECT_EQ(tx(), "80 00 20 00 00 00 04 05");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
  EXPECT_EQ(server_->next_deadline(), TimePoint::max());
}

TEST_F(SdoServerTest, TimeoutIsConfigurableAndRestartsWithEachFrame) {
  ServerConfig cfg;
  cfg.timeout = 250ms;
  make_server(cfg);
  rx("40 01 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "41 01 20 00 0C 00 00 00");
  clock_.advance(200ms);
  rx("60 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "00 68 65 6C 6C 6F 20 77");
  EXPECT_EQ(server_->next_deadline(), clock_.now() + 250ms);
  clock_.advance(249ms);
  server_->on_time(clock_.now());
  EXPECT_TRUE(silent());
  clock_.advance(1ms);
  server_->on_time(clock_.now());
  EXPECT_EQ(tx(), "80 01 20 00 00 00 04 05");
}

TEST_F(SdoServerTest, TimeoutInEveryBlockStep) {
  // Block download waiting for segments, block upload waiting for the ack.
  rx("C6 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  clock_.advance(1s);
  server_->on_time(clock_.now());
  EXPECT_EQ(tx(), "80 00 20 00 00 00 04 05");

  rx("A4 01 20 00 7F 00 00 00");
  EXPECT_EQ(tx(), "C6 01 20 00 0C 00 00 00");
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx_all().size(), 2U);
  clock_.advance(1s);
  server_->on_time(clock_.now());
  EXPECT_EQ(tx(), "80 01 20 00 00 00 04 05");
}

TEST_F(SdoServerTest, UnknownCommandSpecifierAborts05040001) {
  rx("E0 17 10 00 00 00 00 00");  // ccs=7 does not exist
  EXPECT_EQ(tx(), "80 17 10 00 01 00 04 05");
}

TEST_F(SdoServerTest, SegmentWithoutTransferAborts05040001) {
  rx("00 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "80 01 02 03 01 00 04 05");
  rx("60 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "80 00 00 00 01 00 04 05");
}

TEST_F(SdoServerTest, WrongCommandInTheMiddleOfATransferAborts05040001) {
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("60 00 00 00 00 00 00 00");  // upload segment request during a download
  EXPECT_EQ(tx(), "80 00 20 00 01 00 04 05");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, BlockEndWithoutTransferAborts05040001) {
  rx("C1 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "80 00 00 00 01 00 04 05");
}

TEST_F(SdoServerTest, ShortFrameAborts05040001) {
  server_->on_frame(can::Frame::standard(0x605, {0x40, 0x00, 0x10}), clock_.now());
  EXPECT_EQ(tx(), "80 00 00 00 01 00 04 05");
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  server_->on_frame(can::Frame::standard(0x605, {0x00, 0x01}), clock_.now());
  EXPECT_EQ(tx(), "80 00 20 00 01 00 04 05");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, InvalidBlockSizeAborts05040002) {
  rx("A4 01 20 00 00 00 00 00");  // blksize 0
  EXPECT_EQ(tx(), "80 01 20 00 02 00 04 05");
  rx("A4 01 20 00 80 00 00 00");  // blksize 128
  EXPECT_EQ(tx(), "80 01 20 00 02 00 04 05");
  // In an acknowledgement.
  rx("A4 01 20 00 01 00 00 00");
  EXPECT_EQ(tx(), "C6 01 20 00 0C 00 00 00");
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "01 68 65 6C 6C 6F 20 77");
  rx("A2 01 00 00 00 00 00 00");  // ackseq 1, blksize 0
  EXPECT_EQ(tx(), "80 01 20 00 02 00 04 05");
}

TEST_F(SdoServerTest, InvalidSequenceNumberAborts05040003) {
  // Block download: seqno 0 ...
  rx("C6 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx("00 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "80 00 20 00 03 00 04 05");
  // ... or above blksize.
  ServerConfig cfg;
  cfg.max_block_size = 4;
  make_server(cfg);
  rx("C6 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "A4 00 20 00 04 00 00 00");
  rx("05 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "80 00 20 00 03 00 04 05");
  // Block upload: ackseq above the number of segments sent.
  rx("A4 01 20 00 7F 00 00 00");
  EXPECT_EQ(tx(), "C6 01 20 00 0C 00 00 00");
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx_all().size(), 2U);
  rx("A2 03 7F 00 00 00 00 00");
  EXPECT_EQ(tx(), "80 01 20 00 03 00 04 05");
}

TEST_F(SdoServerTest, CrcErrorAborts05040004) {
  rx("C6 00 20 00 03 00 00 00");
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx("81 01 02 03 00 00 00 00");
  EXPECT_EQ(tx(), "A2 01 7F 00 00 00 00 00");
  const std::uint16_t good = crc16(Bytes{1, 2, 3});
  rx(block_download_end(4, static_cast<std::uint16_t>(good ^ 1U)));
  EXPECT_EQ(tx(), "80 00 20 00 04 00 04 05");
  EXPECT_TRUE(test::domain_bytes(od_, test::kDomain).empty());
}

TEST_F(SdoServerTest, SizeAboveTheLimitAborts05040005) {
  ServerConfig cfg;
  cfg.max_download_size = 100;
  make_server(cfg);
  rx("21 00 20 00 65 00 00 00");  // segmented, 101 bytes
  EXPECT_EQ(tx(), "80 00 20 00 05 00 04 05");
  rx("C6 00 20 00 65 00 00 00");  // block, 101 bytes
  EXPECT_EQ(tx(), "80 00 20 00 05 00 04 05");
  rx("21 00 20 00 64 00 00 00");  // 100 bytes is fine
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  // Without size indication the limit applies to the data as it comes.
  rx("20 00 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  bool toggle = false;
  std::string last;
  for (int i = 0; i < 15; ++i) {
    rx(download_segment_request(toggle, Bytes(7, 0x55), false));
    last = tx();
    if (last.starts_with("80")) break;
    toggle = !toggle;
  }
  EXPECT_EQ(last, "80 00 20 00 05 00 04 05");
}

TEST_F(SdoServerTest, MoreDataThanIndicatedAborts06070010) {
  rx("21 00 20 00 03 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("00 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "80 00 20 00 10 00 07 06");
  rx("21 00 20 00 09 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("07 01 02 03 04 00 00 00");  // last after 4 of 9 bytes
  EXPECT_EQ(tx(), "80 00 20 00 10 00 07 06");
}

// ---- aborts: object dictionary errors ----------------------------------------------------------

TEST_F(SdoServerTest, ObjectDictionaryErrorsAreAbortCodes) {
  rx("40 00 30 00 00 00 00 00");  // no such object
  EXPECT_EQ(tx(), "80 00 30 00 00 00 02 06");
  rx("40 04 20 07 00 00 00 00");  // no such sub-index
  EXPECT_EQ(tx(), "80 04 20 07 11 00 09 06");
  rx("23 00 10 00 01 02 03 04");  // write a read-only object
  EXPECT_EQ(tx(), "80 00 10 00 02 00 01 06");
  rx("40 03 20 00 00 00 00 00");  // read a write-only object
  EXPECT_EQ(tx(), "80 03 20 00 01 00 01 06");
  rx("23 17 10 00 01 02 03 04");  // 4 bytes to a u16
  EXPECT_EQ(tx(), "80 17 10 00 12 00 07 06");
  rx("2F 17 10 00 01 00 00 00");  // 1 byte to a u16
  EXPECT_EQ(tx(), "80 17 10 00 13 00 07 06");
  rx("2F 02 20 00 15 00 00 00");  // 21 > high limit 20
  EXPECT_EQ(tx(), "80 02 20 00 31 00 09 06");
  rx("2F 02 20 00 09 00 00 00");  // 9 < low limit 10
  EXPECT_EQ(tx(), "80 02 20 00 32 00 09 06");
  rx("40 06 20 00 00 00 00 00");  // the read hook refuses
  EXPECT_EQ(tx(), "80 06 20 00 24 00 00 08");
  EXPECT_EQ(od_.get_unsigned(test::kLimited, 0), 15U);
}

TEST_F(SdoServerTest, SegmentedAndBlockInitiatesCheckTheObjectFirst) {
  rx("21 00 30 00 0A 00 00 00");
  EXPECT_EQ(tx(), "80 00 30 00 00 00 02 06");
  rx("21 00 10 00 0A 00 00 00");
  EXPECT_EQ(tx(), "80 00 10 00 02 00 01 06");
  rx("21 17 10 00 05 00 00 00");  // 5 bytes for a u16
  EXPECT_EQ(tx(), "80 17 10 00 12 00 07 06");
  rx("C6 04 20 09 0A 00 00 00");
  EXPECT_EQ(tx(), "80 04 20 09 11 00 09 06");
  rx("A4 00 30 00 7F 00 00 00");
  EXPECT_EQ(tx(), "80 00 30 00 00 00 02 06");
}

TEST_F(SdoServerTest, SegmentedDownloadRejectedByTheDictionaryAtTheEnd) {
  rx("21 01 20 00 08 00 00 00");  // string: fine until the value is checked
  EXPECT_EQ(tx(), "60 01 20 00 00 00 00 00");
  rx("00 61 62 63 64 65 66 67");
  EXPECT_EQ(tx(), "20 00 00 00 00 00 00 00");
  od_.on_write(test::kString, [](od::SubEntry&, const Value&) { return make_error_code(SdoAbort::CannotStore); });
  rx("1D 68 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "80 01 20 00 20 00 00 08");
}

// ---- abort from the client, restarts, other frames ---------------------------------------------

TEST_F(SdoServerTest, ClientAbortEndsTheTransferSilently) {
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("80 00 20 00 00 00 00 08");
  EXPECT_TRUE(silent());
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
  rx("80 00 20 00 00 00 00 08");  // and when idle, too
  EXPECT_TRUE(silent());
}

TEST_F(SdoServerTest, ClientAbortInsideASubBlock) {
  rx("C6 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx("80 00 20 00 00 00 04 05");
  EXPECT_TRUE(silent());
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, NewInitiateRestartsWithoutAbort) {
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  rx("00 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "20 00 00 00 00 00 00 00");
  rx("40 00 10 00 00 00 00 00");  // a new initiate: the old download is dropped
  EXPECT_EQ(tx(), "43 00 10 00 92 01 02 00");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
  EXPECT_TRUE(test::domain_bytes(od_, test::kDomain).empty());
}

TEST_F(SdoServerTest, IgnoresOtherCobIdsAndRemoteFrames) {
  EXPECT_FALSE(server_->on_frame(make_frame(0x606, hex("40 00 10 00")), clock_.now()));
  EXPECT_FALSE(server_->on_frame(can::Frame::rtr(0x605, 8), clock_.now()));
  EXPECT_TRUE(silent());
}

TEST_F(SdoServerTest, CustomCobIds) {
  ServerConfig cfg;
  cfg.rx_cob_id = 0x640;
  cfg.tx_cob_id = 0x5C0;
  make_server(cfg);
  EXPECT_FALSE(server_->on_frame(make_frame(0x605, hex("40 00 10 00")), clock_.now()));
  EXPECT_TRUE(server_->on_frame(make_frame(0x640, hex("40 00 10 00")), clock_.now()));
  ASSERT_EQ(sent_.size(), 1U);
  EXPECT_EQ(sent_[0].id, 0x5C0U);
}

TEST_F(SdoServerTest, LocalAbort) {
  rx("21 00 20 00 0A 00 00 00");
  EXPECT_EQ(tx(), "60 00 20 00 00 00 00 00");
  server_->abort(SdoAbort::CannotStoreDeviceState);
  EXPECT_EQ(tx(), "80 00 20 00 22 00 00 08");
  server_->abort(SdoAbort::GeneralError);  // idle: nothing
  EXPECT_TRUE(silent());
}

// ---- block download ---------------------------------------------------------------------------------

TEST_F(SdoServerTest, BlockDownload) {
  rx("C6 00 20 00 14 00 00 00");  // 20 bytes with CRC
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx("01 01 02 03 04 05 06 07");
  rx("02 08 09 0A 0B 0C 0D 0E");
  EXPECT_TRUE(silent());
  rx("83 0F 10 11 12 13 14 00");  // c=1, 6 data bytes + 1 padding
  EXPECT_EQ(tx(), "A2 03 7F 00 00 00 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::BlockDownloadEnd);
  Bytes expected;
  for (std::uint8_t i = 1; i <= 20; ++i) expected.push_back(i);
  rx(block_download_end(1, crc16(expected)));
  EXPECT_EQ(tx(), "A1 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), expected);
}

TEST_F(SdoServerTest, BlockDownloadWithoutCrcOrSize) {
  ServerConfig cfg;
  cfg.crc = false;
  make_server(cfg);
  rx("C4 00 20 00 00 00 00 00");  // client offers CRC, server does not
  EXPECT_EQ(tx(), "A0 00 20 00 7F 00 00 00");
  rx("81 AA BB 00 00 00 00 00");
  EXPECT_EQ(tx(), "A2 01 7F 00 00 00 00 00");
  rx("D5 00 00 00 00 00 00 00");  // n=5, CRC not checked
  EXPECT_EQ(tx(), "A1 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), (Bytes{0xAA, 0xBB}));
}

TEST_F(SdoServerTest, BlockDownloadSeveralSubBlocks) {
  ServerConfig cfg;
  cfg.max_block_size = 2;
  make_server(cfg);
  const Bytes data = test::pattern(30);  // 5 segments, the last with 2 bytes
  rx(block_download_initiate({test::kDomain, 0}, true, 30));
  EXPECT_EQ(tx(), "A4 00 20 00 02 00 00 00");
  const auto seg = [&](std::uint8_t seq, std::size_t i) {
    const std::size_t n = std::min<std::size_t>(7, data.size() - i * 7);
    return block_segment(seq, std::span(data).subspan(i * 7, n), i == 4);
  };
  rx(seg(1, 0));
  rx(seg(2, 1));
  EXPECT_EQ(tx(), "A2 02 02 00 00 00 00 00");
  rx(seg(1, 2));
  rx(seg(2, 3));
  EXPECT_EQ(tx(), "A2 02 02 00 00 00 00 00");
  rx(seg(1, 4));
  EXPECT_EQ(tx(), "A2 01 02 00 00 00 00 00");
  rx(block_download_end(5, crc16(data)));
  EXPECT_EQ(tx(), "A1 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), data);
}

TEST_F(SdoServerTest, BlockDownloadLostSegmentIsAcknowledgedForResend) {
  ServerConfig cfg;
  cfg.max_block_size = 4;
  make_server(cfg);
  const Bytes data = test::pattern(35);  // 5 full segments
  const auto seg = [&](std::uint8_t seq, std::size_t i) {
    return block_segment(seq, std::span(data).subspan(i * 7, 7), i == 4);
  };
  rx(block_download_initiate({test::kDomain, 0}, true, 35));
  EXPECT_EQ(tx(), "A4 00 20 00 04 00 00 00");
  rx(seg(1, 0));
  rx(seg(3, 2));  // segment 2 lost: 3 and 4 are dropped
  rx(seg(4, 3));
  EXPECT_EQ(tx(), "A2 01 04 00 00 00 00 00");
  // The client goes on after segment 1.
  rx(seg(1, 1));
  rx(seg(2, 2));
  rx(seg(3, 3));
  rx(seg(4, 4));
  EXPECT_EQ(tx(), "A2 04 04 00 00 00 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::BlockDownloadEnd);
  rx(block_download_end(0, crc16(data)));
  EXPECT_EQ(tx(), "A1 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), data);
}

TEST_F(SdoServerTest, BlockDownloadLostLastSegmentIsAcknowledgedForResend) {
  const Bytes data = test::pattern(14);
  rx(block_download_initiate({test::kDomain, 0}, true, 14));
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx(block_segment(2, std::span(data).subspan(7, 7), true));  // 1 lost, 2 (c=1) arrives
  EXPECT_EQ(tx(), "A2 00 7F 00 00 00 00 00");
  rx(block_segment(1, std::span(data).subspan(0, 7), false));
  rx(block_segment(2, std::span(data).subspan(7, 7), true));
  EXPECT_EQ(tx(), "A2 02 7F 00 00 00 00 00");
  rx(block_download_end(0, crc16(data)));
  EXPECT_EQ(tx(), "A1 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), data);
}

TEST_F(SdoServerTest, BlockDownloadDuplicatesAreIgnored) {
  const Bytes data = test::pattern(14);
  const Payload init = block_download_initiate({test::kDomain, 0}, true, 14);
  rx(init);
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx(init);  // a copy of the initiate must not be taken for a segment
  EXPECT_TRUE(silent());
  rx(block_segment(1, std::span(data).subspan(0, 7), false));
  rx(block_segment(1, std::span(data).subspan(0, 7), false));
  const Payload last = block_segment(2, std::span(data).subspan(7, 7), true);
  rx(last);
  EXPECT_EQ(tx(), "A2 02 7F 00 00 00 00 00");
  rx(last);  // a copy of the last segment in the end phase
  EXPECT_TRUE(silent());
  rx(block_download_end(0, crc16(data)));
  EXPECT_EQ(tx(), "A1 00 00 00 00 00 00 00");
  EXPECT_EQ(test::domain_bytes(od_, test::kDomain), data);
}

TEST_F(SdoServerTest, BlockDownloadOfNothing) {
  rx("C6 00 20 00 00 00 00 00");
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx("81 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "A2 01 7F 00 00 00 00 00");
  rx("DD 00 00 00 00 00 00 00");  // n=7, CRC of nothing = 0
  EXPECT_EQ(tx(), "A1 00 00 00 00 00 00 00");
}

TEST_F(SdoServerTest, BlockDownloadSizeMismatchAtTheEnd) {
  rx("C6 00 20 00 05 00 00 00");
  EXPECT_EQ(tx(), "A4 00 20 00 7F 00 00 00");
  rx("81 01 02 03 04 05 06 07");
  EXPECT_EQ(tx(), "A2 01 7F 00 00 00 00 00");
  rx(block_download_end(0, crc16(Bytes{1, 2, 3, 4, 5, 6, 7})));  // 7 bytes, 5 indicated
  EXPECT_EQ(tx(), "80 00 20 00 10 00 07 06");
}

// ---- block upload -------------------------------------------------------------------------------------

TEST_F(SdoServerTest, BlockUpload) {
  rx("A4 01 20 00 7F 00 00 00");  // "hello world!" with CRC, no protocol switch
  EXPECT_EQ(tx(), "C6 01 20 00 0C 00 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::BlockUploadStart);
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx_all(), (std::vector<std::string>{"01 68 65 6C 6C 6F 20 77", "82 6F 72 6C 64 21 00 00"}));
  rx("A2 02 7F 00 00 00 00 00");
  const std::string text = "hello world!";
  const Payload end = block_upload_end(2, crc16(Bytes(text.begin(), text.end())));
  EXPECT_EQ(tx(), to_hex(end));
  EXPECT_EQ(server_->state(), SdoServer::State::BlockUploadEnd);
  rx("A1 00 00 00 00 00 00 00");
  EXPECT_TRUE(silent());
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, BlockUploadWithoutCrc) {
  rx("A0 01 20 00 7F 00 00 00");  // client without CRC
  EXPECT_EQ(tx(), "C2 01 20 00 0C 00 00 00");
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx_all().size(), 2U);
  rx("A2 02 7F 00 00 00 00 00");
  EXPECT_EQ(tx(), "C9 00 00 00 00 00 00 00");
}

TEST_F(SdoServerTest, BlockUploadProtocolSwitch) {
  rx("A4 00 10 00 7F 04 00 00");  // 4 bytes <= pst 4: expedited answer
  EXPECT_EQ(tx(), "43 00 10 00 92 01 02 00");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
  rx("A4 01 20 00 7F 0C 00 00");  // 12 bytes <= pst 12: segmented
  EXPECT_EQ(tx(), "41 01 20 00 0C 00 00 00");
  rx("60 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "00 68 65 6C 6C 6F 20 77");
  rx("70 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "15 6F 72 6C 64 21 00 00");
  rx("A4 01 20 00 7F 0B 00 00");  // 12 bytes > pst 11: block
  EXPECT_EQ(tx(), "C6 01 20 00 0C 00 00 00");
}

TEST_F(SdoServerTest, BlockUploadClientBlockSizeAndResend) {
  const Bytes data = test::pattern(40);  // 6 segments, the last with 5 bytes
  ASSERT_FALSE(od_.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
  const auto seg = [&](std::uint8_t seq, std::size_t i) {
    const std::size_t n = std::min<std::size_t>(7, data.size() - i * 7);
    return to_hex(block_segment(seq, std::span(data).subspan(i * 7, n), i == 5));
  };
  rx("A4 05 20 00 03 00 00 00");  // blksize 3
  EXPECT_EQ(tx(), "C6 05 20 00 28 00 00 00");
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx_all(), (std::vector<std::string>{seg(1, 0), seg(2, 1), seg(3, 2)}));
  rx("A2 01 03 00 00 00 00 00");  // only the first arrived: resend from segment 2
  EXPECT_EQ(tx_all(), (std::vector<std::string>{seg(1, 1), seg(2, 2), seg(3, 3)}));
  rx("A2 03 02 00 00 00 00 00");  // all three, and blksize 2 from now on
  EXPECT_EQ(tx_all(), (std::vector<std::string>{seg(1, 4), seg(2, 5)}));
  rx("A2 01 02 00 00 00 00 00");  // the last (c=1) was lost
  EXPECT_EQ(tx_all(), (std::vector<std::string>{seg(1, 5)}));
  rx("A2 01 02 00 00 00 00 00");  // an equal partial ack is taken for a bus duplicate
  EXPECT_TRUE(silent());
  rx("A2 01 7F 00 00 00 00 00");  // (a receiver varies blksize to make it distinct)
  EXPECT_EQ(tx(), to_hex(block_upload_end(2, crc16(data))));
  rx("A2 01 7F 00 00 00 00 00");  // a late copy in the end phase changes nothing
  EXPECT_TRUE(silent());
  rx("A1 00 00 00 00 00 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, EqualFullSubBlockAcksAreNotDuplicates) {
  const Bytes data = test::pattern(21);  // 3 segments with blksize 1
  ASSERT_FALSE(od_.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
  rx("A4 05 20 00 01 00 00 00");
  EXPECT_EQ(tx(), "C6 05 20 00 15 00 00 00");
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), to_hex(block_segment(1, std::span(data).subspan(0, 7), false)));
  rx("A2 01 01 00 00 00 00 00");
  EXPECT_EQ(tx(), to_hex(block_segment(1, std::span(data).subspan(7, 7), false)));
  rx("A2 01 01 00 00 00 00 00");
  EXPECT_EQ(tx(), to_hex(block_segment(1, std::span(data).subspan(14, 7), true)));
  rx("A2 01 01 00 00 00 00 00");
  EXPECT_EQ(tx(), to_hex(block_upload_end(0, crc16(data))));
}

TEST_F(SdoServerTest, RepeatedPartialAckGetsAnotherBlockSize) {
  // Segment 2 lost twice in a row: the second ack must not equal the first.
  ServerConfig cfg;
  cfg.max_block_size = 4;
  make_server(cfg);
  const Bytes data = test::pattern(70);
  const auto seg = [&](std::uint8_t seq, std::size_t i) {
    return block_segment(seq, std::span(data).subspan(i * 7, 7), i == 9);
  };
  rx(block_download_initiate({test::kDomain, 0}, true, 70));
  EXPECT_EQ(tx(), "A4 00 20 00 04 00 00 00");
  rx(seg(1, 0));
  rx(seg(4, 3));
  EXPECT_EQ(tx(), "A2 01 04 00 00 00 00 00");
  rx(seg(1, 1));
  rx(seg(4, 4));
  EXPECT_EQ(tx(), "A2 01 03 00 00 00 00 00");  // blksize 3 for the next sub-block
  rx(seg(1, 2));
  rx(seg(2, 3));
  rx(seg(3, 4));
  EXPECT_EQ(tx(), "A2 03 03 00 00 00 00 00");
  rx(seg(4, 5));  // above the new blksize
  EXPECT_EQ(tx(), "80 00 20 00 03 00 04 05");
}

TEST_F(SdoServerTest, BlockUploadOfNothing) {
  rx("A4 00 20 00 7F 00 00 00");
  EXPECT_EQ(tx(), "C6 00 20 00 00 00 00 00");
  rx("A3 00 00 00 00 00 00 00");
  EXPECT_EQ(tx(), "81 00 00 00 00 00 00 00");
  rx("A2 01 7F 00 00 00 00 00");
  EXPECT_EQ(tx(), "DD 00 00 00 00 00 00 00");
  rx("A1 00 00 00 00 00 00 00");
  EXPECT_EQ(server_->state(), SdoServer::State::Idle);
}

TEST_F(SdoServerTest, BlockUploadExactlyOneFullSubBlock) {
  ServerConfig cfg;
  make_server(cfg);
  const Bytes data = test::pattern(889);  // 127 * 7: the last segment of the block has c=1
  ASSERT_FALSE(od_.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
  rx("A4 05 20 00 7F 00 00 00");
  EXPECT_EQ(tx(), "C6 05 20 00 79 03 00 00");
  rx("A3 00 00 00 00 00 00 00");
  const auto frames = tx_all();
  ASSERT_EQ(frames.size(), 127U);
  EXPECT_TRUE(frames.back().starts_with("FF"));
  rx("A2 7F 7F 00 00 00 00 00");
  EXPECT_EQ(tx(), to_hex(block_upload_end(0, crc16(data))));
}

}  // namespace
}  // namespace canopen::sdo
