#include "canopen/sdo/server.hpp"

#include <algorithm>
#include <limits>
#include <utility>

namespace canopen::sdo {

namespace {

constexpr std::size_t kKeepBufferCapacity = std::size_t{64} << 10;

std::uint8_t clamp_block_size(std::uint8_t b) { return std::clamp(b, kMinBlockSize, kMaxBlockSize); }

bool is_initiate(PayloadView p) {
  switch (static_cast<ClientCommand>(command_bits(p))) {
    case ClientCommand::InitiateDownload:
    case ClientCommand::InitiateUpload:
      return true;
    case ClientCommand::BlockDownload:
      return (p[0] & 0x01U) == static_cast<std::uint8_t>(BlockDownloadClientSub::Initiate);
    case ClientCommand::BlockUpload:
      return block_sub_command(p) == static_cast<std::uint8_t>(BlockUploadClientSub::Initiate);
    default:
      return false;
  }
}

bool is_block_upload_ack(PayloadView p) {
  return command_bits(p) == static_cast<std::uint8_t>(ClientCommand::BlockUpload) &&
         block_sub_command(p) == static_cast<std::uint8_t>(BlockUploadClientSub::Ack);
}

}  // namespace

SdoServer::SdoServer(od::ObjectDictionary& dictionary, ServerConfig config, FrameSink sink)
    : od_(dictionary),
      cfg_(config),
      sink_(std::move(sink)),
      rx_id_(config.rx_cob_id != 0 ? config.rx_cob_id : kDefaultRxBase + config.node_id),
      tx_id_(config.tx_cob_id != 0 ? config.tx_cob_id : kDefaultTxBase + config.node_id) {
  cfg_.max_block_size = clamp_block_size(cfg_.max_block_size);
}

void SdoServer::send(const Payload& p) { sink_(make_frame(tx_id_, p)); }

void SdoServer::fail(Multiplexer m, std::error_code code) {
  send(abort_transfer(m, to_abort_code(code)));
  finish();
}

void SdoServer::finish() {
  state_ = State::Idle;
  size_.reset();
  // A 1 MiB domain should not pin its buffer for the server's lifetime.
  if (buf_.capacity() > kKeepBufferCapacity) {
    Bytes().swap(buf_);
  } else {
    buf_.clear();
  }
}

void SdoServer::abort(std::error_code code) {
  if (state_ != State::Idle) fail(mux_, code);
}

void SdoServer::on_time(TimePoint now) {
  if (state_ != State::Idle && now >= deadline_) fail(mux_, SdoAbort::Timeout);
}

bool SdoServer::is_duplicate(PayloadView p) const {
  if (!last_rx_ || !std::equal(p.begin(), p.end(), last_rx_->begin())) return false;
  switch (state_) {
    case State::Idle:
      // A repeated initiate is a new request; a repeated segment or command
      // of a finished transfer is a stale copy.
      return !is_initiate(p);
    case State::BlockUploadSubBlock: {
      if (!is_block_upload_ack(p)) return true;
      // Successive full sub-blocks are acknowledged with equal frames
      // (ackseq == blksize). An equal partial ack, or one that cannot
      // belong to this sub-block, is a late copy.
      const BlockAck a = parse_block_ack(p);
      return a.ackseq != a.blksize || a.ackseq > seq_;
    }
    case State::BlockDownloadSubBlock:
      return blksize_ != 1;  // with blksize 1 every segment has seqno 1
    default:
      return true;
  }
}

bool SdoServer::on_frame(const can::Frame& frame, TimePoint now) {
  if (frame.id != rx_id_ || frame.extended() || frame.remote()) return false;
  if (frame.len != kFrameLength) {
    // Not an SDO frame (they are always 8 bytes): report it rather than guess.
    Multiplexer m = mux_;
    if (state_ == State::Idle) {
      m = frame.len >= 4 ? Multiplexer{static_cast<std::uint16_t>(frame.data[1] | (frame.data[2] << 8)),
                                       frame.data[3]}
                         : Multiplexer{};
    }
    fail(m, SdoAbort::InvalidCommand);
    last_rx_.reset();
    return true;
  }
  const PayloadView p = payload_of(frame);
  if (is_duplicate(p)) return true;
  last_rx_.emplace();
  std::copy(p.begin(), p.end(), last_rx_->begin());
  handle(p);
  if (state_ != State::Idle) deadline_ = now + cfg_.timeout;
  return true;
}

void SdoServer::handle(PayloadView p) {
  if (state_ == State::BlockDownloadSubBlock) {
    // Inside a sub-block byte 0 is c|seqno; 80h (c=1, seqno 0) is the abort.
    if (p[0] == 0x80U) {
      finish();
    } else {
      block_download_segment(p);
    }
    return;
  }
  const auto ccs = static_cast<ClientCommand>(command_bits(p));
  if (state_ == State::BlockDownloadEnd) {
    // Late segments of the last sub-block (a resend that crossed our ack)
    // may still come; their byte 0 can look like any command, so only the
    // end request and an exact abort (80h) count here.
    if (p[0] == 0x80U) {
      finish();
    } else if (ccs == ClientCommand::BlockDownload &&
               (p[0] & 0x01U) == static_cast<std::uint8_t>(BlockDownloadClientSub::End)) {
      block_download_end(p);
    }
    return;
  }
  if (ccs == ClientCommand::Abort) {
    if (state_ != State::Idle) finish();  // an abort is never answered
    return;
  }
  if (handle_initiate(p)) return;

  switch (state_) {
    case State::DownloadSegment:
      if (ccs == ClientCommand::DownloadSegment) return download_segment(p);
      break;
    case State::UploadSegment:
      if (ccs == ClientCommand::UploadSegment) return upload_segment(p);
      break;
    case State::BlockUploadStart:
      if (ccs == ClientCommand::BlockUpload &&
          block_sub_command(p) == static_cast<std::uint8_t>(BlockUploadClientSub::Start)) {
        offset_ = 0;
        send_sub_block();
        state_ = State::BlockUploadSubBlock;
        return;
      }
      break;
    case State::BlockUploadSubBlock:
      if (is_block_upload_ack(p)) return block_upload_ack(p);
      break;
    case State::BlockUploadEnd:
      if (ccs == ClientCommand::BlockUpload) {
        const auto sub = block_sub_command(p);
        if (sub == static_cast<std::uint8_t>(BlockUploadClientSub::End)) return finish();
        // A late acknowledgement of the last sub-block (e.g. a duplicate
        // that overtook the client's) changes nothing.
        if (sub == static_cast<std::uint8_t>(BlockUploadClientSub::Ack)) return;
      }
      break;
    case State::Idle:
    case State::BlockDownloadSubBlock:
    case State::BlockDownloadEnd:
      break;
  }
  fail(state_ == State::Idle ? multiplexer(p) : mux_, SdoAbort::InvalidCommand);
}

bool SdoServer::handle_initiate(PayloadView p) {
  if (!is_initiate(p)) return false;
  // A new initiate ends the transfer in progress (see the header).
  finish();
  mux_ = multiplexer(p);
  switch (static_cast<ClientCommand>(command_bits(p))) {
    case ClientCommand::InitiateDownload: initiate_download(p); break;
    case ClientCommand::InitiateUpload: initiate_upload(mux_); break;
    case ClientCommand::BlockDownload: block_download_initiate(p); break;
    case ClientCommand::BlockUpload: block_upload_initiate(p); break;
    default: break;
  }
  return true;
}

std::error_code SdoServer::check_writable(Multiplexer m, std::optional<std::uint32_t> size) const {
  if (od_.find(m.index) == nullptr) return SdoAbort::NoSuchObject;
  const od::SubEntry* e = od_.find(m.index, m.sub);
  if (e == nullptr) return SdoAbort::NoSuchSubIndex;
  if (!od::writable(e->access)) return SdoAbort::WriteOfReadOnly;
  if (size) {
    if (*size > cfg_.max_download_size) return SdoAbort::OutOfMemory;
    // A fixed-size object tells at once whether the indicated size can fit.
    if (const auto fs = fixed_size(e->type)) {
      if (*size > *fs) return SdoAbort::LengthTooHigh;
      if (*size < *fs) return SdoAbort::LengthTooLow;
    }
  }
  return {};
}

// ---- expedited and segmented download ------------------------------------

void SdoServer::initiate_download(PayloadView p) {
  const Initiate in = parse_initiate(p);
  if (in.expedited) {
    std::size_t n = in.size;
    if (!in.size_indicated) {
      // e=1, s=0: "unspecified number of bytes"; take the object's size when it is fixed.
      if (const od::SubEntry* e = od_.find(mux_.index, mux_.sub)) {
        if (const auto fs = fixed_size(e->type); fs && *fs <= kExpeditedMax) n = *fs;
      }
    }
    if (const auto ec = od_.write(mux_.index, mux_.sub, p.subspan(4, n))) return fail(mux_, ec);
    return send(initiate_download_response(mux_));
  }
  std::optional<std::uint32_t> size;
  if (in.size_indicated) size = in.size;
  if (const auto ec = check_writable(mux_, size)) return fail(mux_, ec);
  size_ = size;
  if (size_) buf_.reserve(*size_);
  toggle_ = false;
  state_ = State::DownloadSegment;
  send(initiate_download_response(mux_));
}

void SdoServer::download_segment(PayloadView p) {
  const Segment s = parse_segment(p);
  if (s.toggle != toggle_) return fail(mux_, SdoAbort::ToggleNotAlternated);
  const std::size_t total = buf_.size() + s.size;
  if (size_ && total > *size_) return fail(mux_, SdoAbort::LengthMismatch);
  if (total > cfg_.max_download_size) return fail(mux_, SdoAbort::OutOfMemory);
  buf_.insert(buf_.end(), p.begin() + 1, p.begin() + 1 + s.size);
  if (s.last) {
    if (size_ && buf_.size() != *size_) return fail(mux_, SdoAbort::LengthMismatch);
    if (const auto ec = od_.write(mux_.index, mux_.sub, buf_)) return fail(mux_, ec);
    finish();
  }
  send(download_segment_response(toggle_));
  toggle_ = !toggle_;
}

// ---- expedited and segmented upload ----------------------------------------

void SdoServer::initiate_upload(Multiplexer m) {
  auto r = od_.read(m.index, m.sub);
  if (!r) return fail(m, r.code());
  buf_ = std::move(r).value();
  start_upload_response();
}

// Answers an upload initiate (or a block upload initiate below the protocol
// switch threshold) with the object's bytes in buf_.
void SdoServer::start_upload_response() {
  if (buf_.size() > std::numeric_limits<std::uint32_t>::max()) return fail(mux_, SdoAbort::OutOfMemory);
  if (!buf_.empty() && buf_.size() <= kExpeditedMax) {
    send(initiate_upload_response_expedited(mux_, buf_));
    return finish();
  }
  // An empty object goes segmented: expedited cannot say "0 bytes".
  send(initiate_upload_response_normal(mux_, static_cast<std::uint32_t>(buf_.size())));
  offset_ = 0;
  toggle_ = false;
  state_ = State::UploadSegment;
}

void SdoServer::upload_segment(PayloadView p) {
  if (toggle_bit(p) != toggle_) return fail(mux_, SdoAbort::ToggleNotAlternated);
  const std::size_t n = std::min(kSegmentData, buf_.size() - offset_);
  const bool last = offset_ + n == buf_.size();
  send(upload_segment_response(toggle_, std::span(buf_).subspan(offset_, n), last));
  offset_ += n;
  toggle_ = !toggle_;
  if (last) finish();
}

// ---- block download ------------------------------------------------------------

void SdoServer::block_download_initiate(PayloadView p) {
  const BlockInitiate in = parse_block_initiate(p);
  std::optional<std::uint32_t> size;
  if (in.size_indicated) size = in.size;
  if (const auto ec = check_writable(mux_, size)) return fail(mux_, ec);
  size_ = size;
  // Segments carry 7 bytes each; the padding of the last is cut at the end.
  if (size_) buf_.reserve(*size_ + kSegmentData);
  crc_ = in.crc && cfg_.crc;
  blksize_ = cfg_.max_block_size;
  seq_ = 0;
  last_ack_.reset();
  ack_trigger_.reset();
  state_ = State::BlockDownloadSubBlock;
  send(block_download_initiate_response(mux_, crc_, blksize_));
}

void SdoServer::block_download_segment(PayloadView p) {
  const BlockSegment s = parse_block_segment(p);
  if (s.seqno == 0 || s.seqno > blksize_) return fail(mux_, SdoAbort::InvalidSequenceNumber);
  if (s.seqno != seq_ + 1) {
    // Out of sequence: a segment was lost (or this one is a stale copy).
    // Drop it; at the end of the sub-block acknowledge the last good one.
    if (s.seqno > seq_ + 1 && (s.last || s.seqno == blksize_) && !is_ack_trigger(p)) {
      send_block_download_ack(p);
      seq_ = 0;
    }
    return;
  }
  const std::size_t total = buf_.size() + kSegmentData;
  if (size_ && total > std::max<std::size_t>(*size_ + kSegmentData - 1, kSegmentData)) {
    return fail(mux_, SdoAbort::LengthMismatch);
  }
  if (!size_ && total > cfg_.max_download_size + kSegmentData) return fail(mux_, SdoAbort::OutOfMemory);
  buf_.insert(buf_.end(), p.begin() + 1, p.end());
  seq_ = s.seqno;
  if (s.last) {
    send_block_download_ack(p);
    state_ = State::BlockDownloadEnd;
  } else if (seq_ == blksize_) {
    send_block_download_ack(p);
    seq_ = 0;
  }
}

// A late copy of the segment that ended the previous sub-block would look
// like the end of a sub-block with segments missing; it must not trigger
// another ack.
// (After an ack of 0 the resent sub-block is numbered as before, so its end
// legitimately equals the old one.)
bool SdoServer::is_ack_trigger(PayloadView p) const {
  return ack_trigger_ && last_ack_ && last_ack_->ackseq > 0 && std::equal(p.begin(), p.end(), ack_trigger_->begin());
}

// Acknowledges seq_ after segment `trigger`; blksize_ becomes the size of
// the next sub-block.
void SdoServer::send_block_download_ack(PayloadView trigger) {
  blksize_ = distinct_ack_blksize(last_ack_, seq_, blksize_, cfg_.max_block_size);
  last_ack_ = BlockAck{seq_, blksize_};
  ack_trigger_.emplace();
  std::copy(trigger.begin(), trigger.end(), ack_trigger_->begin());
  send(block_download_ack(seq_, blksize_));
}

void SdoServer::block_download_end(PayloadView p) {
  const BlockEnd e = parse_block_end(p);
  // The last segment held 7 - n bytes; there is always at least one segment.
  if (e.unused > buf_.size()) return fail(mux_, SdoAbort::LengthMismatch);
  buf_.erase(buf_.end() - e.unused, buf_.end());
  if (size_ && buf_.size() != *size_) return fail(mux_, SdoAbort::LengthMismatch);
  if (!size_ && buf_.size() > cfg_.max_download_size) return fail(mux_, SdoAbort::OutOfMemory);
  if (crc_ && crc16(buf_) != e.crc) return fail(mux_, SdoAbort::CrcError);
  if (const auto ec = od_.write(mux_.index, mux_.sub, buf_)) return fail(mux_, ec);
  finish();
  send(block_download_end_response());
}

// ---- block upload -------------------------------------------------------------------

void SdoServer::block_upload_initiate(PayloadView p) {
  const std::uint8_t blksize = p[4];
  const std::uint8_t pst = p[5];
  if (blksize < kMinBlockSize || blksize > kMaxBlockSize) return fail(mux_, SdoAbort::InvalidBlockSize);
  auto r = od_.read(mux_.index, mux_.sub);
  if (!r) return fail(mux_, r.code());
  buf_ = std::move(r).value();
  if (buf_.size() > std::numeric_limits<std::uint32_t>::max()) return fail(mux_, SdoAbort::OutOfMemory);
  // Protocol switch (7.2.4.3.13): small objects go the normal upload way.
  if (pst > 0 && buf_.size() <= pst) return start_upload_response();
  crc_ = crc_bit(p) && cfg_.crc;
  blksize_ = blksize;
  state_ = State::BlockUploadStart;
  send(block_upload_initiate_response(mux_, crc_, static_cast<std::uint32_t>(buf_.size())));
}

// Sends up to blksize segments from offset_; seq_ = number sent.
void SdoServer::send_sub_block() {
  std::size_t pos = offset_;
  seq_ = 0;
  while (seq_ < blksize_) {
    const std::size_t n = std::min(kSegmentData, buf_.size() - pos);
    const bool last = pos + n == buf_.size();
    ++seq_;
    send(block_segment(seq_, std::span(buf_).subspan(pos, n), last));
    pos += n;
    if (last) break;
  }
}

void SdoServer::block_upload_ack(PayloadView p) {
  const BlockAck a = parse_block_ack(p);
  if (a.ackseq > seq_) return fail(mux_, SdoAbort::InvalidSequenceNumber);
  if (a.blksize < kMinBlockSize || a.blksize > kMaxBlockSize) return fail(mux_, SdoAbort::InvalidBlockSize);
  const std::size_t block_end = offset_ + std::size_t{seq_} * kSegmentData;
  if (a.ackseq == seq_ && block_end >= buf_.size()) {
    // Everything confirmed, the segment with c=1 included.
    const std::size_t in_last = buf_.size() - (offset_ + std::size_t{seq_ - 1U} * kSegmentData);
    send(block_upload_end(static_cast<std::uint8_t>(kSegmentData - in_last), crc_ ? crc16(buf_) : 0));
    state_ = State::BlockUploadEnd;
    return;
  }
  // Go on after the last segment the client confirmed (a resend when ackseq < seq_).
  offset_ += std::size_t{a.ackseq} * kSegmentData;
  blksize_ = a.blksize;
  send_sub_block();
}

}  // namespace canopen::sdo
