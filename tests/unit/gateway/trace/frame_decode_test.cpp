// Trace decoding, one table per CiA 301 service (COB-IDs of the predefined
// connection set, CiA 301 7.3.5 table 72). Frames are written in the
// can-utils text form; the gateway's own node-ID is 127 unless a row says.
#include "trace/frame_decode.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace gateway::trace {
namespace {

struct Row {
  const char* frame;
  const char* decoded;
};

std::string run(const char* text, std::uint8_t own = 127) {
  auto f = canopen::can::parse_frame(text);
  EXPECT_TRUE(f) << text;
  DecodeContext ctx;
  ctx.own_node_id = own;
  return f ? decode(*f, ctx) : "";
}

void check(const std::vector<Row>& rows) {
  for (const auto& r : rows) EXPECT_EQ(run(r.frame), r.decoded) << r.frame;
}

// 7.2.8.3.1 NMT node control: cs 01h start, 02h stop, 80h pre-operational,
// 81h reset node, 82h reset communication; node-ID 0 = all nodes.
TEST(FrameDecode, NmtNodeControl_Cia301_7_2_8_3_1) {
  check({{"000#0100", "NMT start all"},
         {"000#0205", "NMT stop 5"},
         {"000#800A", "NMT pre-operational 10"},
         {"000#8100", "NMT reset node all"},
         {"000#827F", "NMT reset communication 127"},
         {"000#0705", "NMT cs 07h 5"},
         {"000#01", "NMT malformed (1 byte)"}});
}

// 7.2.5 SYNC: no data, or the counter (1..240) in one byte.
TEST(FrameDecode, SyncWithAndWithoutCounter_Cia301_7_2_5) {
  check({{"080#", "SYNC"}, {"080#05", "SYNC 5"}, {"080#0102", "SYNC malformed (2 bytes)"}});
}

// 7.2.6 TIME: TIME_OF_DAY, ms after midnight (28 bits) and days since
// 1984-01-01: 03D06D53h ms = 17:46:31.123, 3D34h = 15668 days = 2026-11-24.
TEST(FrameDecode, TimeOfDay_Cia301_7_2_6) {
  check({{"100#000000000000", "TIME 1984-01-01 00:00:00.000"},
         {"100#536DD003343D", "TIME 2026-11-24 17:46:31.123"},
         {"100#00", "TIME malformed (1 byte)"}});
}

// 7.2.7.3.1 EMCY: error code (LE), error register, manufacturer bytes;
// 0000h is "error reset or no error".
TEST(FrameDecode, Emcy_Cia301_7_2_7_3_1) {
  check({{"085#1032040000000000", "EMCY 5 3210h register 04h"},
         {"0FF#0000000000000000", "EMCY 127 0000h register 00h (error reset)"},
         {"085#10", "EMCY 5 malformed (1 byte)"}});
}

// 7.3.5 default PDO COB-IDs: TPDO1..4 at 180h/280h/380h/480h + node,
// RPDO1..4 at 200h/300h/400h/500h + node; an RTR asks for a TPDO.
TEST(FrameDecode, PdosOfThePredefinedConnectionSet_Cia301_7_3_5) {
  check({{"185#0102", "TPDO1 5"},
         {"285#", "TPDO2 5"},
         {"38A#01", "TPDO3 10"},
         {"4FF#01", "TPDO4 127"},
         {"20A#01", "RPDO1 10"},
         {"30A#01", "RPDO2 10"},
         {"405#01", "RPDO3 5"},
         {"505#01", "RPDO4 5"},
         {"185#R", "TPDO1 5 RTR"}});
}

// 7.2.4.3 SDO: from the gateway's point of view it is the client of node
// 5: requests on 605h are "SDO tx 5", responses on 585h "SDO rx 5".
TEST(FrameDecode, SdoExpeditedAndSegmented_Cia301_7_2_4_3) {
  check({// initiate upload request / expedited response with 4 bytes (e=1 s=1 n=0)
         {"605#4018100100000000", "SDO tx 5 upload 1018h:01"},
         {"585#4318100178563412", "SDO rx 5 upload 1018h:01 4 bytes"},
         {"585#4F00100001000000", "SDO rx 5 upload 1000h:00 1 byte"},
         // expedited download of 2 bytes (n=2), confirmed
         {"605#2B40600006000000", "SDO tx 5 download 6040h:00 2 bytes"},
         {"585#6040600000000000", "SDO rx 5 download 6040h:00 ok"},
         // segmented download: size indicated, segments with toggle, last with c
         {"605#2108100014000000", "SDO tx 5 download 1008h:00 size 20"},
         {"605#0041424344454647", "SDO tx 5 download segment t0 7 bytes"},
         {"585#2000000000000000", "SDO rx 5 download segment t0 ok"},
         {"605#1B41420000000000", "SDO tx 5 download segment t1 2 bytes last"},
         // segmented upload
         {"585#4108100014000000", "SDO rx 5 upload 1008h:00 size 20"},
         {"605#6000000000000000", "SDO tx 5 upload segment t0"},
         {"585#1141424344454647", "SDO rx 5 upload segment t1 7 bytes last"},
         {"605#40", "SDO tx 5 malformed (1 byte)"}});
}

// 7.2.4.3.17 abort transfer, with the code and its CiA 301 table 22 text.
TEST(FrameDecode, SdoAbortWithCode_Cia301_7_2_4_3_17) {
  check({{"585#8000200000000206", "SDO rx 5 abort 2000h:00 0x06020000 (Object does not exist in the object dictionary)"}});
}

// The gateway's own node-ID is the SDO server: requests to it are received.
TEST(FrameDecode, SdoToTheGatewaysOwnServerIsRx) {
  EXPECT_EQ(run("67F#4018100100000000"), "SDO rx 127 upload 1018h:01");
  EXPECT_EQ(run("5FF#4318100178563412"), "SDO tx 127 upload 1018h:01 4 bytes");
  EXPECT_EQ(run("605#4018100100000000", 5), "SDO rx 5 upload 1018h:01");
}

// 7.2.4.3.9-15 block download: initiate, sub-block segments (seqno, c in
// bit 7), ack, end with CRC; the segments are only told apart by following
// the transfer (track_sdo_block).
TEST(FrameDecode, SdoBlockDownloadFollowed_Cia301_7_2_4_3_9) {
  std::vector<Row> rows = {{"605#C6501F0110000000", "SDO tx 5 block download 1F50h:01 size 16 crc"},
                           {"585#A4501F0104000000", "SDO rx 5 block download 1F50h:01 blksize 4"},
                           {"605#0100010203040506", "SDO tx 5 block segment 1"},
                           {"605#0207080910111213", "SDO tx 5 block segment 2"},
                           {"605#8314150000000000", "SDO tx 5 block segment 3 last"},
                           {"585#A203040000000000", "SDO rx 5 block download ack seq 3 blksize 4"},
                           {"605#D5ABCD0000000000", "SDO tx 5 block download end 2 bytes crc CDABh"},
                           {"585#A100000000000000", "SDO rx 5 block download end ok"}};
  DecodeContext ctx;
  ctx.own_node_id = 127;
  for (const auto& r : rows) {
    const auto f = *canopen::can::parse_frame(r.frame);
    EXPECT_EQ(decode(f, ctx), r.decoded) << r.frame;
    track_sdo_block(f, ctx.block);
  }
  EXPECT_FALSE(ctx.block.download[5]);
}

// Block upload: initiate, response with size, start, server segments, ack, end.
TEST(FrameDecode, SdoBlockUploadFollowed_Cia301_7_2_4_3_12) {
  std::vector<Row> rows = {{"605#A418100104000000", "SDO tx 5 block upload 1018h:01 blksize 4"},
                           {"585#C618100104000000", "SDO rx 5 block upload 1018h:01 size 4"},
                           {"605#A300000000000000", "SDO tx 5 block upload start"},
                           {"585#8178563412000000", "SDO rx 5 block segment 1 last"},
                           {"605#A201040000000000", "SDO tx 5 block upload ack seq 1 blksize 4"},
                           {"585#CD12340000000000", "SDO rx 5 block upload end 4 bytes crc 3412h"},
                           {"605#A100000000000000", "SDO tx 5 block upload end ok"}};
  DecodeContext ctx;
  for (const auto& r : rows) {
    const auto f = *canopen::can::parse_frame(r.frame);
    EXPECT_EQ(decode(f, ctx), r.decoded) << r.frame;
    track_sdo_block(f, ctx.block);
  }
}

// An abort ends a block transfer: what follows is read as commands again.
TEST(FrameDecode, SdoAbortEndsABlockTransfer) {
  SdoBlockState st;
  track_sdo_block(*canopen::can::parse_frame("585#A4501F0104000000"), st);
  EXPECT_TRUE(st.download[5]);
  track_sdo_block(*canopen::can::parse_frame("585#80501F0100000405"), st);
  EXPECT_FALSE(st.download[5]);
}

// 7.2.8.3.2 error control: boot-up (00h), heartbeat states 04h/05h/7Fh,
// node guarding (RTR request, toggle bit 7 in the answer).
TEST(FrameDecode, HeartbeatBootUpAndGuarding_Cia301_7_2_8_3_2) {
  check({{"705#00", "boot-up 5"},
         {"705#05", "HB 5 operational"},
         {"705#04", "HB 5 stopped"},
         {"70A#7F", "HB 10 pre-operational"},
         {"705#85", "HB 5 operational toggle"},
         {"705#R1", "guard request 5"},
         {"705#", "HB 5 malformed (0 bytes)"}});
}

// CiA 305 LSS: master 7E5h, slaves 7E4h.
TEST(FrameDecode, Lss_Cia305) {
  check({{"7E5#0401000000000000", "LSS switch state global configuration"},
         {"7E5#0400000000000000", "LSS switch state global waiting"},
         {"7E5#110A000000000000", "LSS configure node-ID 10"},
         {"7E4#1100000000000000", "LSS response configure node-ID ok"},
         {"7E4#1101000000000000", "LSS response configure node-ID error 1"},
         {"7E5#4078563412000000", "LSS switch state selective vendor 12345678h"},
         {"7E4#4400000000000000", "LSS response switch state selective"},
         {"7E5#1700000000000000", "LSS store configuration"},
         {"7E5#5A00000000000000", "LSS inquire vendor"},
         {"7E4#5A78563412000000", "LSS response vendor 12345678h"},
         {"7E5#5E00000000000000", "LSS inquire node-ID"},
         {"7E4#5E05000000000000", "LSS response node-ID 5"},
         {"7E5#5100000000800000", "LSS fastscan reset id 00000000h bit 128 sub 0 next 0"},
         {"7E4#4F00000000000000", "LSS response identify slave"}});
}

// Outside the predefined connection set, 29-bit ids, node 0: raw.
TEST(FrameDecode, UnknownIdsAreRaw) {
  check({{"123#DEADBEEF", "raw"}, {"180#01", "raw"}, {"12345678#01", "raw"}, {"7FF#00", "raw"}});
}

// The structured service and node of every frame (the trace message's
// "service" and "node", which the dashboard filters on): one row per CiA 301
// service of the predefined connection set (7.3.5 table 72); node 0 = none.
// Whatever decode() calls raw is "other".
TEST(FrameClassify, ServiceAndNodePerCobId_Cia301_7_3_5) {
  struct C {
    const char* frame;
    std::string_view service;
    int node;
  };
  for (const auto& c : std::vector<C>{
           {"000#0100", "nmt", 0},            // start all: no single node
           {"000#020A", "nmt", 10},           // addressed to node 10
           {"000#01", "nmt", 0},              // malformed: no node to name
           {"080#", "sync", 0},
           {"080#05", "sync", 0},
           {"100#000000000000", "time", 0},
           {"08A#1032040000000000", "emcy", 10},
           {"18A#0102", "tpdo", 10},
           {"48A#R8", "tpdo", 10},            // remote request of TPDO4
           {"20A#01", "rpdo", 10},
           {"50A#01", "rpdo", 10},
           {"58A#4318100178563412", "sdo", 10},
           {"60A#4018100100000000", "sdo", 10},
           {"70A#05", "error-control", 10},   // heartbeat
           {"70A#00", "error-control", 10},   // boot-up
           {"70A#R1", "error-control", 10},   // guard request
           {"7E5#0401000000000000", "lss", 0},
           {"7E4#5E05000000000000", "lss", 0},
           {"123#DEADBEEF", "other", 0},
           {"180#01", "other", 0},            // node 0
           {"60A#R8", "other", 0},            // no remote SDO
           {"12345678#01", "other", 0},       // 29-bit
       }) {
    auto f = canopen::can::parse_frame(c.frame);
    ASSERT_TRUE(f) << c.frame;
    const Service s = classify(*f);
    EXPECT_EQ(s.service, c.service) << c.frame;
    EXPECT_EQ(s.node, c.node) << c.frame;
    DecodeContext ctx;
    EXPECT_EQ(s.service == "other", decode(*f, ctx) == "raw") << c.frame;
  }
}

}  // namespace
}  // namespace gateway::trace
