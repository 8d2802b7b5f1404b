#include "canopen/sdo/client.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <utility>

namespace canopen::sdo {

namespace {

constexpr std::size_t kNeverReported = std::numeric_limits<std::size_t>::max();

std::string mux_text(Multiplexer m) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04Xh/%02Xh", static_cast<unsigned>(m.index), static_cast<unsigned>(m.sub));
  return buf;
}

std::string byte_text(std::uint8_t b) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%02Xh", static_cast<unsigned>(b));
  return buf;
}

bool is_block_download_ack(PayloadView p) {
  return command_bits(p) == static_cast<std::uint8_t>(ServerCommand::BlockDownload) &&
         block_sub_command(p) == static_cast<std::uint8_t>(BlockDownloadServerSub::Ack);
}

}  // namespace

SdoClient::SdoClient(ClientConfig config, FrameSink sink) : cfg_(config), sink_(std::move(sink)) {
  cfg_.block_size = std::clamp(cfg_.block_size, kMinBlockSize, kMaxBlockSize);
  for (std::uint32_t n = 1; n < nodes_.size(); ++n) {
    nodes_[n].request_id = kDefaultRxBase + n;
    nodes_[n].response_id = kDefaultTxBase + n;
  }
  running_.reserve(nodes_.size());
}

// ---- submission and queueing ------------------------------------------------------

Result<RequestId> SdoClient::upload(Request request, TimePoint now) {
  const Report<SdoClient> deadline_report(*this);  // the driver follows
  Job job;
  job.upload = true;
  job.req = std::move(request);
  return submit(std::move(job), now);
}

Result<RequestId> SdoClient::download(Request request, Bytes data, TimePoint now) {
  const Report<SdoClient> deadline_report(*this);  // the driver follows
  if (request.mode == Mode::Expedited && (data.empty() || data.size() > kExpeditedMax)) {
    return Error{std::make_error_code(std::errc::invalid_argument),
                 "an expedited download carries 1 to 4 bytes, not " + std::to_string(data.size())};
  }
  if (data.size() > std::numeric_limits<std::uint32_t>::max()) {
    return Error{std::make_error_code(std::errc::invalid_argument), "SDO sizes are 32-bit"};
  }
  Job job;
  job.req = std::move(request);
  job.data = std::move(data);
  return submit(std::move(job), now);
}

Result<RequestId> SdoClient::submit(Job job, TimePoint now) {
  const std::uint8_t node = job.req.node;
  if (node == 0 || node >= nodes_.size()) {
    return Error{std::make_error_code(std::errc::invalid_argument),
                 "node-ID " + std::to_string(node) + " is not 1..127"};
  }
  Node& n = nodes_[node];
  if (n.active && n.queue.size() >= cfg_.queue_limit) {
    return Error{make_error_code(SdoAbort::NoSdoConnection),
                 "SDO queue of node " + std::to_string(node) + " is full (" + std::to_string(cfg_.queue_limit) +
                     " waiting)"};
  }
  job.id = next_id_++;
  const RequestId id = job.id;
  n.queue.push_back(std::move(job));
  pump(node, now);
  return id;
}

void SdoClient::pump(std::uint8_t node, TimePoint now) {
  Node& n = nodes_[node];
  if (n.active || n.queue.empty()) return;
  Job job = std::move(n.queue.front());
  n.queue.pop_front();
  start(node, std::move(job), now);
}

Duration SdoClient::timeout_for(std::uint8_t node, const Request& r) const {
  if (r.timeout) return *r.timeout;
  if (nodes_[node].timeout) return *nodes_[node].timeout;
  return cfg_.default_timeout;
}

void SdoClient::start(std::uint8_t node, Job job, TimePoint now) {
  Node& n = nodes_[node];
  // Transfer{} rather than emplace(): clang cannot default-construct a nested
  // class with member initializers from inside its enclosing class.
  Transfer& t = n.active.emplace(Transfer{});
  t.job = std::move(job);
  t.mux = {t.job.req.index, t.job.req.sub};
  t.timeout = timeout_for(node, t.job.req);
  t.deadline = now + t.timeout;
  t.last_progress = kNeverReported;
  running_.push_back(node);
  send_initiate(node, t, now);
}

void SdoClient::send_initiate(std::uint8_t node, Transfer& t, TimePoint now) {
  const Node& n = nodes_[node];
  const Mode mode = t.job.req.mode;
  const bool block_ok = block_allowed(node, now);
  if (t.job.upload) {
    const bool small = t.job.req.expected_size && *t.job.req.expected_size <= cfg_.block_threshold;
    if (mode == Mode::Block || (mode == Mode::Auto && block_ok && !small)) {
      const auto pst = mode == Mode::Block ? std::uint8_t{0}
                                           : static_cast<std::uint8_t>(std::min<std::size_t>(cfg_.block_threshold, 255));
      t.step = Step::BlockUploadInitiate;
      t.blksize = cfg_.block_size;
      send(n, block_upload_initiate(t.mux, cfg_.crc, t.blksize, pst));
    } else {
      t.step = Step::InitiateUpload;
      send(n, initiate_upload_request(t.mux));
    }
    return;
  }
  const std::size_t size = t.job.data.size();
  const auto size32 = static_cast<std::uint32_t>(size);
  if (mode == Mode::Expedited || (mode == Mode::Auto && size >= 1 && size <= kExpeditedMax)) {
    t.step = Step::ExpeditedDownload;
    send(n, initiate_download_expedited(t.mux, t.job.data));
  } else if (mode == Mode::Block || (mode == Mode::Auto && size > cfg_.block_threshold && block_ok)) {
    t.step = Step::BlockDownloadInitiate;
    send(n, block_download_initiate(t.mux, cfg_.crc, size32));
  } else {
    t.step = Step::InitiateDownload;
    send(n, initiate_download_normal(t.mux, size32));
  }
}

void SdoClient::send(const Node& n, const Payload& p) { sink_(make_frame(n.request_id, p)); }

// ---- completion -----------------------------------------------------------------------

void SdoClient::complete(std::uint8_t node, std::error_code ec, Origin origin, std::string detail, TimePoint now,
                         bool cancelled) {
  Node& n = nodes_[node];
  // Move everything out first: the handler may submit or cancel re-entrantly.
  Transfer t = std::move(*n.active);
  n.active.reset();
  std::erase(running_, node);
  TransferResult r;
  r.id = t.job.id;
  r.node = node;
  r.mux = t.mux;
  r.upload = t.job.upload;
  r.error = ec;
  r.origin = origin;
  r.cancelled = cancelled;
  r.detail = std::move(detail);
  if (!ec && t.job.req.on_progress) {
    // Success always ends with a report of the full size.
    const std::size_t done = t.job.upload ? t.data.size() : t.job.data.size();
    if (t.last_progress != done) t.job.req.on_progress(done, done);
  }
  if (t.job.upload && !ec) r.data = std::move(t.data);
  if (!ec && !t.job.upload && download_observer_) download_observer_(node, t.mux, t.job.data);
  if (t.job.req.on_done) t.job.req.on_done(std::move(r));
  pump(node, now);
}

void SdoClient::fail_local(std::uint8_t node, std::error_code ec, std::string detail, TimePoint now) {
  Node& n = nodes_[node];
  send(n, abort_transfer(n.active->mux, to_abort_code(ec)));
  complete(node, ec, Origin::Local, std::move(detail), now);
}

bool SdoClient::cancel(RequestId id, TimePoint now) {
  const Report<SdoClient> deadline_report(*this);  // the driver follows
  for (std::size_t i = 1; i < nodes_.size(); ++i) {
    const auto node = static_cast<std::uint8_t>(i);
    Node& n = nodes_[node];
    if (n.active && n.active->job.id == id) {
      send(n, abort_transfer(n.active->mux, to_abort_code(SdoAbort::GeneralError)));
      complete(node, SdoAbort::GeneralError, Origin::Local, "cancelled", now, true);
      return true;
    }
    const auto it = std::find_if(n.queue.begin(), n.queue.end(), [id](const Job& j) { return j.id == id; });
    if (it != n.queue.end()) {
      Job job = std::move(*it);
      n.queue.erase(it);
      TransferResult r;
      r.id = id;
      r.node = node;
      r.mux = {job.req.index, job.req.sub};
      r.upload = job.upload;
      r.error = SdoAbort::GeneralError;
      r.origin = Origin::Local;
      r.cancelled = true;
      r.detail = "cancelled before it started";
      if (job.req.on_done) job.req.on_done(std::move(r));
      return true;
    }
  }
  return false;
}

// ---- time -----------------------------------------------------------------------------------

TimePoint SdoClient::next_deadline() const {
  TimePoint t = TimePoint::max();
  for (const std::uint8_t node : running_) t = std::min(t, nodes_[node].active->deadline);
  return t;
}

void SdoClient::on_time(TimePoint now) {
  // Collect first: completing a transfer changes running_.
  std::array<std::uint8_t, 128> due{};
  std::size_t count = 0;
  for (const std::uint8_t node : running_) {
    if (nodes_[node].active->deadline <= now) due[count++] = node;
  }
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint8_t node = due[i];
    const Node& n = nodes_[node];
    if (!n.active || n.active->deadline > now) continue;
    const Transfer& t = *n.active;
    if (t.stray_refusal && t.job.req.mode == Mode::Auto) {
      // A 05040001h with a stale multiplexer and no answer since: the server
      // refused the block initiate (see the header). Abort in case it is
      // only slow, then go the normal way.
      send(n, abort_transfer(t.mux, to_abort_code(SdoAbort::Timeout)));
      refuse_block(node, now);
      continue;
    }
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(t.timeout).count();
    std::string detail = "no response from node " + std::to_string(node) + " within " + std::to_string(ms) + " ms";
    if (t.stray_refusal) {
      detail += "; it sent abort 05040001h for " + mux_text(*t.stray_refusal) +
                " instead, maybe a refusal of block transfer";
    }
    fail_local(node, SdoAbort::Timeout, std::move(detail), now);
  }
}

// ---- settings ------------------------------------------------------------------------------

void SdoClient::set_node_timeout(std::uint8_t node, Duration timeout) {
  if (node > 0 && node < nodes_.size()) nodes_[node].timeout = timeout;
}

void SdoClient::set_node_cob_ids(std::uint8_t node, std::uint32_t request_id, std::uint32_t response_id) {
  if (node == 0 || node >= nodes_.size()) return;
  nodes_[node].request_id = request_id;
  nodes_[node].response_id = response_id;
}

void SdoClient::forget_block_support(std::uint8_t node) {
  if (node > 0 && node < nodes_.size()) nodes_[node].no_block_until = TimePoint{};
}

bool SdoClient::block_allowed(std::uint8_t node, TimePoint now) const {
  return node > 0 && node < nodes_.size() && now >= nodes_[node].no_block_until;
}

// Remembers the refusal and restarts the running request the normal way.
void SdoClient::refuse_block(std::uint8_t node, TimePoint now) {
  Node& n = nodes_[node];
  const Duration wait = std::max(cfg_.block_retry_interval, Duration::zero());
  n.no_block_until = now < TimePoint::max() - wait ? now + wait : TimePoint::max();
  Job job = std::move(n.active->job);
  n.active.reset();
  std::erase(running_, node);
  start(node, std::move(job), now);
}

std::size_t SdoClient::pending(std::uint8_t node) const {
  if (node == 0 || node >= nodes_.size()) return 0;
  return nodes_[node].queue.size() + (nodes_[node].active ? 1U : 0U);
}

bool SdoClient::busy(std::uint8_t node) const { return node > 0 && node < nodes_.size() && nodes_[node].active; }

// ---- received frames ---------------------------------------------------------------------------

bool SdoClient::on_frame(const can::Frame& frame, TimePoint now) {
  if (frame.remote() || frame.extended()) return false;
  std::uint8_t node = 0;
  for (const std::uint8_t r : running_) {
    if (nodes_[r].response_id == frame.id) {
      node = r;
      break;
    }
  }
  if (node == 0) return false;
  Node& n = nodes_[node];
  if (frame.len != kFrameLength) {
    fail_local(node, SdoAbort::InvalidCommand,
               "response of " + std::to_string(frame.len) + " bytes; SDO frames have 8", now);
    return true;
  }
  const PayloadView p = payload_of(frame);
  Transfer& t = *n.active;
  if (is_abort(t, p) && multiplexer(p) != t.mux) {
    // Not this transfer's abort: it neither ends nor advances it.
    stray_abort(t, p);
    return true;
  }
  if (is_duplicate(t, p)) return true;
  t.last_rx.emplace();
  std::copy(p.begin(), p.end(), t.last_rx->begin());
  const RequestId id = t.job.id;
  handle(node, p, now);
  // The transfer may have completed (and the next one started) meanwhile.
  if (!n.active || n.active->job.id != id) return true;
  Transfer& still = *n.active;
  still.deadline = now + still.timeout;
  still.stray_refusal.reset();  // the server answered: the stray abort was no refusal
  if (still.progress_due) {
    // Copy: the handler may cancel this very transfer and destroy the original.
    const ProgressHandler h = still.job.req.on_progress;
    const auto [done, total] = *still.progress_due;
    still.progress_due.reset();
    h(done, total);
  }
  return true;
}

bool SdoClient::is_abort(const Transfer& t, PayloadView p) const {
  // Where block upload segments flow, byte 0 is c|seqno and only 80h (c=1,
  // seqno 0, not a valid segment) is an abort.
  if (t.step == Step::BlockUploadSubBlock || t.step == Step::BlockUploadEnd) return p[0] == 0x80U;
  return command_bits(p) == static_cast<std::uint8_t>(ServerCommand::Abort);
}

void SdoClient::stray_abort(Transfer& t, PayloadView p) {
  ++stray_aborts_;
  const bool initiating = t.step == Step::BlockUploadInitiate || t.step == Step::BlockDownloadInitiate;
  if (initiating && abort_code(p) == static_cast<std::uint32_t>(SdoAbort::InvalidCommand)) {
    t.stray_refusal = multiplexer(p);
  }
}

bool SdoClient::is_duplicate(const Transfer& t, PayloadView p) const {
  if (!t.last_rx || !std::equal(p.begin(), p.end(), t.last_rx->begin())) return false;
  // Equal consecutive frames the protocol allows: acks of successive full
  // sub-blocks (ackseq == blksize), and block segments when every one has
  // seqno 1. An equal partial ack, or one that cannot belong to this
  // sub-block, is a late copy.
  if (t.step == Step::BlockDownloadSubBlock && is_block_download_ack(p)) {
    const BlockAck a = parse_block_ack(p);
    return a.ackseq != a.blksize || a.ackseq > t.seq;
  }
  if (t.step == Step::BlockUploadSubBlock && t.blksize == 1) return false;
  return true;
}

void SdoClient::progress(Transfer& t, std::size_t done, std::optional<std::size_t> total) {
  if (!t.job.req.on_progress) return;
  const bool final = total && done == *total;
  const bool due = t.last_progress == kNeverReported
                       ? (done >= cfg_.progress_step || final)
                       : (done >= t.last_progress + cfg_.progress_step || (final && done != t.last_progress));
  if (!due) return;
  t.last_progress = done;
  t.progress_due.emplace(done, total);
}

bool SdoClient::check_mux(std::uint8_t node, PayloadView p, TimePoint now) {
  const Transfer& t = *nodes_[node].active;
  const Multiplexer m = multiplexer(p);
  if (m == t.mux) return true;
  fail_local(node, SdoAbort::ParameterIncompatible,
             "node " + std::to_string(node) + " answered for " + mux_text(m) + " instead of " + mux_text(t.mux),
             now);
  return false;
}

void SdoClient::handle(std::uint8_t node, PayloadView p, TimePoint now) {
  Node& n = nodes_[node];
  Transfer& t = *n.active;
  const auto scs = static_cast<ServerCommand>(command_bits(p));
  if (is_abort(t, p)) return remote_abort(node, p, now);
  if (t.step == Step::BlockUploadSubBlock || t.step == Step::BlockUploadEnd) {
    if (t.step == Step::BlockUploadSubBlock) return on_block_upload_segment(node, p, now);
    if (scs == ServerCommand::BlockUpload && (p[0] & 0x01U) != 0) return on_block_upload_end(node, p, now);
    // Anything else after the last segment is a late resend that crossed
    // our acknowledgement: the data is complete, so it is ignored.
    return;
  }
  const std::uint8_t sub = block_sub_command(p);
  switch (t.step) {
    case Step::ExpeditedDownload:
      if (scs != ServerCommand::InitiateDownload) break;
      if (check_mux(node, p, now)) complete(node, {}, Origin::None, {}, now);
      return;
    case Step::InitiateDownload:
      if (scs != ServerCommand::InitiateDownload) break;
      if (!check_mux(node, p, now)) return;
      t.toggle = false;
      t.step = Step::DownloadSegment;
      return send_download_segment(node, t);
    case Step::DownloadSegment:
      if (scs == ServerCommand::DownloadSegment) return on_download_segment_response(node, p, now);
      break;
    case Step::InitiateUpload:
      if (scs == ServerCommand::InitiateUpload) return on_upload_initiate_response(node, p, now);
      break;
    case Step::UploadSegment:
      if (scs == ServerCommand::UploadSegment) return on_upload_segment(node, p, now);
      break;
    case Step::BlockDownloadInitiate:
      if (scs != ServerCommand::BlockDownload || sub != static_cast<std::uint8_t>(BlockDownloadServerSub::Initiate)) {
        break;
      }
      if (!check_mux(node, p, now)) return;
      if (p[4] < kMinBlockSize || p[4] > kMaxBlockSize) {
        return fail_local(node, SdoAbort::InvalidBlockSize, "server blksize " + std::to_string(p[4]), now);
      }
      t.blksize = p[4];
      t.crc = cfg_.crc && crc_bit(p);
      t.offset = 0;
      t.step = Step::BlockDownloadSubBlock;
      return send_sub_block(node, t);
    case Step::BlockDownloadSubBlock:
      if (is_block_download_ack(p)) return on_block_download_ack(node, p, now);
      break;
    case Step::BlockDownloadEnd:
      if (scs != ServerCommand::BlockDownload) break;
      if (sub == static_cast<std::uint8_t>(BlockDownloadServerSub::End)) return complete(node, {}, Origin::None, {}, now);
      // A late copy of the last acknowledgement changes nothing.
      if (sub == static_cast<std::uint8_t>(BlockDownloadServerSub::Ack)) return;
      break;
    case Step::BlockUploadInitiate:
      if (scs == ServerCommand::BlockUpload && (p[0] & 0x01U) == 0) {
        return on_block_upload_initiate_response(node, p, now);
      }
      // Protocol switch: the object is at most pst bytes.
      if (scs == ServerCommand::InitiateUpload) return on_upload_initiate_response(node, p, now);
      break;
    case Step::BlockUploadSubBlock:
    case Step::BlockUploadEnd:
      break;  // handled above
  }
  fail_local(node, SdoAbort::InvalidCommand, "unexpected response " + byte_text(p[0]) + " from node " +
                                                 std::to_string(node) + " for " + mux_text(t.mux),
             now);
}

// An abort for the transfer's own multiplexer (stray ones never get here).
void SdoClient::remote_abort(std::uint8_t node, PayloadView p, TimePoint now) {
  const Transfer& t = *nodes_[node].active;
  const std::uint32_t code = abort_code(p);
  if (code == static_cast<std::uint32_t>(SdoAbort::InvalidCommand) && t.job.req.mode == Mode::Auto &&
      (t.step == Step::BlockDownloadInitiate || t.step == Step::BlockUploadInitiate)) {
    // The server has no block transfer: remember, and redo it the normal way.
    return refuse_block(node, now);
  }
  if (code == 0) {
    // Not a valid abort code; it must still not read as success.
    complete(node, SdoAbort::GeneralError, Origin::Remote, "abort frame with code 0", now);
    return;
  }
  complete(node, {static_cast<int>(code), sdo_abort_category()}, Origin::Remote, {}, now);
}

// ---- segmented download -------------------------------------------------------------------

void SdoClient::send_download_segment(std::uint8_t node, Transfer& t) {
  const Bytes& data = t.job.data;
  const std::size_t n = std::min(kSegmentData, data.size() - t.offset);
  const bool last = t.offset + n == data.size();
  send(nodes_[node], download_segment_request(t.toggle, std::span(data).subspan(t.offset, n), last));
  t.offset += n;
}

void SdoClient::on_download_segment_response(std::uint8_t node, PayloadView p, TimePoint now) {
  Transfer& t = *nodes_[node].active;
  if (toggle_bit(p) != t.toggle) {
    return fail_local(node, SdoAbort::ToggleNotAlternated, "download segment response with the wrong toggle bit",
                      now);
  }
  const std::size_t size = t.job.data.size();
  progress(t, t.offset, size);
  if (t.offset == size) return complete(node, {}, Origin::None, {}, now);
  t.toggle = !t.toggle;
  send_download_segment(node, t);
}

// ---- expedited and segmented upload ------------------------------------------------------------

void SdoClient::on_upload_initiate_response(std::uint8_t node, PayloadView p, TimePoint now) {
  if (!check_mux(node, p, now)) return;
  Transfer& t = *nodes_[node].active;
  const Initiate in = parse_initiate(p);
  if (in.expedited) {
    t.data.assign(p.begin() + 4, p.begin() + 4 + in.size);
    return complete(node, {}, Origin::None, {}, now);
  }
  if (in.size_indicated) {
    if (in.size > cfg_.max_upload_size) {
      return fail_local(node, SdoAbort::OutOfMemory, "upload of " + std::to_string(in.size) + " bytes", now);
    }
    t.size = in.size;
    t.data.reserve(in.size);
  }
  t.toggle = false;
  t.step = Step::UploadSegment;
  send(nodes_[node], upload_segment_request(false));
}

void SdoClient::on_upload_segment(std::uint8_t node, PayloadView p, TimePoint now) {
  Transfer& t = *nodes_[node].active;
  const Segment s = parse_segment(p);
  if (s.toggle != t.toggle) {
    return fail_local(node, SdoAbort::ToggleNotAlternated, "upload segment with the wrong toggle bit", now);
  }
  const std::size_t total = t.data.size() + s.size;
  if (t.size && total > *t.size) {
    return fail_local(node, SdoAbort::LengthMismatch,
                      "server sent more than the " + std::to_string(*t.size) + " bytes it indicated", now);
  }
  if (total > cfg_.max_upload_size) return fail_local(node, SdoAbort::OutOfMemory, "upload too large", now);
  t.data.insert(t.data.end(), p.begin() + 1, p.begin() + 1 + s.size);
  if (s.last) {
    if (t.size && t.data.size() != *t.size) {
      return fail_local(node, SdoAbort::LengthMismatch,
                        "server sent " + std::to_string(t.data.size()) + " of the " + std::to_string(*t.size) +
                            " bytes it indicated",
                        now);
    }
    return complete(node, {}, Origin::None, {}, now);
  }
  progress(t, t.data.size(), t.size);
  t.toggle = !t.toggle;
  send(nodes_[node], upload_segment_request(t.toggle));
}

// ---- block download -------------------------------------------------------------------------------

// Sends up to blksize segments from the confirmed offset; t.seq = number sent.
void SdoClient::send_sub_block(std::uint8_t node, Transfer& t) {
  const Node& n = nodes_[node];
  const Bytes& data = t.job.data;
  std::size_t pos = t.offset;
  t.seq = 0;
  while (t.seq < t.blksize) {
    const std::size_t len = std::min(kSegmentData, data.size() - pos);
    const bool last = pos + len == data.size();
    ++t.seq;
    send(n, block_segment(t.seq, std::span(data).subspan(pos, len), last));
    pos += len;
    if (last) break;
  }
}

void SdoClient::on_block_download_ack(std::uint8_t node, PayloadView p, TimePoint now) {
  Transfer& t = *nodes_[node].active;
  const BlockAck a = parse_block_ack(p);
  if (a.ackseq > t.seq) {
    return fail_local(node, SdoAbort::InvalidSequenceNumber,
                      "ackseq " + std::to_string(a.ackseq) + " but " + std::to_string(t.seq) + " segments sent", now);
  }
  if (a.blksize < kMinBlockSize || a.blksize > kMaxBlockSize) {
    return fail_local(node, SdoAbort::InvalidBlockSize, "server blksize " + std::to_string(a.blksize), now);
  }
  const Bytes& data = t.job.data;
  if (a.ackseq == t.seq && t.offset + std::size_t{t.seq} * kSegmentData >= data.size()) {
    // Everything confirmed, the segment with c=1 included.
    const std::size_t in_last = data.size() - (t.offset + std::size_t{t.seq - 1U} * kSegmentData);
    progress(t, data.size(), data.size());
    t.step = Step::BlockDownloadEnd;
    send(nodes_[node], block_download_end(static_cast<std::uint8_t>(kSegmentData - in_last), t.crc ? crc16(data) : 0));
    return;
  }
  // Go on after the last segment the server confirmed (a resend when ackseq < seq).
  t.offset += std::size_t{a.ackseq} * kSegmentData;
  t.blksize = a.blksize;
  progress(t, t.offset, data.size());
  send_sub_block(node, t);
}

// ---- block upload ------------------------------------------------------------------------------------

void SdoClient::on_block_upload_initiate_response(std::uint8_t node, PayloadView p, TimePoint now) {
  if (!check_mux(node, p, now)) return;
  Transfer& t = *nodes_[node].active;
  const BlockInitiate in = parse_block_initiate(p);
  if (in.size_indicated) {
    if (in.size > cfg_.max_upload_size) {
      return fail_local(node, SdoAbort::OutOfMemory, "upload of " + std::to_string(in.size) + " bytes", now);
    }
    t.size = in.size;
    t.data.reserve(std::size_t{in.size} + kSegmentData);
  }
  t.crc = cfg_.crc && in.crc;
  t.seq = 0;
  t.step = Step::BlockUploadSubBlock;
  send(nodes_[node], block_upload_start());
}

void SdoClient::on_block_upload_segment(std::uint8_t node, PayloadView p, TimePoint now) {
  Transfer& t = *nodes_[node].active;
  const BlockSegment s = parse_block_segment(p);
  if (s.seqno == 0 || s.seqno > t.blksize) {
    return fail_local(node, SdoAbort::InvalidSequenceNumber,
                      "segment seqno " + std::to_string(s.seqno) + " with blksize " + std::to_string(t.blksize), now);
  }
  if (s.seqno != t.seq + 1) {
    // Out of sequence: a segment was lost (or this is a stale copy). Drop
    // it; at the end of the sub-block acknowledge the last good one so the
    // server resends the rest.
    // A late copy of the segment that ended the previous sub-block must not
    // trigger another ack. (After an ack of 0 the resent sub-block is
    // numbered as before, so its end legitimately equals the old one.)
    const bool trigger_copy = t.ack_trigger && t.last_ack && t.last_ack->ackseq > 0 &&
                              std::equal(p.begin(), p.end(), t.ack_trigger->begin());
    if (s.seqno > t.seq + 1 && (s.last || s.seqno == t.blksize) && !trigger_copy) {
      send_block_upload_ack(node, t, p);
      t.seq = 0;
    }
    return;
  }
  const std::size_t total = t.data.size() + kSegmentData;
  if (t.size && total > std::max<std::size_t>(std::size_t{*t.size} + kSegmentData - 1, kSegmentData)) {
    return fail_local(node, SdoAbort::LengthMismatch,
                      "server sent more than the " + std::to_string(*t.size) + " bytes it indicated", now);
  }
  if (!t.size && total > cfg_.max_upload_size + kSegmentData) {
    return fail_local(node, SdoAbort::OutOfMemory, "upload too large", now);
  }
  t.data.insert(t.data.end(), p.begin() + 1, p.end());
  t.seq = s.seqno;
  if (s.last) {
    send_block_upload_ack(node, t, p);
    t.step = Step::BlockUploadEnd;
  } else if (t.seq == t.blksize) {
    send_block_upload_ack(node, t, p);
    t.seq = 0;
    progress(t, t.data.size(), t.size);
  }
}

// Acknowledges t.seq after segment `trigger`; t.blksize becomes the size of
// the next sub-block.
void SdoClient::send_block_upload_ack(std::uint8_t node, Transfer& t, PayloadView trigger) {
  t.blksize = distinct_ack_blksize(t.last_ack, t.seq, t.blksize, cfg_.block_size);
  t.last_ack = BlockAck{t.seq, t.blksize};
  t.ack_trigger.emplace();
  std::copy(trigger.begin(), trigger.end(), t.ack_trigger->begin());
  send(nodes_[node], block_upload_ack(t.seq, t.blksize));
}

void SdoClient::on_block_upload_end(std::uint8_t node, PayloadView p, TimePoint now) {
  Transfer& t = *nodes_[node].active;
  const BlockEnd e = parse_block_end(p);
  // The segment with c=1 was received, so at least 7 bytes are there.
  if (e.unused > t.data.size()) return fail_local(node, SdoAbort::LengthMismatch, "block end n too large", now);
  t.data.erase(t.data.end() - e.unused, t.data.end());
  if (t.size && t.data.size() != *t.size) {
    return fail_local(node, SdoAbort::LengthMismatch,
                      "server sent " + std::to_string(t.data.size()) + " of the " + std::to_string(*t.size) +
                          " bytes it indicated",
                      now);
  }
  if (!t.size && t.data.size() > cfg_.max_upload_size) {
    return fail_local(node, SdoAbort::OutOfMemory, "upload too large", now);
  }
  if (t.crc && crc16(t.data) != e.crc) return fail_local(node, SdoAbort::CrcError, "block upload CRC mismatch", now);
  send(nodes_[node], block_upload_end_response());
  complete(node, {}, Origin::None, {}, now);
}

}  // namespace canopen::sdo
