#include "trace/bus_load.hpp"

#include <algorithm>

namespace gateway::trace {

std::uint32_t frame_bits(const canopen::can::Frame& f) {
  const std::uint32_t data = f.remote() ? 0 : 8u * f.len;
  const std::uint32_t stuffed = (f.extended() ? 54u : 34u) + data;  // SOF .. end of CRC
  return (f.extended() ? 67u : 47u) + data + (stuffed - 1) / 4;
}

void BusLoad::advance(Clock::time_point now) {
  const std::int64_t b = now.time_since_epoch() / kBucket;
  if (current_ < 0) {
    current_ = b;
    return;
  }
  if (b <= current_) return;
  // Buckets skipped (no frames) are emptied, at most all of them.
  for (std::int64_t i = current_ + 1; i <= b && i <= current_ + static_cast<std::int64_t>(kBuckets); ++i)
    bits_[slot(i)] = 0;
  current_ = b;
}

void BusLoad::add_bits(std::uint32_t bits, Clock::time_point now) {
  advance(now);
  bits_[slot(current_)] += bits;
}

std::optional<double> BusLoad::percent(std::chrono::milliseconds window, Clock::time_point now) const {
  if (bitrate_ == 0) return std::nullopt;
  const std::int64_t want = std::clamp<std::int64_t>(window / kBucket, 1, kBuckets);
  if (current_ < 0) return 0.0;
  const std::int64_t b = now.time_since_epoch() / kBucket;
  // Buckets b-want+1 .. b: the full ones before and the current, partly elapsed.
  std::uint64_t sum = 0;
  for (std::int64_t i = b - want + 1; i <= b; ++i)
    if (i <= current_ && i > current_ - static_cast<std::int64_t>(kBuckets)) sum += bits_[slot(i)];
  const auto bucket_start = Clock::time_point(b * kBucket);
  auto span = std::chrono::duration<double>((want - 1) * kBucket + (now - bucket_start));
  // Not yet running for the whole window: the time it has run.
  span = std::min(span, std::chrono::duration<double>(std::max<Clock::duration>(now - created_, kBucket)));
  if (span.count() <= 0) return 0.0;
  return 100.0 * static_cast<double>(sum) / (static_cast<double>(bitrate_) * span.count());
}

}  // namespace gateway::trace
