#include "canopen/socketcan/service_driver.hpp"

#include <algorithm>

#include <boost/asio/post.hpp>

namespace canopen::socketcan {

ServiceDriver::ServiceDriver(boost::asio::io_context& io, can::Channel& channel) : channel_(channel), timer_(io) {
  channel_.on_frames([this, alive = std::weak_ptr<bool>(alive_)](std::span<const can::Frame> frames) {
    if (alive.expired()) return;
    const TimePoint now = SteadyClock::now();
    feeding_ = true;
    for (const auto& f : frames) {
      for (std::size_t i = 0; i < entries_.size(); ++i) entries_[i].on_frame(f, now);
    }
    if (tap_) tap_(frames);
    feeding_ = false;
    rearm();
  });
}

ServiceDriver::~ServiceDriver() {
  *alive_ = false;
  alive_.reset();
  channel_.on_frames(nullptr);
  timer_.cancel();
  for (auto& e : entries_) {
    if (e.detach) e.detach();
  }
}

void ServiceDriver::remove(const void* service) {
  std::erase_if(entries_, [service](Entry& e) {
    if (e.id != service) return false;
    if (e.detach) e.detach();
    return true;
  });
}

void ServiceDriver::rearm() {
  TimePoint next = TimePoint::max();
  for (const auto& e : entries_) next = std::min(next, e.next_deadline());
  if (next == armed_for_) return;
  if (next == TimePoint::max()) {
    armed_for_ = next;
    timer_.cancel();
    return;
  }
  arm(next);
}

void ServiceDriver::deadline_moved(TimePoint next) {
  // While feeding, rearm() runs afterwards anyway; a later deadline only
  // means the timer finds nothing due and re-arms then.
  if (feeding_ || next >= armed_for_) return;
  arm(next);
}

void ServiceDriver::arm(TimePoint at) {
  armed_for_ = at;
  timer_.expires_at(at);
  timer_.async_wait([this, alive = std::weak_ptr<bool>(alive_)](const boost::system::error_code& ec) {
    if (ec || alive.expired()) return;
    on_timer();
  });
}

void ServiceDriver::on_timer() {
  armed_for_ = TimePoint::max();
  const TimePoint now = SteadyClock::now();
  feeding_ = true;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    if (entries_[i].next_deadline() <= now) entries_[i].on_time(now);
  }
  feeding_ = false;
  rearm();
}

void ServiceDriver::deliver_locally(const can::Frame& f, const void* only) {
  local_.emplace_back(f, only);
  local_.back().first.timestamp = can::Frame::Clock::now();
  if (drain_posted_) return;
  drain_posted_ = true;
  boost::asio::post(timer_.get_executor(), [this, alive = std::weak_ptr<bool>(alive_)] {
    if (alive.expired()) return;
    drain_local();
  });
}

void ServiceDriver::drain_local() {
  drain_posted_ = false;
  std::vector<std::pair<can::Frame, const void*>> frames;
  frames.swap(local_);
  const TimePoint now = SteadyClock::now();
  feeding_ = true;
  for (const auto& [f, only] : frames) {
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (only == nullptr || entries_[i].id == only) entries_[i].on_frame(f, now);
    }
  }
  feeding_ = false;
  rearm();
}

}  // namespace canopen::socketcan
