#include "mqtt/disk_queue.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>
#include <vector>

#include "mqtt/disk_queue_format.hpp"

// Opening (the constructor, the position file's read, replay) is in
// disk_queue_replay.cpp; the file format in disk_queue_format.hpp.
namespace gateway::mqtt {

using namespace disk_format;

DiskQueue::~DiskQueue() {
  sync();  // flushes first
  for (auto& [first, seg] : segments_) ::close(seg.fd);
  if (head_fd_ >= 0) ::close(head_fd_);
}

void DiskQueue::write_head() {
  if (opts_.buffered_writes) {
    head_unwritten_ = true;  // flush(true) or sync() writes it
    return;
  }
  (void)persist_head();
}

bool DiskQueue::persist_head() {
  head_unwritten_ = true;
  if (head_fd_ < 0) {
    head_fd_ = ::open((opts_.dir / "acked").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (head_fd_ < 0) {
      failed(errno);
      return false;
    }
  }
  // Alternate slots so a torn write leaves the other, older slot valid; a
  // failed write is retried in the same slot (the other one stays valid).
  const std::uint64_t gen = head_generation_ + 1;
  char s[kSlot] = {};
  put_le(s, gen, 8);
  put_le(s + 8, head_, 8);
  put_le(s + 16, crc32(s, 16), 4);
  if (!pwrite_all(head_fd_, s, kSlot, (gen % 2) * kSlot)) {
    failed(errno);
    return false;
  }
  head_generation_ = gen;
  head_unwritten_ = false;
  counters_.storage_bytes += kSlot;
  return true;
}

// The segment the next record (seq next_seq_) goes to; nullptr when it
// cannot be created.
DiskQueue::Segment* DiskQueue::writable_segment(std::uint64_t need) {
  if (!segments_.empty()) {
    auto& last = segments_.rbegin()->second;
    if (last.size == 0 || last.size + need <= opts_.segment_bytes) return &last;
    if (!flush_segment(last)) return nullptr;  // its buffer goes first
  }
  // A fully acked last segment goes before new space is taken.
  delete_consumed_segments(true);
  auto path = opts_.dir / segment_name(next_seq_);
  int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0 && errno == EISDIR) {
    // A stray directory has the name (ignored at open): skip that number.
    entries_.push_back(Entry{next_seq_, 0, 0, 0, State::Dropped, false});
    ++next_seq_;
    advance_head();
    path = opts_.dir / segment_name(next_seq_);
    fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  }
  if (fd < 0) {
    failed(errno);
    append_failed_ = true;
    return nullptr;
  }
  Segment& seg = segments_[next_seq_];
  seg.fd = fd;
  tail_.clear();
  tail_base_ = 0;
  delete_consumed_segments(false);  // the previous one may be fully acked already
  return &seg;
}

std::uint64_t DiskQueue::refuse() {
  ++counters_.dropped_full;
  return 0;
}

std::uint64_t DiskQueue::push(const QueuedMessage& m, bool durable) {
  return push(m.topic, m.payload, m.qos, m.retained, durable);
}

std::uint64_t DiskQueue::push(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained,
                              bool durable) {
  const std::size_t tlen = std::min<std::size_t>(topic.size(), 0xffff);
  const std::size_t body = kBodyFixed + tlen + payload.size();
  const std::uint64_t size = kHeader + body;
  if (size > opts_.max_bytes || body > kMaxBody) {
    ++counters_.dropped_too_big;
    return 0;
  }
  enforce_bounds(size);

  Segment* seg = writable_segment(size);
  if (seg == nullptr && free_space()) seg = writable_segment(size);
  if (seg == nullptr) return refuse();
  if (opts_.buffered_writes && seg->size - seg->written + size > opts_.write_buffer_bytes) {
    // The buffer is full: write it out. Not while appends fail (flush()
    // retries), so a full disk costs no write() per message.
    if (append_failed_ || !flush_segment(*seg)) {
      if (free_space() && (seg = writable_segment(size)) == nullptr) return refuse();
      if (seg->size - seg->written + size > opts_.write_buffer_bytes) return refuse();
    }
  }
  // The tail cache keeps at most about one segment; past that (a segment
  // larger than the cap, or a huge record) it starts again after a flush.
  const std::uint64_t cap = std::max<std::uint64_t>(opts_.segment_bytes, 1u << 20) + (1u << 16);
  if (tail_.size() + size > cap) {
    if (!flush_segment(*seg)) return refuse();
    tail_.clear();
    tail_base_ = seg->size;
  }
  const std::uint64_t seq = next_seq_;
  const std::size_t at = tail_.size();
  tail_.resize(at + size);
  char* p = tail_.data() + at;
  put_le(p, body, 4);
  char* b = p + kHeader;
  put_le(b, seq, 8);
  b[8] = static_cast<char>(qos == 0 ? 0 : 1);
  b[9] = static_cast<char>(retained ? 1 : 0);
  put_le(b + 10, tlen, 2);
  std::memcpy(b + kBodyFixed, topic.data(), tlen);
  if (!payload.empty()) std::memcpy(b + kBodyFixed + tlen, payload.data(), payload.size());
  put_le(p + 4, crc32(b, body), 4);

  if (!opts_.buffered_writes) {
    if (!pwrite_all(seg->fd, p, size, seg->size)) {
      const int e = errno;
      (void)::ftruncate(seg->fd, static_cast<off_t>(seg->size));  // no half record stays
      tail_.resize(at);
      failed(e);
      append_failed_ = true;
      (void)free_space();  // for the next push
      return refuse();
    }
    seg->written = seg->size + size;
    counters_.storage_bytes += size;
    append_failed_ = false;
  }
  entries_.push_back(Entry{segments_.rbegin()->first, seg->size, static_cast<std::uint32_t>(size),
                           static_cast<std::uint8_t>(qos == 0 ? 0 : 1), State::Live, durable});
  (qos == 0 ? live_qos0_ : live_qos1_).push_back(seq);
  seg->size += size;
  if (durable) seg->unsynced = true;
  counters_.disk_bytes += size;
  ++next_seq_;
  ++live_;
  live_bytes_ += size;
  ++counters_.written;
  counters_.depth = live_;
  counters_.bytes = live_bytes_;
  if (storage_error_ && !opts_.buffered_writes) update_error_state();
  return seq;
}

DiskQueue::Entry* DiskQueue::entry(std::uint64_t seq) {
  if (seq < head_ || seq >= next_seq_) return nullptr;
  return &entries_[static_cast<std::size_t>(seq - head_)];
}

bool DiskQueue::oldest_live(std::deque<std::uint64_t>& fifo, std::uint64_t& seq) {
  while (!fifo.empty()) {
    Entry* e = entry(fifo.front());
    if (e != nullptr && e->state == State::Live) {
      seq = fifo.front();
      return true;
    }
    fifo.pop_front();
  }
  return false;
}

void DiskQueue::drop(std::uint64_t seq, std::uint64_t& reason) {
  Entry* e = entry(seq);
  if (e == nullptr || e->state != State::Live) return;
  e->state = State::Dropped;
  --live_;
  live_bytes_ -= e->size;
  ++reason;
}

void DiskQueue::enforce_bounds(std::uint64_t incoming) {
  const std::uint64_t n_in = incoming > 0 ? 1 : 0;
  std::uint64_t seq = 0;
  while (live_ + n_in > opts_.max_messages || live_bytes_ + incoming > opts_.max_bytes) {
    if (oldest_live(live_qos0_, seq)) {
      drop(seq, counters_.dropped_qos0);
    } else if (oldest_live(live_qos1_, seq)) {
      drop(seq, counters_.dropped_qos1);
    } else {
      break;
    }
  }
  advance_head();
  // Disk span bound: drop from the head whatever the QoS.
  const std::uint64_t span_limit = 2 * opts_.max_bytes + opts_.segment_bytes;
  while (counters_.disk_bytes + incoming > span_limit && live_ > 0) {
    std::uint64_t before = head_;
    for (std::uint64_t s = head_; s < next_seq_; ++s) {
      if (entry(s)->state == State::Live) {
        drop(s, counters_.dropped_span);
        break;
      }
    }
    advance_head();
    if (head_ == before && segments_.size() <= 1) break;
  }
  counters_.depth = live_;
  counters_.bytes = live_bytes_;
}

void DiskQueue::advance_head() {
  const std::uint64_t old = head_;
  while (!entries_.empty() && entries_.front().state != State::Live) {
    if (entries_.front().durable) head_sync_needed_ = true;
    entries_.pop_front();
    ++head_;
  }
  if (cursor_ < head_) cursor_ = head_;
  if (head_ == old) return;
  write_head();
  delete_consumed_segments(false);
}

// Segments wholly below the head go; the last one (appended to) only with
// including_last and when everything pushed is acked or dropped (its
// unwritten buffer goes with it). Deleting before the position is written
// is safe: replay fills the missing prefix with dropped entries, and every
// record in a deleted file was acked or dropped. So the position write is
// tried first (fewer repeats after a crash) but its failure stops nothing.
void DiskQueue::delete_consumed_segments(bool including_last) {
  while (!segments_.empty()) {
    auto it = segments_.begin();
    auto nx = std::next(it);
    const bool consumed = nx != segments_.end() ? nx->first <= head_ : including_last && head_ == next_seq_;
    if (!consumed) break;
    if (head_unwritten_) (void)persist_head();
    delete_segment(it);
  }
}

void DiskQueue::delete_segment(std::map<std::uint64_t, Segment>::iterator it) {
  if (rd_valid_ && rd_segment_ == it->first) rd_valid_ = false;
  if (std::next(it) == segments_.end()) {
    tail_.clear();
    tail_base_ = 0;
  }
  ::close(it->second.fd);
  counters_.disk_bytes -= it->second.size;
  ::unlink((opts_.dir / segment_name(it->first)).c_str());
  segments_.erase(it);
}

// After a failed write: frees what can be freed (see the header). True if
// a file went.
bool DiskQueue::free_space() {
  const auto before = segments_.size();
  delete_consumed_segments(true);
  return segments_.size() < before;
}

void DiskQueue::failed(int err) {
  ++counters_.write_errors;
  if (!storage_error_) storage_error_ = std::error_code(err != 0 ? err : EIO, std::generic_category());
}

// Cleared only after records were written again (append_failed_ false), so
// a disk that is still full does not end its episode just because nothing
// was pending for a moment.
void DiskQueue::update_error_state() {
  if (storage_error_ && !append_failed_ && !flush_pending() && !head_unwritten_) storage_error_.clear();
}

bool DiskQueue::next(Item& out) {
  while (cursor_ < next_seq_) {
    const std::uint64_t seq = cursor_++;
    Entry* e = entry(seq);
    if (e == nullptr || e->state != State::Live) continue;
    const char* rec = record(*e);
    if (rec == nullptr) {
      // Unreadable (a read error): skip it rather than stop the queue.
      drop(seq, counters_.corrupt_records);
      advance_head();
      counters_.depth = live_;
      counters_.bytes = live_bytes_;
      continue;
    }
    const char* b = rec + kHeader;
    const std::size_t body = e->size - kHeader;
    const auto tlen = static_cast<std::size_t>(get_le(b + 10, 2));
    out.seq = seq;
    out.msg.qos = static_cast<std::uint8_t>(b[8]);
    out.msg.retained = b[9] != 0;
    out.msg.topic.assign(b + kBodyFixed, tlen);
    out.msg.payload.assign(b + kBodyFixed + tlen, body - kBodyFixed - tlen);
    return true;
  }
  return false;
}

std::uint64_t DiskQueue::peek() {
  for (; cursor_ < next_seq_; ++cursor_) {
    const Entry* e = entry(cursor_);
    if (e != nullptr && e->state == State::Live) return cursor_;
  }
  return 0;
}

const char* DiskQueue::record(const Entry& e) {
  auto it = segments_.find(e.segment);
  if (it == segments_.end()) return nullptr;
  if (std::next(it) == segments_.end() && e.offset >= tail_base_)
    return tail_.data() + (e.offset - tail_base_);  // the last segment's tail, in memory
  if (!rd_valid_ || rd_segment_ != e.segment || e.offset < rd_offset_ || e.offset + e.size > rd_offset_ + rd_buf_.size()) {
    // Read ahead (records written before this run, or older segments) up
    // to what is in the file.
    const std::uint64_t end = std::min<std::uint64_t>(it->second.written, e.offset + std::max<std::uint64_t>(e.size, 256u << 10));
    rd_valid_ = false;
    if (end < e.offset + e.size) return nullptr;
    rd_buf_.resize(end - e.offset);
    if (!pread_all(it->second.fd, rd_buf_.data(), rd_buf_.size(), e.offset)) return nullptr;
    rd_segment_ = e.segment;
    rd_offset_ = e.offset;
    rd_valid_ = true;
  }
  return rd_buf_.data() + (e.offset - rd_offset_);
}

void DiskQueue::rewind() { cursor_ = head_; }

void DiskQueue::rewind_to(std::uint64_t seq) { cursor_ = std::clamp(seq, head_, cursor_); }

std::uint64_t DiskQueue::unsent() const {
  std::uint64_t n = 0;
  for (std::uint64_t s = std::max(cursor_, head_); s < next_seq_; ++s)
    if (entries_[static_cast<std::size_t>(s - head_)].state == State::Live) ++n;
  return n;
}

bool DiskQueue::has_unsent() const {
  for (std::uint64_t s = std::max(cursor_, head_); s < next_seq_; ++s)
    if (entries_[static_cast<std::size_t>(s - head_)].state == State::Live) return true;
  return false;
}

bool DiskQueue::ack(std::uint64_t seq) {
  Entry* e = entry(seq);
  if (e == nullptr || e->state != State::Live) return false;
  e->state = State::Acked;
  --live_;
  live_bytes_ -= e->size;
  ++counters_.acked;
  if (seq == head_) advance_head();
  counters_.depth = live_;
  counters_.bytes = live_bytes_;
  return true;
}

bool DiskQueue::flush_segment(Segment& seg) {
  if (seg.written >= seg.size) return true;
  // Only the last segment has buffered bytes, all in tail_.
  const char* p = tail_.data() + (seg.written - tail_base_);
  const std::uint64_t n = seg.size - seg.written;
  if (!pwrite_all(seg.fd, p, n, seg.written)) {
    const int e = errno;
    (void)::ftruncate(seg.fd, static_cast<off_t>(seg.written));  // no half record stays
    failed(e);
    append_failed_ = true;
    return false;
  }
  seg.written = seg.size;
  counters_.storage_bytes += n;
  append_failed_ = false;
  return true;
}

bool DiskQueue::flush_pending() const {
  return !segments_.empty() && segments_.rbegin()->second.written < segments_.rbegin()->second.size;
}

bool DiskQueue::flush(bool with_position) {
  bool ok = segments_.empty() || flush_segment(segments_.rbegin()->second);
  if (!ok && free_space() && !flush_pending()) ok = true;  // all acked: nothing needs writing
  if (with_position && head_unwritten_) ok = persist_head() && ok;
  update_error_state();
  return ok;
}

void DiskQueue::sync() {
  (void)flush(true);
  for (auto& [first, seg] : segments_) {
    if (!seg.unsynced) continue;
    ++counters_.syncs;
    if (::fdatasync(seg.fd) != 0) {
      failed(errno);
      continue;
    }
    seg.unsynced = seg.written < seg.size;  // the rest once it is written
  }
  if (head_sync_needed_ && !head_unwritten_ && head_fd_ >= 0) {
    ++counters_.syncs;
    if (::fdatasync(head_fd_) == 0)
      head_sync_needed_ = false;
    else
      failed(errno);
  }
}

std::vector<std::string> DiskQueue::take_warnings() {
  std::vector<std::string> out;
  out.swap(warnings_);
  return out;
}

}  // namespace gateway::mqtt
