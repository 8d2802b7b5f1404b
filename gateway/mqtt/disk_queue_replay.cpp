// Opening a DiskQueue: the position file and the replay of the segment
// files ("Replay" in disk_queue.hpp), skipping corruption and cutting a torn
// tail.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <system_error>
#include <vector>

#include "mqtt/disk_queue.hpp"
#include "mqtt/disk_queue_format.hpp"

namespace gateway::mqtt {

using namespace disk_format;

namespace {

[[noreturn]] void throw_errno(const std::string& what) {
  throw std::system_error(errno, std::generic_category(), what);
}

// "<20 digits>.seg" naming a value that fits in 64 bits.
bool parse_segment_name(const std::string& name, std::uint64_t& first) {
  if (name.size() != 24 || name.compare(20, 4, ".seg") != 0) return false;
  if (!std::all_of(name.begin(), name.begin() + 20, [](char c) { return c >= '0' && c <= '9'; })) return false;
  auto [p, ec] = std::from_chars(name.data(), name.data() + 20, first);
  return ec == std::errc() && p == name.data() + 20;
}

}  // namespace

DiskQueue::DiskQueue(DiskQueueOptions opts) : opts_(std::move(opts)) {
  if (opts_.max_messages == 0) opts_.max_messages = 1;
  if (opts_.segment_bytes < 4096) opts_.segment_bytes = 4096;
  std::error_code ec;
  std::filesystem::create_directories(opts_.dir, ec);
  if (ec) throw std::system_error(ec, "create " + opts_.dir.string());
  const auto acked = opts_.dir / "acked";
  head_fd_ = ::open(acked.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (head_fd_ < 0) {
    // A full disk must not stop the gateway: the position is written once
    // there is room again (persist_head opens it then).
    if (errno != ENOSPC && errno != EDQUOT) throw_errno("open " + acked.string());
    failed(errno);
  }
  read_head();
  open_existing();
}

void DiskQueue::read_head() {
  if (head_fd_ < 0) return;
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
  // Both slots allocated now, so that rewriting them later needs no new
  // space (a full disk then cannot fail the position write on most file
  // systems). Best effort: persist_head() copes.
  struct stat st {};
  if (::fstat(head_fd_, &st) == 0 && st.st_size < static_cast<off_t>(2 * kSlot)) {
    const auto have = static_cast<std::size_t>(st.st_size);
    (void)pwrite_all(head_fd_, buf + have, 2 * kSlot - have, have);
  }
}

void DiskQueue::open_existing() {
  std::vector<std::uint64_t> firsts;
  for (const auto& de : std::filesystem::directory_iterator(opts_.dir)) {
    const auto name = de.path().filename().string();
    if (name == "acked") continue;
    std::uint64_t first = 0;
    std::error_code ec;
    if (parse_segment_name(name, first) && de.is_regular_file(ec)) {
      firsts.push_back(first);
      continue;
    }
    ++counters_.ignored_files;
    warnings_.push_back("ignoring unknown " + std::string(de.is_directory(ec) ? "directory" : "file") + " '" + name +
                        "' in " + opts_.dir.string());
  }
  std::sort(firsts.begin(), firsts.end());
  for (std::size_t i = 0; i < firsts.size(); ++i) {
    const auto path = opts_.dir / segment_name(firsts[i]);
    const bool last = i + 1 == firsts.size();
    // Fully acked segments (the next one starts at or before the head) go.
    if (!last && firsts[i + 1] <= head_) {
      ::unlink(path.c_str());
      continue;
    }
    int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) {
      ++counters_.ignored_files;
      warnings_.push_back("cannot open " + path.string() + ": " + std::strerror(errno) + "; its messages are lost");
      continue;
    }
    Segment& seg = segments_[firsts[i]];
    seg.fd = fd;
    replay_segment(firsts[i], seg, last, last ? ~std::uint64_t{0} : firsts[i + 1]);
  }
  cursor_ = head_;
  enforce_bounds(0);
}

// Replays one segment's records (see "Replay" in the header). Records of
// this segment have sequence numbers in [first, limit), increasing.
void DiskQueue::replay_segment(std::uint64_t first, Segment& seg, bool last, std::uint64_t limit) {
  const auto name = (opts_.dir / segment_name(first)).string();
  off_t end = ::lseek(seg.fd, 0, SEEK_END);
  const auto file_size = static_cast<std::uint64_t>(std::max<off_t>(end, 0));
  std::vector<char> data(file_size);
  if (file_size > 0 && !pread_all(seg.fd, data.data(), data.size(), 0)) {
    // Unreadable: its messages are lost; appends (if last) go after it.
    counters_.corrupt_bytes += file_size;
    warnings_.push_back("cannot read " + name + ": " + std::strerror(errno) + "; its messages are lost");
    data.clear();
  }
  const std::uint64_t have = data.size();

  // Seqs before this segment's first that are missing are in deleted (fully
  // acked) segments: not corruption.
  auto fill_to = [&](std::uint64_t s, bool corrupt) {
    while (next_seq_ < s) {
      if (next_seq_ >= head_) {
        entries_.push_back(Entry{first, 0, 0, 0, State::Dropped, false});
        if (corrupt) ++counters_.corrupt_records;
      }
      ++next_seq_;
    }
  };
  fill_to(first, false);

  std::uint64_t prev = 0;  // last good seq in this segment
  // The size of a valid record at `at`, or 0. slack > 0 (resynchronising):
  // its seq must also be within `slack` of the expected one, as the skipped
  // bytes cannot have held more records than that.
  auto record_at = [&](std::uint64_t at, std::uint64_t slack) -> std::uint64_t {
    if (at + kHeader + kBodyFixed > have) return 0;
    const char* h = data.data() + at;
    const auto len = static_cast<std::uint32_t>(get_le(h, 4));
    if (len < kBodyFixed || len > kMaxBody || at + kHeader + len > have) return 0;
    const char* b = h + kHeader;
    const std::uint64_t seq = get_le(b, 8);
    const std::uint64_t expected = prev != 0 ? prev + 1 : first;
    if (seq < expected || seq >= limit || (slack > 0 && seq - expected >= slack)) return 0;
    if (kBodyFixed + get_le(b + 10, 2) > len) return 0;
    if (static_cast<std::uint32_t>(get_le(h + 4, 4)) != crc32(b, len)) return 0;
    return kHeader + len;
  };

  std::uint64_t off = 0;
  std::uint64_t bad_at = 0, bad_bytes = 0;
  while (off < have) {
    std::uint64_t size = record_at(off, 0);
    if (size == 0) {
      // Corrupt (or a torn tail): look for the next record that validates.
      std::uint64_t at = off + 1;
      for (; at + kHeader + kBodyFixed <= have; ++at)
        if ((size = record_at(at, (at - off) / (kHeader + kBodyFixed) + 2)) != 0) break;
      if (size == 0) break;  // nothing valid after off: the tail
      counters_.corrupt_bytes += at - off;
      bad_at = off;
      bad_bytes = at - off;
      off = at;
    }
    const char* b = data.data() + off + kHeader;
    const std::uint64_t seq = get_le(b, 8);
    prev = seq;
    const std::uint64_t lost_before = counters_.corrupt_records;
    if (seq >= next_seq_) fill_to(seq, true);  // the seqs skipped over are lost
    if (bad_bytes > 0) {
      warnings_.push_back(name + ": skipped " + std::to_string(bad_bytes) + " corrupt bytes at offset " +
                          std::to_string(bad_at) + " (" + std::to_string(counters_.corrupt_records - lost_before) +
                          " messages lost)");
      bad_bytes = 0;
    }
    if (seq >= next_seq_) {
      const std::uint8_t qos = static_cast<std::uint8_t>(b[8]) == 0 ? 0 : 1;
      entries_.push_back(Entry{first, off, static_cast<std::uint32_t>(size), qos, State::Live, true});
      (qos == 0 ? live_qos0_ : live_qos1_).push_back(seq);
      ++live_;
      live_bytes_ += size;
      ++counters_.replayed;
      ++next_seq_;
    }
    off += size;
  }
  if (off < have) {
    if (last) {
      // Torn write of a crash: cut it so appends continue from a clean
      // record (a failed cut is harmless: appends overwrite it).
      counters_.truncated_bytes += have - off;
      (void)::ftruncate(seg.fd, static_cast<off_t>(off));
    } else {
      counters_.corrupt_bytes += have - off;
      warnings_.push_back(name + ": skipped " + std::to_string(have - off) + " corrupt bytes at its end");
    }
  }
  seg.size = seg.written = last && have == file_size ? off : file_size;
  counters_.disk_bytes += seg.size;
  if (last) {
    tail_.clear();
    tail_base_ = seg.size;  // appends to the last segment go after this
  }
  // Keep the head consistent when the file started past it (earlier lost).
  while (!entries_.empty() && entries_.front().state != State::Live) {
    entries_.pop_front();
    ++head_;
  }
  if (entries_.empty() && head_ < next_seq_) head_ = next_seq_;
}

}  // namespace gateway::mqtt
