#include "canopen/sdo/protocol.hpp"

#include <algorithm>
#include <cassert>

namespace canopen::sdo {

namespace {

constexpr std::uint8_t cs_byte(std::uint8_t cs) { return static_cast<std::uint8_t>(cs << 5); }
constexpr std::uint8_t cs_byte(ClientCommand c) { return cs_byte(static_cast<std::uint8_t>(c)); }
constexpr std::uint8_t cs_byte(ServerCommand c) { return cs_byte(static_cast<std::uint8_t>(c)); }

void put_mux(Payload& p, Multiplexer m) {
  p[1] = static_cast<std::uint8_t>(m.index & 0xFFU);
  p[2] = static_cast<std::uint8_t>(m.index >> 8);
  p[3] = m.sub;
}

void put_u32(Payload& p, std::size_t at, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) p[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void put_data(Payload& p, std::size_t at, std::span<const std::uint8_t> data) {
  assert(at + data.size() <= p.size());
  std::copy(data.begin(), data.end(), p.begin() + static_cast<std::ptrdiff_t>(at));
}

// Initiate download request / initiate upload response: same layout.
Payload initiate_expedited(std::uint8_t cs, Multiplexer m, std::span<const std::uint8_t> data, bool indicate_size) {
  assert(!data.empty() && data.size() <= kExpeditedMax);
  Payload p{};
  std::uint8_t b0 = static_cast<std::uint8_t>(cs_byte(cs) | 0x02U);  // e = 1
  if (indicate_size) b0 = static_cast<std::uint8_t>(b0 | ((kExpeditedMax - data.size()) << 2) | 0x01U);
  p[0] = b0;
  put_mux(p, m);
  put_data(p, 4, data);
  return p;
}

Payload initiate_normal(std::uint8_t cs, Multiplexer m, std::optional<std::uint32_t> size) {
  Payload p{};
  p[0] = static_cast<std::uint8_t>(cs_byte(cs) | (size ? 0x01U : 0x00U));
  put_mux(p, m);
  if (size) put_u32(p, 4, *size);
  return p;
}

Payload segment(std::uint8_t cs, bool toggle, std::span<const std::uint8_t> data, bool last) {
  assert(data.size() <= kSegmentData);
  Payload p{};
  p[0] = static_cast<std::uint8_t>(cs_byte(cs) | (toggle ? 0x10U : 0U) | ((kSegmentData - data.size()) << 1) |
                                   (last ? 0x01U : 0U));
  put_data(p, 1, data);
  return p;
}

Payload block_initiate(std::uint8_t cs, Multiplexer m, bool crc, std::optional<std::uint32_t> size) {
  Payload p{};
  p[0] = static_cast<std::uint8_t>(cs_byte(cs) | (crc ? 0x04U : 0U) | (size ? 0x02U : 0U));
  put_mux(p, m);
  if (size) put_u32(p, 4, *size);
  return p;
}

Payload single(std::uint8_t b0) {
  Payload p{};
  p[0] = b0;
  return p;
}

Payload ack(std::uint8_t b0, std::uint8_t ackseq, std::uint8_t blksize) {
  Payload p{};
  p[0] = b0;
  p[1] = ackseq;
  p[2] = blksize;
  return p;
}

Payload end(std::uint8_t cs, std::uint8_t unused, std::uint16_t crc) {
  assert(unused <= kSegmentData);
  Payload p{};
  p[0] = static_cast<std::uint8_t>(cs_byte(cs) | ((unused & 0x07U) << 2) | 0x01U);
  p[1] = static_cast<std::uint8_t>(crc & 0xFFU);
  p[2] = static_cast<std::uint8_t>(crc >> 8);
  return p;
}

constexpr std::uint8_t u8(ClientCommand c) { return static_cast<std::uint8_t>(c); }
constexpr std::uint8_t u8(ServerCommand c) { return static_cast<std::uint8_t>(c); }

// Table for the MSB-first CRC-16 with polynomial 1021h.
constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> t{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned c = i << 8;
    for (int b = 0; b < 8; ++b) c = (c & 0x8000U) != 0 ? (c << 1) ^ 0x1021U : c << 1;
    t[i] = static_cast<std::uint16_t>(c & 0xFFFFU);
  }
  return t;
}
constexpr auto kCrcTable = make_crc_table();

}  // namespace

can::Frame make_frame(std::uint32_t cob_id, const Payload& p) {
  can::Frame f;
  f.id = cob_id;
  f.len = static_cast<std::uint8_t>(kFrameLength);
  std::copy(p.begin(), p.end(), f.data.begin());
  return f;
}

Initiate parse_initiate(PayloadView p) {
  Initiate r;
  r.mux = multiplexer(p);
  r.expedited = (p[0] & 0x02U) != 0;
  r.size_indicated = (p[0] & 0x01U) != 0;
  if (r.expedited) {
    r.size = r.size_indicated ? static_cast<std::uint32_t>(kExpeditedMax - ((p[0] >> 2) & 0x03U))
                              : static_cast<std::uint32_t>(kExpeditedMax);
  } else {
    r.size = r.size_indicated ? u32_at(p, 4) : 0;
  }
  return r;
}

Payload initiate_download_expedited(Multiplexer m, std::span<const std::uint8_t> data, bool indicate_size) {
  return initiate_expedited(u8(ClientCommand::InitiateDownload), m, data, indicate_size);
}
Payload initiate_download_normal(Multiplexer m, std::optional<std::uint32_t> size) {
  return initiate_normal(u8(ClientCommand::InitiateDownload), m, size);
}
Payload initiate_download_response(Multiplexer m) {
  Payload p{};
  p[0] = cs_byte(ServerCommand::InitiateDownload);
  put_mux(p, m);
  return p;
}
Payload initiate_upload_request(Multiplexer m) {
  Payload p{};
  p[0] = cs_byte(ClientCommand::InitiateUpload);
  put_mux(p, m);
  return p;
}
Payload initiate_upload_response_expedited(Multiplexer m, std::span<const std::uint8_t> data, bool indicate_size) {
  return initiate_expedited(u8(ServerCommand::InitiateUpload), m, data, indicate_size);
}
Payload initiate_upload_response_normal(Multiplexer m, std::optional<std::uint32_t> size) {
  return initiate_normal(u8(ServerCommand::InitiateUpload), m, size);
}

Segment parse_segment(PayloadView p) {
  return {toggle_bit(p), (p[0] & 0x01U) != 0, static_cast<std::uint8_t>(kSegmentData - ((p[0] >> 1) & 0x07U))};
}
Payload download_segment_request(bool toggle, std::span<const std::uint8_t> data, bool last) {
  return segment(u8(ClientCommand::DownloadSegment), toggle, data, last);
}
Payload download_segment_response(bool toggle) {
  return single(static_cast<std::uint8_t>(cs_byte(ServerCommand::DownloadSegment) | (toggle ? 0x10U : 0U)));
}
Payload upload_segment_request(bool toggle) {
  return single(static_cast<std::uint8_t>(cs_byte(ClientCommand::UploadSegment) | (toggle ? 0x10U : 0U)));
}
Payload upload_segment_response(bool toggle, std::span<const std::uint8_t> data, bool last) {
  return segment(u8(ServerCommand::UploadSegment), toggle, data, last);
}

BlockInitiate parse_block_initiate(PayloadView p) {
  BlockInitiate r;
  r.mux = multiplexer(p);
  r.crc = crc_bit(p);
  r.size_indicated = (p[0] & 0x02U) != 0;
  r.size = r.size_indicated ? u32_at(p, 4) : 0;
  return r;
}
Payload block_download_initiate(Multiplexer m, bool crc, std::optional<std::uint32_t> size) {
  return block_initiate(u8(ClientCommand::BlockDownload), m, crc, size);
}
Payload block_upload_initiate_response(Multiplexer m, bool crc, std::optional<std::uint32_t> size) {
  return block_initiate(u8(ServerCommand::BlockUpload), m, crc, size);
}
Payload block_download_initiate_response(Multiplexer m, bool crc, std::uint8_t blksize) {
  Payload p{};
  p[0] = static_cast<std::uint8_t>(cs_byte(ServerCommand::BlockDownload) | (crc ? 0x04U : 0U));
  put_mux(p, m);
  p[4] = blksize;
  return p;
}
Payload block_upload_initiate(Multiplexer m, bool crc, std::uint8_t blksize, std::uint8_t pst) {
  Payload p{};
  p[0] = static_cast<std::uint8_t>(cs_byte(ClientCommand::BlockUpload) | (crc ? 0x04U : 0U));
  put_mux(p, m);
  p[4] = blksize;
  p[5] = pst;
  return p;
}

Payload block_segment(std::uint8_t seqno, std::span<const std::uint8_t> data, bool last) {
  assert(data.size() <= kSegmentData && seqno <= kMaxBlockSize);
  Payload p{};
  p[0] = static_cast<std::uint8_t>((last ? 0x80U : 0U) | seqno);
  put_data(p, 1, data);
  return p;
}

Payload block_download_ack(std::uint8_t ackseq, std::uint8_t blksize) {
  return ack(static_cast<std::uint8_t>(cs_byte(ServerCommand::BlockDownload) |
                                       static_cast<std::uint8_t>(BlockDownloadServerSub::Ack)),
             ackseq, blksize);
}
Payload block_upload_ack(std::uint8_t ackseq, std::uint8_t blksize) {
  return ack(static_cast<std::uint8_t>(cs_byte(ClientCommand::BlockUpload) |
                                       static_cast<std::uint8_t>(BlockUploadClientSub::Ack)),
             ackseq, blksize);
}
std::uint8_t distinct_ack_blksize(std::optional<BlockAck> previous, std::uint8_t ackseq, std::uint8_t blksize,
                                  std::uint8_t max_blksize) {
  if (!previous || ackseq == blksize || previous->ackseq != ackseq || previous->blksize != blksize) return blksize;
  if (max_blksize <= kMinBlockSize) return blksize;  // no other choice
  return blksize == max_blksize ? static_cast<std::uint8_t>(max_blksize - 1) : max_blksize;
}

Payload block_upload_start() {
  return single(static_cast<std::uint8_t>(cs_byte(ClientCommand::BlockUpload) |
                                          static_cast<std::uint8_t>(BlockUploadClientSub::Start)));
}
Payload block_download_end(std::uint8_t unused, std::uint16_t crc) {
  return end(u8(ClientCommand::BlockDownload), unused, crc);
}
Payload block_upload_end(std::uint8_t unused, std::uint16_t crc) {
  return end(u8(ServerCommand::BlockUpload), unused, crc);
}
Payload block_download_end_response() {
  return single(static_cast<std::uint8_t>(cs_byte(ServerCommand::BlockDownload) |
                                          static_cast<std::uint8_t>(BlockDownloadServerSub::End)));
}
Payload block_upload_end_response() {
  return single(static_cast<std::uint8_t>(cs_byte(ClientCommand::BlockUpload) |
                                          static_cast<std::uint8_t>(BlockUploadClientSub::End)));
}

Payload abort_transfer(Multiplexer m, std::uint32_t code) {
  Payload p{};
  p[0] = cs_byte(ClientCommand::Abort);
  put_mux(p, m);
  put_u32(p, 4, code);
  return p;
}

std::uint16_t crc16(std::span<const std::uint8_t> data, std::uint16_t crc) {
  unsigned c = crc;
  for (const std::uint8_t b : data) c = ((c << 8) ^ kCrcTable[((c >> 8) ^ b) & 0xFFU]) & 0xFFFFU;
  return static_cast<std::uint16_t>(c);
}

}  // namespace canopen::sdo
