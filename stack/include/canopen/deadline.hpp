// "My next deadline may have moved": how a sans-I/O service tells whoever
// runs its timer that a call from outside (submit an SDO request, send an
// NMT command, raise an EMCY, set RPDO values, start, reconfigure ...) made
// it need on_time() sooner, in the style of Lely's "next function". The
// driver never has to be told so by the caller.
//
// A service derives from DeadlineSource and reports at the end of each
// public method that may move its deadline: a `Report<Self> r(*this);` at
// the top of the method reports next_deadline() on every return (nothing is
// computed when nobody listens). The deadline is passed along, so the
// observer never calls back into the service in the middle of a call.
//
// Thread safety: as the service's; the observer runs synchronously inside
// the service's method.
#pragma once

#include <functional>
#include <utility>

#include "canopen/clock.hpp"

namespace canopen {

class DeadlineSource {
 public:
  // `next` is the service's next_deadline() after the call (TimePoint::min():
  // "call on_time() as soon as possible"). It may be later than before (a
  // transfer cancelled); an observer that armed a timer for an earlier time
  // just finds nothing due then.
  using Observer = std::function<void(TimePoint next)>;

  // One observer (the driver); nullptr removes it. It MUST NOT call into the
  // service that reports.
  void on_deadline_change(Observer observer) { observer_ = std::move(observer); }

 protected:
  DeadlineSource() = default;
  ~DeadlineSource() = default;
  DeadlineSource(const DeadlineSource&) = default;
  DeadlineSource& operator=(const DeadlineSource&) = default;

  bool deadline_observed() const { return static_cast<bool>(observer_); }
  void report_deadline(TimePoint next) const {
    if (observer_) observer_(next);
  }

  // Reports self.next_deadline() when the scope ends.
  template <typename Self>
  class Report {
   public:
    explicit Report(const Self& self) : self_(self) {}
    ~Report() {
      const DeadlineSource& source = self_;
      if (source.observer_) source.observer_(self_.next_deadline());
    }
    Report(const Report&) = delete;
    Report& operator=(const Report&) = delete;

   private:
    const Self& self_;
  };

 private:
  Observer observer_;
};

}  // namespace canopen
