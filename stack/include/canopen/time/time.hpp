// TIME object (CiA 301 7.2.6): producer and consumer of the 6-byte
// TIME_OF_DAY (ms after midnight, 28 bits LE in 4 bytes; days since
// 1984-01-01, 16 bits LE).
//
// Both read 1012h from the dictionary at each call, so SDO writes take
// effect at once: bit 30 set = this device produces TIME, bit 31 set = it
// consumes TIME, bits 0..28 the CAN-ID (bit 29: 29-bit CAN-ID).
//
// Sans-I/O: no wall clock is read here. The caller passes Unix time in
// milliseconds (UTC) to the producer, and MUST call on_time() when
// now >= next_deadline() if a period is configured; the consumer MUST be
// given every received frame (other COB-IDs are ignored).
//
// Thread safety: none; use from one thread. Sinks and callbacks are called
// synchronously and must not call back into the object that called them.
#pragma once

#include <array>
#include <cstdint>
#include <functional>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/cob_id.hpp"
#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/types.hpp"

namespace canopen::time {

// Where the service emits its frames. Called synchronously from the
// service's methods; it must not call back into the service that called it.
using FrameSink = std::function<void(const can::Frame&)>;


std::array<std::uint8_t, 6> encode_time_of_day(const TimeOfDay& t);
// Bits 28..31 of the ms field are reserved and ignored.
TimeOfDay decode_time_of_day(const std::array<std::uint8_t, 6>& bytes);

class TimeProducer {
 public:
  // The dictionary must outlive the producer. `period` 0: TIME is sent only
  // by send(); otherwise also every period from `now` (the standard sets no
  // rate; this is the gateway's choice).
  TimeProducer(const od::ObjectDictionary& dictionary, FrameSink sink, Duration period = Duration::zero(),
               TimePoint now = TimePoint{});

  // Sends `unix_ms` as a TIME frame. Returns false (nothing sent) when
  // 1012h bit 30 is clear.
  bool send(std::int64_t unix_ms);

  // TimePoint::max() without a period.
  TimePoint next_deadline() const;
  // When due, sends `unix_ms` (the wall time at `now`, from the caller) and
  // schedules the next one a period later on the same grid.
  void on_time(TimePoint now, std::int64_t unix_ms);

 private:
  const od::ObjectDictionary& od_;
  FrameSink sink_;
  Duration period_;
  TimePoint next_;
};

// Emits a TimeEvent per TIME frame of 6 bytes or more received while 1012h
// bit 31 is set; shorter frames are counted in malformed_count() only.
class TimeConsumer {
 public:
  using Callback = std::function<void(const TimeEvent&)>;

  // The dictionary must outlive the consumer.
  TimeConsumer(const od::ObjectDictionary& dictionary, Callback callback);

  // Returns false when the frame is not a TIME this device consumes.
  bool on_frame(const can::Frame& frame, TimePoint now);
  std::uint64_t malformed_count() const { return malformed_; }

  TimePoint next_deadline() const { return TimePoint::max(); }
  void on_time(TimePoint /*now*/) {}

 private:
  const od::ObjectDictionary& od_;
  Callback callback_;
  std::uint64_t malformed_ = 0;
};

}  // namespace canopen::time
