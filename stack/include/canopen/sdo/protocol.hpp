// SDO wire format (CiA 301 7.2.4.3): command specifiers, the byte layout of
// every SDO frame in both directions, builders and parsers, and the CRC-16
// of block transfers (7.2.4.3.16).
//
// Every SDO frame carries exactly 8 data bytes. Byte 0 is the command byte
// (bits 7..5 = command specifier, except for block segments), bytes 1..2
// the index (little-endian), byte 3 the sub-index, bytes 4..7 data or size.
//
// Builders return the 8 payload bytes; make_frame() wraps them in a CAN
// frame. Parsers take the 8 payload bytes and never fail: they decode the
// bit fields; deciding whether a field is acceptable is the state machines'
// job. All functions are pure and thread-safe.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>

#include "canopen/can/frame.hpp"

namespace canopen::sdo {

using Payload = std::array<std::uint8_t, 8>;
// Where the SDO services put the frames they send.
using FrameSink = std::function<void(const can::Frame&)>;
using PayloadView = std::span<const std::uint8_t, 8>;

inline constexpr std::size_t kFrameLength = 8;
inline constexpr std::size_t kExpeditedMax = 4;   // data bytes in an expedited initiate
inline constexpr std::size_t kSegmentData = 7;    // data bytes per (block) segment
inline constexpr std::uint8_t kMinBlockSize = 1;  // segments per sub-block, 0 < blksize < 128
inline constexpr std::uint8_t kMaxBlockSize = 127;
inline constexpr std::uint32_t kDefaultRxBase = 0x600;  // client -> server, + node-ID
inline constexpr std::uint32_t kDefaultTxBase = 0x580;  // server -> client, + node-ID

// Client command specifier (ccs), bits 7..5 of byte 0 of a client frame.
enum class ClientCommand : std::uint8_t {
  DownloadSegment = 0,
  InitiateDownload = 1,
  InitiateUpload = 2,
  UploadSegment = 3,
  Abort = 4,
  BlockUpload = 5,
  BlockDownload = 6,
};

// Server command specifier (scs), bits 7..5 of byte 0 of a server frame.
enum class ServerCommand : std::uint8_t {
  UploadSegment = 0,
  DownloadSegment = 1,
  InitiateUpload = 2,
  InitiateDownload = 3,
  Abort = 4,
  BlockDownload = 5,
  BlockUpload = 6,
};

// Sub-commands of the block protocols: cs/ss in bits 1..0 (bit 0 only where
// the other bit carries a flag).
enum class BlockDownloadClientSub : std::uint8_t { Initiate = 0, End = 1 };
enum class BlockDownloadServerSub : std::uint8_t { Initiate = 0, End = 1, Ack = 2 };
enum class BlockUploadClientSub : std::uint8_t { Initiate = 0, End = 1, Ack = 2, Start = 3 };
enum class BlockUploadServerSub : std::uint8_t { Initiate = 0, End = 1 };

// The multiplexer: which object an SDO transfer is about.
struct Multiplexer {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  friend bool operator==(const Multiplexer&, const Multiplexer&) = default;
};

// ---- common fields -----------------------------------------------------------
inline std::uint8_t command_bits(PayloadView p) { return static_cast<std::uint8_t>(p[0] >> 5); }
inline Multiplexer multiplexer(PayloadView p) {
  return {static_cast<std::uint16_t>(p[1] | (p[2] << 8)), p[3]};
}
inline std::uint32_t u32_at(PayloadView p, std::size_t at) {
  return static_cast<std::uint32_t>(p[at]) | (static_cast<std::uint32_t>(p[at + 1]) << 8) |
         (static_cast<std::uint32_t>(p[at + 2]) << 16) | (static_cast<std::uint32_t>(p[at + 3]) << 24);
}
// The 8 payload bytes of a frame. Precondition: f.len >= 8.
inline PayloadView payload_of(const can::Frame& f) { return PayloadView(f.data.data(), kFrameLength); }
// A classic 11-bit data frame with the 8 bytes.
can::Frame make_frame(std::uint32_t cob_id, const Payload& p);

// ---- initiate download request / initiate upload response -------------------
// Same layout (7.2.4.3.3, 7.2.4.3.6): cs | x | n(3..2) | e(1) | s(0), m, d.
struct Initiate {
  Multiplexer mux;
  bool expedited = false;
  bool size_indicated = false;
  // Expedited: number of data bytes in bytes 4..7 (4 - n, or 4 when s = 0).
  // Normal: the indicated size (0 when s = 0).
  std::uint32_t size = 0;
};
Initiate parse_initiate(PayloadView p);

// Expedited, 1..4 data bytes. Without size indication n is 0 and all four
// bytes go out (unused ones 0), as the standard allows for e=1, s=0.
Payload initiate_download_expedited(Multiplexer m, std::span<const std::uint8_t> data, bool indicate_size = true);
Payload initiate_download_normal(Multiplexer m, std::optional<std::uint32_t> size);
Payload initiate_download_response(Multiplexer m);
Payload initiate_upload_request(Multiplexer m);
Payload initiate_upload_response_expedited(Multiplexer m, std::span<const std::uint8_t> data,
                                           bool indicate_size = true);
Payload initiate_upload_response_normal(Multiplexer m, std::optional<std::uint32_t> size);

// ---- segments (7.2.4.3.4, 7.2.4.3.7) ------------------------------------------
// Download segment request and upload segment response share the layout
// cs | t(4) | n(3..1) | c(0), 7 data bytes.
struct Segment {
  bool toggle = false;
  bool last = false;     // c
  std::uint8_t size = 0; // data bytes, 7 - n
};
Segment parse_segment(PayloadView p);
// data: 0..7 bytes (0 is legal: an empty last segment of an empty transfer).
Payload download_segment_request(bool toggle, std::span<const std::uint8_t> data, bool last);
Payload download_segment_response(bool toggle);
Payload upload_segment_request(bool toggle);
Payload upload_segment_response(bool toggle, std::span<const std::uint8_t> data, bool last);
inline bool toggle_bit(PayloadView p) { return (p[0] & 0x10U) != 0; }

// ---- block transfer ------------------------------------------------------------
// Block download initiate request and block upload initiate response share
// the layout cs | x x | crc(2) | s(1) | sub(0), m, size (7.2.4.3.9, 7.2.4.3.13).
struct BlockInitiate {
  Multiplexer mux;
  bool crc = false;
  bool size_indicated = false;
  std::uint32_t size = 0;
};
BlockInitiate parse_block_initiate(PayloadView p);
Payload block_download_initiate(Multiplexer m, bool crc, std::optional<std::uint32_t> size);
Payload block_upload_initiate_response(Multiplexer m, bool crc, std::optional<std::uint32_t> size);

// Block download initiate response: scs=5 | x x | sc(2) | ss=0, m, blksize.
Payload block_download_initiate_response(Multiplexer m, bool crc, std::uint8_t blksize);
// Block upload initiate request: ccs=5 | x x | cc(2) | cs=0, m, blksize, pst.
Payload block_upload_initiate(Multiplexer m, bool crc, std::uint8_t blksize, std::uint8_t pst);
inline bool crc_bit(PayloadView p) { return (p[0] & 0x04U) != 0; }
inline std::uint8_t block_sub_command(PayloadView p) { return static_cast<std::uint8_t>(p[0] & 0x03U); }

// Sub-block segment (7.2.4.3.10, 7.2.4.3.14), both directions: c(7) | seqno(6..0), 7 data bytes.
struct BlockSegment {
  std::uint8_t seqno = 0;
  bool last = false;
};
inline BlockSegment parse_block_segment(PayloadView p) {
  return {static_cast<std::uint8_t>(p[0] & 0x7FU), (p[0] & 0x80U) != 0};
}
// data: 0..7 bytes, the rest is sent as 0.
Payload block_segment(std::uint8_t seqno, std::span<const std::uint8_t> data, bool last);

// Block acknowledge: byte 0 = A2h (scs=5 ss=2 from a download server, ccs=5
// cs=2 from an upload client), ackseq, blksize.
struct BlockAck {
  std::uint8_t ackseq = 0;
  std::uint8_t blksize = 0;
};
inline BlockAck parse_block_ack(PayloadView p) { return {p[1], p[2]}; }
Payload block_download_ack(std::uint8_t ackseq, std::uint8_t blksize);
Payload block_upload_ack(std::uint8_t ackseq, std::uint8_t blksize);
// The blksize a block receiver announces in its next ack. A sender cannot
// tell a repeated ack from a bus duplicate, so it takes an ack equal to the
// previous one as a duplicate unless it confirms a full sub-block (ackseq ==
// blksize, the normal case of successive full sub-blocks). When the ack
// about to be sent would equal `previous` without being such a full ack,
// this returns another blksize (toggling between max_blksize and
// max_blksize - 1) so the two frames differ; otherwise `blksize`.
std::uint8_t distinct_ack_blksize(std::optional<BlockAck> previous, std::uint8_t ackseq, std::uint8_t blksize,
                                  std::uint8_t max_blksize);
// Block upload start (client): A3h.
Payload block_upload_start();

// Block end from the data sender: cs=6 | n(4..2) | x | 1, crc (7.2.4.3.11, 7.2.4.3.15).
struct BlockEnd {
  std::uint8_t unused = 0;  // n: bytes of the last segment without data
  std::uint16_t crc = 0;
};
inline BlockEnd parse_block_end(PayloadView p) {
  return {static_cast<std::uint8_t>((p[0] >> 2) & 0x07U), static_cast<std::uint16_t>(p[1] | (p[2] << 8))};
}
Payload block_download_end(std::uint8_t unused, std::uint16_t crc);
Payload block_upload_end(std::uint8_t unused, std::uint16_t crc);
// End response from the data receiver: A1h.
Payload block_download_end_response();
Payload block_upload_end_response();

// ---- abort (7.2.4.3.17) -----------------------------------------------------------
Payload abort_transfer(Multiplexer m, std::uint32_t code);
inline std::uint32_t abort_code(PayloadView p) { return u32_at(p, 4); }

// ---- CRC (7.2.4.3.16) ------------------------------------------------------------
// CRC-16 with polynomial x^16+x^12+x^5+1 (1021h), initial value 0000h, no
// reflection, no final XOR: crc16("123456789") == 31C3h. Pass the previous
// result as `crc` to continue over several pieces.
std::uint16_t crc16(std::span<const std::uint8_t> data, std::uint16_t crc = 0);

}  // namespace canopen::sdo
