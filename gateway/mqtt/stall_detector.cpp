#include "mqtt/stall_detector.hpp"

namespace gateway::mqtt {

void StallDetector::reset(canopen::TimePoint now) {
  waiting_since_ = now;
  was_in_flight_ = false;
  idle_since_.reset();
}

void StallDetector::progress(canopen::TimePoint now) { waiting_since_ = now; }

StallDetector::Verdict StallDetector::check(canopen::TimePoint now, const Observation& o) {
  if (o.in_flight > 0) {
    idle_since_.reset();
    if (!was_in_flight_) {
      // Waiting starts now, not at the last acknowledgement before an idle spell.
      was_in_flight_ = true;
      waiting_since_ = now;
      return Verdict::Ok;
    }
    if (now - waiting_since_ < opts_.progress_timeout) return Verdict::Ok;
    reset(now);
    return Verdict::NoProgress;
  }
  was_in_flight_ = false;
  if (!o.unsent || o.send_scheduled) {
    idle_since_.reset();
    return Verdict::Ok;
  }
  if (!idle_since_) {
    idle_since_ = now;
    return Verdict::Ok;
  }
  if (now - *idle_since_ < opts_.idle_timeout) return Verdict::Ok;
  reset(now);
  return Verdict::Idle;
}

}  // namespace gateway::mqtt
