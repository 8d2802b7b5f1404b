// The per-network event sequence number kept across restarts
// (../shared/api-contract.md: "seq ... continues across restarts, kept in
// state-dir"), so a consumer deduplicating by (network, seq) is never
// misled by a restarted gateway whose queue replays older numbers.
//
// File <state-dir>/seq-net<N>: the first seq network N may use next, in
// decimal, and a newline. It is keyed by the network number alone, not the
// interface: consumers key by network number, so network N's numbers must
// never repeat, whichever interface it is configured with.
//
// Flash wear: nothing is written per event. open() reserves a block of
// numbers durably (temp file, fsync, rename, fsync of the directory), and
// so does use() whenever the running seq reaches the reserved bound: one
// small write per `block` events (the default, 2^20, is about one a minute
// on a CAN bus saturated with 18,000 frames/s). close() writes the exact
// next number at a clean stop. So the sequence continues without a gap
// after a clean stop, and after a crash at the reserved bound: numbers
// never repeat, and the gap (at most one block) shows that events may be
// missing.
//
// A missing file (first start, or an upgrade from a version that did not
// keep it) or an unreadable one (not a number) does not stop start-up: the
// sequence then starts at the wall-clock time in microseconds since 1970.
// That is above any number an earlier run can have reached: a run that
// started at 1 (or at the clock) gains less than one number per microsecond
// (CAN carries under 20,000 frames/s), and each crash skips one block,
// about a second of the clock, while systemd restarts a crashing service
// at most 5 times in 10 s. It assumes the clock did not go back (an edge
// box without RTC and NTP may boot in 1970: keep the file then).
//
// Thread safety: none; one owner thread. Blocking file I/O on the caller's
// thread (a few small writes and two fsyncs, once per block).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <system_error>

namespace gateway {

class SeqStore {
 public:
  static constexpr std::uint64_t kDefaultBlock = std::uint64_t{1} << 20;
  using WallClock = std::function<std::chrono::system_clock::time_point()>;

  // dir "": nothing is kept, every run starts at 1 (tests, tools).
  SeqStore(std::filesystem::path dir, std::uint32_t network, std::uint64_t block = kDefaultBlock,
           WallClock wall = [] { return std::chrono::system_clock::now(); });

  struct Opened {
    std::uint64_t first = 1;  // the seq of this run's first event
    // Why the stored value was not used (missing or unreadable file), for
    // the log; "" when it was, or when nothing is kept.
    std::string note;
    bool corrupt = false;  // the file exists but does not hold a number
    std::error_code error;  // the reservation could not be written
  };
  // Reads the stored value and reserves [first, first + block). Call once,
  // before the first event.
  Opened open();
  // Call with every event's seq before the event leaves the process. When
  // seq reaches the reserved bound, reserves the next block first (the one
  // durable write). A write error is returned; the bound moves on in memory
  // all the same, so a failing disk costs one attempt per block, not one
  // per event (numbers may then repeat after a crash).
  std::error_code use(std::uint64_t seq);
  // At a clean stop: stores `next` (the latest seq + 1) exactly.
  std::error_code close(std::uint64_t next);

  const std::filesystem::path& file() const { return file_; }
  // Numbers below this one may have been used (the durable bound).
  std::uint64_t reserved() const { return bound_; }

 private:
  std::error_code store(std::uint64_t value);

  std::filesystem::path file_;  // "" = nothing kept
  std::uint64_t block_;
  WallClock wall_;
  std::uint64_t bound_ = 0;
};

}  // namespace gateway
