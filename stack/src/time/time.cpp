// TIME producer and consumer (CiA 301 7.2.6, object 1012h; TIME_OF_DAY 7.1.6.5).
#include "canopen/time/time.hpp"

#include <algorithm>
#include <utility>

namespace canopen::time {
namespace {

constexpr std::uint32_t kMsMask = 0x0FFFFFFFU;  // 28 bits; the top 4 are reserved

std::uint32_t cob_id_time(const od::ObjectDictionary& od) {
  return static_cast<std::uint32_t>(od.get_unsigned(0x1012, 0).value_or(0x100));
}

}  // namespace

std::array<std::uint8_t, 6> encode_time_of_day(const TimeOfDay& t) {
  const std::uint32_t ms = t.ms & kMsMask;
  return {static_cast<std::uint8_t>(ms), static_cast<std::uint8_t>(ms >> 8), static_cast<std::uint8_t>(ms >> 16),
          static_cast<std::uint8_t>(ms >> 24), static_cast<std::uint8_t>(t.days),
          static_cast<std::uint8_t>(t.days >> 8)};
}

TimeOfDay decode_time_of_day(const std::array<std::uint8_t, 6>& b) {
  TimeOfDay t;
  t.ms = (static_cast<std::uint32_t>(b[0]) | (static_cast<std::uint32_t>(b[1]) << 8) |
          (static_cast<std::uint32_t>(b[2]) << 16) | (static_cast<std::uint32_t>(b[3]) << 24)) &
         kMsMask;
  t.days = static_cast<std::uint16_t>(b[4] | (b[5] << 8));
  return t;
}

TimeProducer::TimeProducer(const od::ObjectDictionary& dictionary, FrameSink sink, Duration period, TimePoint now)
    : od_(dictionary), sink_(std::move(sink)), period_(period), next_(now + period) {}

bool TimeProducer::send(std::int64_t unix_ms) {
  const std::uint32_t cob_id = cob_id_time(od_);
  if ((cob_id & kCobIdBit30) == 0) return false;
  const auto bytes = encode_time_of_day(time_of_day_from_unix_ms(unix_ms));
  const can::Frame f = frame_for_cob_id(cob_id, bytes.data(), static_cast<std::uint8_t>(bytes.size()));
  if (sink_) sink_(f);
  return true;
}

TimePoint TimeProducer::next_deadline() const {
  return period_ > Duration::zero() ? next_ : TimePoint::max();
}

void TimeProducer::on_time(TimePoint now, std::int64_t unix_ms) {
  if (period_ <= Duration::zero() || now < next_) return;
  next_ += period_;
  if (next_ <= now) next_ += ((now - next_) / period_ + 1) * period_;
  (void)send(unix_ms);
}

TimeConsumer::TimeConsumer(const od::ObjectDictionary& dictionary, Callback callback)
    : od_(dictionary), callback_(std::move(callback)) {}

bool TimeConsumer::on_frame(const can::Frame& frame, TimePoint /*now*/) {
  const std::uint32_t cob_id = cob_id_time(od_);
  if ((cob_id & kCobIdBit31) == 0 || !matches_cob_id(frame, cob_id)) return false;
  const auto p = frame.payload();
  if (p.size() < 6) {
    ++malformed_;
    return true;
  }
  std::array<std::uint8_t, 6> b{};
  std::copy_n(p.begin(), b.size(), b.begin());
  if (callback_) callback_(TimeEvent{decode_time_of_day(b)});
  return true;
}

}  // namespace canopen::time
