#include "canopen/can/tx_queue.hpp"

#include <algorithm>

namespace canopen::can {

TxQueue::TxQueue(std::size_t capacity, Duration first_retry, Duration max_retry)
    : frames_(capacity), capacity_(capacity), first_retry_(first_retry), max_retry_(max_retry),
      retry_delay_(first_retry) {}

bool TxQueue::push(const Frame& f) {
  if (size_ >= capacity_) {
    ++dropped_;
    return false;
  }
  frames_[(head_ + size_) % capacity_] = f;
  ++size_;
  high_water_ = std::max(high_water_, size_);
  return true;
}

void TxQueue::clear() {
  dropped_ += size_;
  head_ = size_ = 0;
}

std::span<const Frame> TxQueue::front_run(std::size_t max) const {
  const std::size_t n = std::min({size_, capacity_ - head_, std::max<std::size_t>(max, 1)});
  return {frames_.data() + head_, n};
}

void TxQueue::pop(std::size_t n) {
  n = std::min(n, size_);
  for (std::size_t i = 0; i < n; ++i) on_written();
  head_ = size_ == n ? 0 : (head_ + n) % capacity_;
  size_ -= n;
}

std::optional<FlushResult> TxQueue::on_refused(WriteResult r) {
  switch (r) {
    case WriteResult::Written: return std::nullopt;
    case WriteResult::Failed:
      // This frame can never go out (e.g. EINVAL): drop it, go on.
      head_ = size_ == 1 ? 0 : (head_ + 1) % capacity_;
      --size_;
      ++failed_;
      return std::nullopt;
    case WriteResult::WouldBlock:
      ++retries_;
      return FlushResult::WouldBlock;
    case WriteResult::NoBuffers:
      on_no_buffers();
      return FlushResult::NoBuffers;
    case WriteResult::LinkDown: return FlushResult::LinkDown;
  }
  return std::nullopt;
}

void TxQueue::on_written() {
  ++written_;
  consecutive_no_buffers_ = 0;
  retry_delay_ = first_retry_;
}

void TxQueue::on_no_buffers() {
  ++retries_;
  // First ENOBUFS waits first_retry; each consecutive one doubles it.
  retry_delay_ = first_retry_;
  for (unsigned i = 0; i < consecutive_no_buffers_ && retry_delay_ < max_retry_; ++i) retry_delay_ *= 2;
  retry_delay_ = std::min(retry_delay_, max_retry_);
  ++consecutive_no_buffers_;
}

}  // namespace canopen::can
