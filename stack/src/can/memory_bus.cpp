#include "canopen/can/memory_bus.hpp"

#include <algorithm>

namespace canopen::can {

MemoryEndpoint::~MemoryEndpoint() { bus_->detach(*this); }

SendStatus MemoryEndpoint::send(const Frame& frame) {
  if (!frame.valid()) {
    ++stats_.tx_dropped;
    return SendStatus::Invalid;
  }
  if (state() == BusState::Down) {
    ++stats_.tx_dropped;
    return SendStatus::QueueFull;
  }
  ++stats_.tx_frames;
  bus_->submit(*this, frame);
  return SendStatus::Accepted;
}

void MemoryEndpoint::set_link_up(bool up) {
  auto ev = up ? tracker_.on_link_up() : tracker_.on_link_down(false);
  if (ev) report(*ev);
}

void MemoryEndpoint::receive(const Frame& f) {
  ++stats_.rx_frames;
  deliver({&f, 1});
}

MemoryBus::MemoryBus(BusFaults faults) : faults_(std::move(faults)), rng_(faults_.seed) {}

void MemoryBus::set_faults(BusFaults faults) {
  faults_ = std::move(faults);
  rng_.seed(faults_.seed);
}

std::unique_ptr<MemoryEndpoint> MemoryBus::attach(std::string name) {
  std::unique_ptr<MemoryEndpoint> ep(new MemoryEndpoint(*this, std::move(name)));
  ep->tracker_.on_link_up();
  endpoints_.push_back(ep.get());
  return ep;
}

void MemoryBus::detach(const MemoryEndpoint& ep) {
  // During delivery the slot is only cleared, so the loop's indexes stay
  // valid; deliver_one() compacts afterwards.
  if (delivering_ > 0) {
    std::replace(endpoints_.begin(), endpoints_.end(), const_cast<MemoryEndpoint*>(&ep),
                 static_cast<MemoryEndpoint*>(nullptr));
  } else {
    std::erase(endpoints_, &ep);
  }
  // Frames already on the bus stay there: the wire does not care that the
  // sender went away. Only the dangling sender pointer is cleared.
  for (auto& q : queue_) {
    if (q.sender == &ep) q.sender = nullptr;
  }
}

bool MemoryBus::chance(double p) {
  if (p <= 0.0) return false;
  return std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < p;
}

void MemoryBus::submit(const MemoryEndpoint& from, const Frame& f) {
  const std::uint64_t index = sent_++;
  FrameVerdict v = FrameVerdict::Deliver;
  if (faults_.verdict) {
    v = faults_.verdict(f, index);
  } else if (chance(faults_.loss)) {
    v = FrameVerdict::Drop;
  } else if (chance(faults_.duplicate)) {
    v = FrameVerdict::Duplicate;
  }
  if (v == FrameVerdict::Drop) {
    ++lost_;
    return;
  }
  Queued q{f, &from};
  if (now_) q.frame.timestamp = now_();
  const int copies = v == FrameVerdict::Duplicate ? 2 : 1;
  for (int i = 0; i < copies; ++i) {
    if (!queue_.empty() && chance(faults_.reorder)) {
      queue_.insert(queue_.end() - 1, q);
    } else {
      queue_.push_back(q);
    }
  }
}

bool MemoryBus::deliver_one() {
  if (queue_.empty()) return false;
  Queued q = std::move(queue_.front());
  queue_.pop_front();
  // Handlers may attach endpoints (they join after this frame) or destroy
  // them (their slot is nulled), so iterate by index over the current size.
  // A handler may even deliver (nested): only the outermost level compacts.
  ++delivering_;
  const std::size_t n = endpoints_.size();
  for (std::size_t i = 0; i < n && i < endpoints_.size(); ++i) {
    MemoryEndpoint* ep = endpoints_[i];
    if (ep == nullptr || ep == q.sender || ep->state() == BusState::Down) continue;
    ep->receive(q.frame);
  }
  if (--delivering_ == 0) std::erase(endpoints_, nullptr);
  return true;
}

std::size_t MemoryBus::deliver(std::size_t max_frames) {
  std::size_t n = 0;
  while (n < max_frames && deliver_one()) ++n;
  return n;
}

}  // namespace canopen::can
