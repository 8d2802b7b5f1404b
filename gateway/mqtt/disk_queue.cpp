#include "mqtt/disk_queue.hpp"

#include <fcntl.h>
#include <unistd.h>


#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <vector>

namespace gateway::mqtt {
namespace {

constexpr std::size_t kHeader = 8;             // u32 length + u32 CRC
constexpr std::size_t kBodyFixed = 12;         // seq, qos, flags, topic length
constexpr std::uint32_t kMaxBody = 256u << 20; // sanity bound when reading
constexpr std::size_t kSlot = 24;

[[noreturn]] void throw_errno(const std::string& what) {
  throw std::system_error(errno, std::generic_category(), what);
}

// CRC-32 (IEEE, reflected 0xEDB88320: the same value as boost::crc_32_type,
// so existing files stay readable), 8 bytes per step with 8 tables: every
// message is checksummed on push, the byte-wise loop cost ~10 instructions
// a byte on the publish path.
struct Crc32Tables {
  std::uint32_t t[8][256];
  constexpr Crc32Tables() : t{} {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
      t[0][i] = c;
    }
    for (std::uint32_t i = 0; i < 256; ++i)
      for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  }
};
constexpr Crc32Tables kCrc;

std::uint32_t crc32(const char* data, std::size_t n) {
  const auto* p = reinterpret_cast<const unsigned char*>(data);
  std::uint32_t c = 0xFFFFFFFFu;
  for (; n >= 8; n -= 8, p += 8) {
    const std::uint32_t lo = c ^ (std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
                                  std::uint32_t{p[3]} << 24);
    const std::uint32_t hi = std::uint32_t{p[4]} | std::uint32_t{p[5]} << 8 | std::uint32_t{p[6]} << 16 |
                             std::uint32_t{p[7]} << 24;
    c = kCrc.t[7][lo & 0xFF] ^ kCrc.t[6][(lo >> 8) & 0xFF] ^ kCrc.t[5][(lo >> 16) & 0xFF] ^ kCrc.t[4][lo >> 24] ^
        kCrc.t[3][hi & 0xFF] ^ kCrc.t[2][(hi >> 8) & 0xFF] ^ kCrc.t[1][(hi >> 16) & 0xFF] ^ kCrc.t[0][hi >> 24];
  }
  for (; n > 0; --n, ++p) c = (c >> 8) ^ kCrc.t[0][(c ^ *p) & 0xFF];
  return c ^ 0xFFFFFFFFu;
}

void put_le(char* p, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) p[i] = static_cast<char>((v >> (8 * i)) & 0xff);
}
std::uint64_t get_le(const char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= std::uint64_t{static_cast<unsigned char>(p[i])} << (8 * i);
  return v;
}

// Repeats a positional read or write until all n bytes are done (short
// transfers, EINTR); false on an error or end of file.
template <typename Ptr, typename Syscall>
bool all_at(Syscall call, int fd, Ptr p, std::size_t n, std::uint64_t off) {
  while (n > 0) {
    ssize_t r = call(fd, p, n, static_cast<off_t>(off));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    n -= static_cast<std::size_t>(r);
    off += static_cast<std::uint64_t>(r);
  }
  return true;
}
bool pread_all(int fd, char* p, std::size_t n, std::uint64_t off) { return all_at(::pread, fd, p, n, off); }
bool pwrite_all(int fd, const char* p, std::size_t n, std::uint64_t off) { return all_at(::pwrite, fd, p, n, off); }

std::string segment_name(std::uint64_t first) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%020llu.seg", static_cast<unsigned long long>(first));
  return buf;
}

}  // namespace

DiskQueue::DiskQueue(DiskQueueOptions opts) : opts_(std::move(opts)) {
  if (opts_.max_messages == 0) opts_.max_messages = 1;
  if (opts_.segment_bytes < 4096) opts_.segment_bytes = 4096;
  std::error_code ec;
  std::filesystem::create_directories(opts_.dir, ec);
  if (ec) throw std::system_error(ec, "create " + opts_.dir.string());
  head_fd_ = ::open((opts_.dir / "acked").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (head_fd_ < 0) throw_errno("open " + (opts_.dir / "acked").string());
  read_head();
  open_existing();
}

DiskQueue::~DiskQueue() {
  sync();  // flushes first
  for (auto& [first, seg] : segments_) ::close(seg.fd);
  if (head_fd_ >= 0) ::close(head_fd_);
}

void DiskQueue::read_head() {
  char buf[2 * kSlot];
  std::memset(buf, 0, sizeof buf);
  (void)pread_all(head_fd_, buf, sizeof buf, 0);  // short file: slots stay zero
  for (int i = 0; i < 2; ++i) {
    const char* s = buf + static_cast<std::size_t>(i) * kSlot;
    std::uint64_t gen = get_le(s, 8);
    std::uint64_t head = get_le(s + 8, 8);
    if (gen == 0 || get_le(s + 16, 4) != crc32(s, 16)) continue;
    if (gen > head_generation_) {
      head_generation_ = gen;
      head_ = std::max<std::uint64_t>(head, 1);
    }
  }
  next_seq_ = cursor_ = head_;
}

void DiskQueue::write_head() {
  if (opts_.buffered_writes) {
    head_unwritten_ = true;  // flush() writes it
    return;
  }
  persist_head();
}

void DiskQueue::persist_head() {
  head_unwritten_ = false;
  // Alternate slots so a torn write leaves the other, older slot valid.
  ++head_generation_;
  char s[kSlot] = {};
  put_le(s, head_generation_, 8);
  put_le(s + 8, head_, 8);
  put_le(s + 16, crc32(s, 16), 4);
  if (!pwrite_all(head_fd_, s, kSlot, (head_generation_ % 2) * kSlot)) throw_errno("write acked position");
  head_dirty_ = true;
}

void DiskQueue::open_existing() {
  std::vector<std::uint64_t> firsts;
  for (const auto& de : std::filesystem::directory_iterator(opts_.dir)) {
    const auto name = de.path().filename().string();
    if (name.size() != 24 || name.substr(20) != ".seg") continue;
    if (!std::all_of(name.begin(), name.begin() + 20, [](char c) { return c >= '0' && c <= '9'; })) continue;
    firsts.push_back(std::stoull(name.substr(0, 20)));
  }
  std::sort(firsts.begin(), firsts.end());
  for (std::size_t i = 0; i < firsts.size(); ++i) {
    const auto path = opts_.dir / segment_name(firsts[i]);
    // Fully acked segments (the next one starts at or before the head) go.
    if (i + 1 < firsts.size() && firsts[i + 1] <= head_) {
      ::unlink(path.c_str());
      continue;
    }
    int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) throw_errno("open " + path.string());
    Segment& seg = segments_[firsts[i]];
    seg.fd = fd;
    replay_segment(firsts[i], seg, i + 1 == firsts.size());
  }
  cursor_ = head_;
  enforce_bounds(0);
}

void DiskQueue::replay_segment(std::uint64_t first, Segment& seg, bool /*last*/) {
  off_t end = ::lseek(seg.fd, 0, SEEK_END);
  if (end < 0) throw_errno("seek segment");
  const auto file_size = static_cast<std::uint64_t>(end);
  std::vector<char> data(file_size);
  if (file_size > 0 && !pread_all(seg.fd, data.data(), data.size(), 0)) throw_errno("read segment");
  std::uint64_t off = 0;
  std::uint64_t expect = std::max(first, head_);
  while (off + kHeader <= file_size) {
    const char* h = data.data() + off;
    auto len = static_cast<std::uint32_t>(get_le(h, 4));
    if (len < kBodyFixed || len > kMaxBody || off + kHeader + len > file_size) break;
    const char* b = h + kHeader;
    if (static_cast<std::uint32_t>(get_le(h + 4, 4)) != crc32(b, len)) break;
    std::uint64_t seq = get_le(b, 8);
    auto tlen = get_le(b + 10, 2);
    if (kBodyFixed + tlen > len) break;
    const auto size = static_cast<std::uint32_t>(kHeader + len);
    if (seq >= expect) {
      // A gap (a lost segment) is filled with dropped entries.
      while (next_seq_ < seq) {
        if (next_seq_ >= head_) entries_.push_back(Entry{first, 0, 0, 0, State::Dropped});
        ++next_seq_;
      }
      if (next_seq_ == seq) {
        std::uint8_t qos = static_cast<std::uint8_t>(b[8]) == 0 ? 0 : 1;
        entries_.push_back(Entry{first, off, size, qos, State::Live});
        (qos == 0 ? live_qos0_ : live_qos1_).push_back(seq);
        ++live_;
        live_bytes_ += size;
        ++counters_.replayed;
        ++next_seq_;
        expect = next_seq_;
      }
    }
    off += size;
  }
  if (off < file_size) {
    // Torn or corrupt tail: cut it so appends continue from a clean record.
    counters_.truncated_bytes += file_size - off;
    if (::ftruncate(seg.fd, static_cast<off_t>(off)) != 0) throw_errno("truncate segment");
  }
  seg.size = seg.written = off;
  counters_.disk_bytes += off;
  tail_.clear();
  tail_base_ = off;  // appends to the last replayed segment go after this
  // An empty segment still numbers from its name.
  while (next_seq_ < first) {
    entries_.push_back(Entry{first, 0, 0, 0, State::Dropped});
    ++next_seq_;
  }
  // Keep the head consistent when the file started past it (earlier lost).
  while (!entries_.empty() && entries_.front().state != State::Live) {
    entries_.pop_front();
    ++head_;
  }
  if (entries_.empty() && head_ < next_seq_) head_ = next_seq_;
}

DiskQueue::Segment& DiskQueue::writable_segment(std::uint64_t seq, std::uint64_t need) {
  if (!segments_.empty()) {
    auto& last = segments_.rbegin()->second;
    if (last.size == 0 || last.size + need <= opts_.segment_bytes) return last;
  }
  if (!segments_.empty()) flush_segment(segments_.rbegin()->second);  // its buffer goes first
  const auto path = opts_.dir / segment_name(seq);
  int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw_errno("create " + path.string());
  Segment& seg = segments_[seq];
  seg.fd = fd;
  tail_.clear();
  tail_base_ = 0;
  delete_consumed_segments();  // the previous one may be fully acked already
  return seg;
}

std::uint64_t DiskQueue::push(const QueuedMessage& m) { return push(m.topic, m.payload, m.qos, m.retained); }

std::uint64_t DiskQueue::push(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained) {
  const std::size_t tlen = std::min<std::size_t>(topic.size(), 0xffff);
  const std::size_t body = kBodyFixed + tlen + payload.size();
  const std::uint64_t size = kHeader + body;
  if (size > opts_.max_bytes || body > kMaxBody) {
    ++counters_.dropped_too_big;
    return 0;
  }
  enforce_bounds(size);

  const std::uint64_t seq = next_seq_;
  Segment& seg = writable_segment(seq, size);
  const std::uint64_t first = segments_.rbegin()->first;
  if (opts_.buffered_writes && seg.size - seg.written + size > opts_.write_buffer_bytes) flush_segment(seg);
  // The tail cache keeps at most about one segment; past that (a segment
  // larger than the cap, or a huge record) it starts again after a flush.
  const std::uint64_t cap = std::max<std::uint64_t>(opts_.segment_bytes, 1u << 20) + (1u << 16);
  if (tail_.size() + size > cap) {
    flush_segment(seg);
    tail_.clear();
    tail_base_ = seg.size;
  }
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
    if (!pwrite_all(seg.fd, p, size, seg.size)) {
      int e = errno;
      (void)::ftruncate(seg.fd, static_cast<off_t>(seg.size));  // no half record stays
      tail_.resize(at);
      errno = e;
      throw_errno("append to message queue");
    }
    seg.written = seg.size + size;
  }
  entries_.push_back(Entry{first, seg.size, static_cast<std::uint32_t>(size), static_cast<std::uint8_t>(qos == 0 ? 0 : 1), State::Live});
  (qos == 0 ? live_qos0_ : live_qos1_).push_back(seq);
  seg.size += size;
  seg.dirty = true;
  counters_.disk_bytes += size;
  ++next_seq_;
  ++live_;
  live_bytes_ += size;
  ++counters_.written;
  counters_.depth = live_;
  counters_.bytes = live_bytes_;
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
    entries_.pop_front();
    ++head_;
  }
  if (cursor_ < head_) cursor_ = head_;
  if (head_ == old) return;
  write_head();
  delete_consumed_segments();
}

void DiskQueue::delete_consumed_segments() {
  // Segments wholly below the head go, except the one appended to.
  while (segments_.size() > 1) {
    auto it = segments_.begin();
    auto nx = std::next(it);
    if (nx->first > head_) break;
    // The position goes to disk before the file it makes obsolete goes.
    if (head_unwritten_) persist_head();
    if (rd_valid_ && rd_segment_ == it->first) rd_valid_ = false;
    ::close(it->second.fd);
    counters_.disk_bytes -= it->second.size;
    ::unlink((opts_.dir / segment_name(it->first)).c_str());
    segments_.erase(it);
  }
}

bool DiskQueue::next(Item& out) {
  while (cursor_ < next_seq_) {
    const std::uint64_t seq = cursor_++;
    Entry* e = entry(seq);
    if (e == nullptr || e->state != State::Live) continue;
    const char* rec = record(*e);
    if (rec == nullptr) continue;
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

const char* DiskQueue::record(const Entry& e) {
  auto it = segments_.find(e.segment);
  if (it == segments_.end()) return nullptr;
  if (std::next(it) == segments_.end() && e.offset >= tail_base_)
    return tail_.data() + (e.offset - tail_base_);  // the last segment's tail, in memory
  if (!rd_valid_ || rd_segment_ != e.segment || e.offset < rd_offset_ || e.offset + e.size > rd_offset_ + rd_buf_.size()) {
    // Read ahead (records written before this run, or older segments) up
    // to what is in the file.
    const std::uint64_t end = std::min<std::uint64_t>(it->second.written, e.offset + std::max<std::uint64_t>(e.size, 256u << 10));
    if (end < e.offset + e.size) throw std::system_error(EIO, std::generic_category(), "read message queue: record not in file");
    rd_valid_ = false;
    rd_buf_.resize(end - e.offset);
    if (!pread_all(it->second.fd, rd_buf_.data(), rd_buf_.size(), e.offset)) throw_errno("read message queue");
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

void DiskQueue::flush_segment(Segment& seg) {
  if (seg.written >= seg.size) return;
  // Only the last segment has buffered bytes, all in tail_.
  const char* p = tail_.data() + (seg.written - tail_base_);
  if (!pwrite_all(seg.fd, p, seg.size - seg.written, seg.written)) {
    int e = errno;
    (void)::ftruncate(seg.fd, static_cast<off_t>(seg.written));  // no half record stays
    errno = e;
    throw_errno("append to message queue");
  }
  seg.written = seg.size;
}

bool DiskQueue::flush_pending() const {
  return !segments_.empty() && segments_.rbegin()->second.written < segments_.rbegin()->second.size;
}

void DiskQueue::flush(bool with_position) {
  if (!segments_.empty()) flush_segment(segments_.rbegin()->second);
  if (with_position && head_unwritten_) persist_head();
}

void DiskQueue::sync() {
  try {
    flush();
    if (head_unwritten_) persist_head();
  } catch (const std::system_error&) {
    // Still buffered; the next flush() or sync() tries again.
  }
  for (auto& [first, seg] : segments_) {
    if (seg.dirty) {
      (void)::fdatasync(seg.fd);
      seg.dirty = false;
    }
  }
  if (head_dirty_ && head_fd_ >= 0) (void)::fdatasync(head_fd_);
  head_dirty_ = false;
}

}  // namespace gateway::mqtt
