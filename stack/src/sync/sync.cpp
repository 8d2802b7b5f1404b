// SYNC producer and consumer (CiA 301 7.2.5, objects 1005h-1007h, 1019h).
#include "canopen/sync/sync.hpp"

#include <utility>

namespace canopen::sync {

SyncProducer::SyncProducer(const od::ObjectDictionary& dictionary, FrameSink sink, TimePoint now)
    : od_(dictionary), sink_(std::move(sink)) {
  reconfigure(now);
}

void SyncProducer::reconfigure(TimePoint now) {
  cob_id_ = static_cast<std::uint32_t>(od_.get_unsigned(0x1005, 0).value_or(0x80));
  const auto period_us = od_.get_unsigned(0x1006, 0).value_or(0);
  period_ = std::chrono::duration_cast<Duration>(std::chrono::microseconds(static_cast<std::int64_t>(period_us)));
  const auto overflow = od_.get_unsigned(0x1019, 0).value_or(0);
  // 1 and 241..255 are reserved (the dictionary refuses them); treat as "no counter".
  overflow_ = (overflow >= 2 && overflow <= 240) ? static_cast<std::uint8_t>(overflow) : 0;
  counter_ = 1;
  const bool generate = (cob_id_ & kCobIdBit30) != 0 && period_us != 0;
  state_ = generate ? State::Running : State::Off;
  next_ = now + period_;
}

std::optional<std::uint8_t> SyncProducer::next_counter() const {
  if (overflow_ == 0) return std::nullopt;
  return counter_;
}

void SyncProducer::on_time(TimePoint now) {
  if (state_ != State::Running || now < next_) return;
  const std::uint8_t byte = counter_;
  const can::Frame f = frame_for_cob_id(cob_id_, &byte, overflow_ == 0 ? 0 : 1);
  if (overflow_ != 0) counter_ = counter_ >= overflow_ ? 1 : static_cast<std::uint8_t>(counter_ + 1);
  // Advance on the grid start + k x period; skip periods already missed.
  next_ += period_;
  if (next_ <= now) next_ += ((now - next_) / period_ + 1) * period_;
  if (sink_) sink_(f);
}

SyncConsumer::SyncConsumer(const od::ObjectDictionary& dictionary, Callback callback)
    : od_(dictionary), callback_(std::move(callback)) {}

bool SyncConsumer::on_frame(const can::Frame& frame, TimePoint now) {
  const auto cob_id = static_cast<std::uint32_t>(od_.get_unsigned(0x1005, 0).value_or(0x80));
  if (!matches_cob_id(frame, cob_id)) return false;
  const auto p = frame.payload();
  if (p.size() > 1) {
    ++bad_length_;
    return true;
  }
  last_ = now;
  last_counter_ = p.empty() ? std::nullopt : std::optional<std::uint8_t>(p[0]);
  if (callback_) callback_(SyncEvent{last_counter_});
  return true;
}

bool SyncConsumer::in_sync_window(TimePoint now) const {
  const auto window_us = od_.get_unsigned(0x1007, 0).value_or(0);
  if (window_us == 0) return true;
  if (!last_ || now < *last_) return false;
  return now - *last_ < std::chrono::microseconds(static_cast<std::int64_t>(window_us));
}

}  // namespace canopen::sync
