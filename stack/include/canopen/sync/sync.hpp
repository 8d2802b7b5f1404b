// SYNC object (CiA 301 7.2.5): producer and consumer.
//
// Sans-I/O. The caller MUST call on_time(now) when now >= next_deadline()
// (producer), and pass every received frame to on_frame() (consumer; other
// COB-IDs are ignored). A SYNC the gateway produces itself does not come
// back from the bus: to open the consumer's synchronous window for it, pass
// the produced frame to the consumer's on_frame() as well (e.g. from the
// producer's sink).
//
// Thread safety: none; use from one thread. Sinks and callbacks are called
// synchronously and must not call back into the object that called them.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/cob_id.hpp"
#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"

namespace canopen::sync {

// Where the service emits its frames. Called synchronously from the
// service's methods; it must not call back into the service that called it.
using FrameSink = std::function<void(const can::Frame&)>;


// SYNC producer. Configuration from the dictionary: 1005h (COB-ID; bit 30
// set = this device generates SYNC), 1006h (communication cycle period in
// us; 0 = no SYNC), 1019h (counter overflow value; 0 = frames carry no
// counter, 2..240 = a counter byte running 1..overflow, then 1 again).
//
// The configuration is read at construction and by reconfigure(); the
// caller MUST call reconfigure(now) after any write to 1005h, 1006h or
// 1019h. Frames are sent at start + k x period exactly (no drift); when
// on_time() is called so late that periods were missed, one SYNC is sent and
// the missed ones are skipped.
class SyncProducer {
 public:
  enum class State : std::uint8_t { Off, Running };

  // The dictionary must outlive the producer. `now` starts the first period.
  SyncProducer(const od::ObjectDictionary& dictionary, FrameSink sink, TimePoint now);

  // Re-reads 1005h/1006h/1019h. When running, the first SYNC goes out one
  // period after `now` and the counter restarts at 1 (7.5.2.6: "SYNC starts
  // within one communication cycle period after the update").
  void reconfigure(TimePoint now);
  // The counter restarts at 1 (NMT boot-up, or stopped -> pre-operational).
  void reset_counter() { counter_ = 1; }

  State state() const { return state_; }
  Duration period() const { return period_; }
  // The counter the next SYNC carries; nullopt when frames carry none.
  std::optional<std::uint8_t> next_counter() const;

  // TimePoint::max() when off.
  TimePoint next_deadline() const { return state_ == State::Running ? next_ : TimePoint::max(); }
  void on_time(TimePoint now);

 private:
  const od::ObjectDictionary& od_;
  FrameSink sink_;
  State state_ = State::Off;
  std::uint32_t cob_id_ = 0;
  Duration period_{};
  std::uint8_t overflow_ = 0;
  std::uint8_t counter_ = 1;
  TimePoint next_{};
};

// SYNC consumer. Reads 1005h (COB-ID) and 1007h (synchronous window length
// in us; 0 = no window) from the dictionary at each call, so SDO writes take
// effect at once. Emits a SyncEvent per SYNC received: frames of 0 data
// bytes carry no counter, of 1 byte a counter. Frames of any other length
// are not SYNCs the standard allows (8240h "unexpected SYNC data length"):
// they are counted in bad_length_count(), produce no event and do not open
// a window; raising the EMCY is the caller's choice.
class SyncConsumer {
 public:
  using Callback = std::function<void(const SyncEvent&)>;

  // The dictionary must outlive the consumer.
  SyncConsumer(const od::ObjectDictionary& dictionary, Callback callback);

  // Returns false when the frame is not on the SYNC COB-ID.
  bool on_frame(const can::Frame& frame, TimePoint now);

  // Whether synchronous PDOs may be processed at `now`: true when 1007h is
  // 0; otherwise true only in [last SYNC, last SYNC + window length). False
  // before the first SYNC (there is no window to be in).
  bool in_sync_window(TimePoint now) const;

  std::optional<TimePoint> last_sync() const { return last_; }
  std::optional<std::uint8_t> last_counter() const { return last_counter_; }
  std::uint64_t bad_length_count() const { return bad_length_; }

  // No timers of its own.
  TimePoint next_deadline() const { return TimePoint::max(); }
  void on_time(TimePoint /*now*/) {}

 private:
  const od::ObjectDictionary& od_;
  Callback callback_;
  std::optional<TimePoint> last_;
  std::optional<std::uint8_t> last_counter_;
  std::uint64_t bad_length_ = 0;
};

}  // namespace canopen::sync
