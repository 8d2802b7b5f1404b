#include "canopen/can/tx_queue.hpp"

#include <algorithm>

namespace canopen::can {

TxQueue::TxQueue(std::size_t capacity, Duration first_retry, Duration max_retry)
    : capacity_(capacity), first_retry_(first_retry), max_retry_(max_retry), retry_delay_(first_retry) {}

bool TxQueue::push(const Frame& f) {
  if (frames_.size() >= capacity_) {
    ++dropped_;
    return false;
  }
  frames_.push_back(f);
  high_water_ = std::max(high_water_, frames_.size());
  return true;
}

void TxQueue::clear() {
  dropped_ += frames_.size();
  frames_.clear();
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
