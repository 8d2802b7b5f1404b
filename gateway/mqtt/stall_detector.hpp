// Decides when the publisher's delivery is stuck, from what the caller
// observes and the current time (sans-I/O: no clock of its own, so tests
// drive it with canopen::FakeClock).
//
// Two kinds of stall, each ending in one verdict after which the caller
// resends from the oldest unacked message (as after a reconnect):
//  - NoProgress: messages are in flight and no acknowledgement has come for
//    progress_timeout, counted from the later of the last progress and the
//    moment something went in flight after an idle spell (so the first
//    message after an hour of silence is not taken for a stall).
//  - Idle: messages wait to be sent, none is in flight and no send is
//    scheduled, continuously for idle_timeout. Messages that wait only
//    because a send is scheduled (a publish whose pump handler has not run
//    yet, or output waiting for the socket) are normal: a timer that runs
//    between a publish and its send must not call that a stall.
// After a verdict the detector starts over (the next one needs a new
// full timeout).
//
// Thread safety: none; one owner thread.
#pragma once

#include <chrono>
#include <cstddef>
#include <optional>

#include "canopen/clock.hpp"

namespace gateway::mqtt {

class StallDetector {
 public:
  struct Options {
    std::chrono::milliseconds progress_timeout{30'000};
    std::chrono::milliseconds idle_timeout{5'000};
  };
  // What the caller sees at a check.
  struct Observation {
    std::size_t in_flight = 0;    // sent, acknowledgement (or socket write) due
    bool unsent = false;          // messages waiting to be handed to the connection
    bool send_scheduled = false;  // a send is already on its way (pump posted, socket busy)
  };
  enum class Verdict { Ok, NoProgress, Idle };

  StallDetector() : StallDetector(Options{}) {}
  explicit StallDetector(Options o) : opts_(o) {}

  // A (re)connect or a resend: start over.
  void reset(canopen::TimePoint now);
  // An acknowledgement came (PUBACK, or QoS 0 output reached the kernel).
  void progress(canopen::TimePoint now);
  // Called periodically (the publisher's sync timer).
  Verdict check(canopen::TimePoint now, const Observation& o);

 private:
  Options opts_;
  canopen::TimePoint waiting_since_{};             // in flight: last progress or start of waiting
  bool was_in_flight_ = false;
  std::optional<canopen::TimePoint> idle_since_;  // unsent, nothing in flight, nothing scheduled
};

}  // namespace gateway::mqtt
