// Bounded, order-preserving transmit queue for a CAN channel, without I/O.
//
// The adapter hands flush() a writer that tries one frame and says what
// happened. The queue keeps every frame the writer could not take yet, in
// order, and tells the adapter what to wait for before flushing again:
//   WouldBlock  (EAGAIN)  -> wait until the socket is writable
//   NoBuffers   (ENOBUFS) -> the device queue is full; retry after a short
//                            back-off (poll() does not signal this case)
//   LinkDown    (ENETDOWN)-> wait for the interface to come back
// A frame the writer rejects for good (Failed, e.g. EINVAL) is dropped and
// counted so one bad frame cannot wedge the queue.
//
// flush_batch() hands the writer contiguous runs of frames at once (for
// sendmmsg: one syscall per run instead of one per frame).
//
// Not thread-safe; owned by one channel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <optional>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"

namespace canopen::can {

enum class WriteResult : std::uint8_t { Written, WouldBlock, NoBuffers, LinkDown, Failed };

// What a batch writer did with a run of frames: the first `written` went
// out; if that is fewer than offered, `stopped_on` says why the next did not
// (Written there means "accepted part of the run, offer the rest again").
struct BatchWrite {
  std::size_t written = 0;
  WriteResult stopped_on = WriteResult::Written;
};

enum class FlushResult : std::uint8_t {
  Drained,     // queue empty
  WouldBlock,  // wait for writability, then flush
  NoBuffers,   // wait retry_delay(), then flush
  LinkDown,    // wait for link up, then flush
};

class TxQueue {
 public:
  explicit TxQueue(std::size_t capacity, Duration first_retry = std::chrono::milliseconds(1),
                   Duration max_retry = std::chrono::milliseconds(32));

  // Appends a frame; false (and the frame counted as dropped) when full.
  bool push(const Frame& f);

  // Writes queued frames in order until empty or the writer stops.
  // Writer: WriteResult(const Frame&).
  template <typename Writer>
  FlushResult flush(Writer&& write);
  // The same, offering runs of up to max_batch frames.
  // Writer: BatchWrite(std::span<const Frame>).
  template <typename BatchWriter>
  FlushResult flush_batch(BatchWriter&& write, std::size_t max_batch);

  // Back-off before the next flush after NoBuffers: doubles on each
  // consecutive NoBuffers up to max_retry, reset by any successful write.
  Duration retry_delay() const { return retry_delay_; }

  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return capacity_; }
  std::size_t high_water() const { return high_water_; }
  std::uint64_t written() const { return written_; }
  std::uint64_t dropped() const { return dropped_; }
  std::uint64_t failed() const { return failed_; }
  std::uint64_t retries() const { return retries_; }
  // Discards everything queued (counted as dropped).
  void clear();

 private:
  void on_written();
  void on_no_buffers();
  // The longest contiguous run at the head of the ring, at most max frames.
  std::span<const Frame> front_run(std::size_t max) const;
  void pop(std::size_t n);
  // Handles a writer's refusal of the head frame; nullopt means "go on".
  std::optional<FlushResult> on_refused(WriteResult r);

  // Ring buffer: frames_[head_ .. head_+size_) modulo capacity_.
  std::vector<Frame> frames_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::size_t capacity_;
  std::size_t high_water_ = 0;
  Duration first_retry_, max_retry_, retry_delay_;
  unsigned consecutive_no_buffers_ = 0;
  std::uint64_t written_ = 0, dropped_ = 0, failed_ = 0, retries_ = 0;
};

template <typename Writer>
FlushResult TxQueue::flush(Writer&& write) {
  while (!empty()) {
    const WriteResult r = write(frames_[head_]);
    if (r == WriteResult::Written) {
      pop(1);
      continue;
    }
    if (auto stop = on_refused(r)) return *stop;
  }
  return FlushResult::Drained;
}

template <typename BatchWriter>
FlushResult TxQueue::flush_batch(BatchWriter&& write, std::size_t max_batch) {
  while (!empty()) {
    const std::span<const Frame> run = front_run(max_batch);
    const BatchWrite r = write(run);
    pop(r.written);
    if (r.written == run.size()) continue;
    if (r.stopped_on == WriteResult::Written) {
      // Part of the run went out without an error for the rest: offer it
      // again. A writer that took nothing is treated as blocked.
      if (r.written > 0) continue;
      if (auto stop = on_refused(WriteResult::WouldBlock)) return *stop;
    }
    if (auto stop = on_refused(r.stopped_on)) return *stop;
  }
  return FlushResult::Drained;
}

}  // namespace canopen::can
