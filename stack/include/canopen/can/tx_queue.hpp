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
// Not thread-safe; owned by one channel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"

namespace canopen::can {

enum class WriteResult : std::uint8_t { Written, WouldBlock, NoBuffers, LinkDown, Failed };

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
  template <typename Writer>
  FlushResult flush(Writer&& write);

  // Back-off before the next flush after NoBuffers: doubles on each
  // consecutive NoBuffers up to max_retry, reset by any successful write.
  Duration retry_delay() const { return retry_delay_; }

  bool empty() const { return frames_.empty(); }
  std::size_t size() const { return frames_.size(); }
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

  std::deque<Frame> frames_;
  std::size_t capacity_;
  std::size_t high_water_ = 0;
  Duration first_retry_, max_retry_, retry_delay_;
  unsigned consecutive_no_buffers_ = 0;
  std::uint64_t written_ = 0, dropped_ = 0, failed_ = 0, retries_ = 0;
};

template <typename Writer>
FlushResult TxQueue::flush(Writer&& write) {
  while (!frames_.empty()) {
    switch (write(frames_.front())) {
      case WriteResult::Written:
        frames_.pop_front();
        on_written();
        break;
      case WriteResult::Failed:
        frames_.pop_front();
        ++failed_;
        break;
      case WriteResult::WouldBlock:
        ++retries_;
        return FlushResult::WouldBlock;
      case WriteResult::NoBuffers:
        on_no_buffers();
        return FlushResult::NoBuffers;
      case WriteResult::LinkDown:
        return FlushResult::LinkDown;
    }
  }
  return FlushResult::Drained;
}

}  // namespace canopen::can
