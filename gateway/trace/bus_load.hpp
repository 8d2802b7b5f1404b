// Bus load of one network: the share of the bus's bit time the frames on
// it took, over sliding windows of 1 s and 10 s.
//
// Bits per frame (ISO 11898-1 classic CAN frame format): a base frame
// (11-bit id) is SOF 1 + id 11 + RTR 1 + IDE 1 + r0 1 + DLC 4 + data 8n +
// CRC 15 + CRC delimiter 1 + ACK slot and delimiter 2 + EOF 7 + interframe
// space 3 = 47 + 8n bits; an extended frame (29-bit id) adds SRR, the 18
// id bits and r1: 67 + 8n. Stuff bits (one after five equal bits, SOF to
// the end of the CRC: 34 + 8n bits base, 54 + 8n extended) are counted at
// their worst case, floor((bits - 1) / 4), so the load is an upper bound
// (real data stuffs less). A remote frame carries no data bits whatever
// its DLC. CAN FD frames are counted with the same layout and their payload
// at the nominal bit rate (an upper bound again; the data phase rate is not
// configured).
//
// Thread safety: none; one meter per network, used on the io thread.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>

#include "canopen/can/frame.hpp"

namespace gateway::trace {

// The bits `f` occupies on the bus, worst-case stuffing, interframe space included.
std::uint32_t frame_bits(const canopen::can::Frame& f);

class BusLoad {
 public:
  using Clock = std::chrono::steady_clock;

  // `bitrate` in bit/s; 0 = unknown (percent() is then nullopt). Until a
  // window has passed since `created`, its percent is over the time since.
  BusLoad(std::uint32_t bitrate, Clock::time_point created) : bitrate_(bitrate), created_(created) {}

  void add(const canopen::can::Frame& f, Clock::time_point now) { add_bits(frame_bits(f), now); }
  void add_bits(std::uint32_t bits, Clock::time_point now);

  // Percent of the bit time over the last `window` (1 s to 10 s, in steps
  // of the 100 ms buckets) before `now`; nullopt without a bit rate. Over
  // 100 only when frames were counted that the bus could not have carried
  // (worst-case stuffing overestimates a fully loaded bus).
  std::optional<double> percent(std::chrono::milliseconds window, Clock::time_point now) const;
  std::uint32_t bitrate() const { return bitrate_; }

 private:
  static constexpr std::chrono::milliseconds kBucket{100};
  static constexpr std::size_t kBuckets = 100;  // 10 s
  void advance(Clock::time_point now);
  // The slot of bits_ for a bucket number. percent() asks for buckets before
  // the clock's epoch (negative) when the steady clock is young, as in UML
  // right after boot: a floor modulo keeps them in range and apart from the
  // buckets that hold frames.
  static std::size_t slot(std::int64_t bucket) {
    constexpr auto n = static_cast<std::int64_t>(kBuckets);
    return static_cast<std::size_t>((bucket % n + n) % n);
  }

  std::uint32_t bitrate_;
  std::array<std::uint64_t, kBuckets> bits_{};
  std::int64_t current_ = -1;  // bucket number (steady time / 100 ms) of bits_[current_ % kBuckets]
  Clock::time_point created_;
};

}  // namespace gateway::trace
