// Binds sans-I/O protocol services to a can::Channel and the io_context's
// steady clock: every received frame is offered to every service, and one
// steady_timer fires at the earliest deadline any service asks for.
//
// A service is anything with
//   void on_frame(const can::Frame&, TimePoint now);
//   void on_time(TimePoint now);
//   TimePoint next_deadline() const;   // TimePoint::max() when idle
// and, optionally, canopen::DeadlineSource's on_deadline_change(): such a
// service reports itself when a call from outside (submit an SDO request,
// raise an EMCY, start ...) moves its deadline, and the timer follows with
// nothing more to do for the caller. Calls made while the driver feeds the
// services (from their callbacks) need no report: the driver re-reads every
// deadline after each batch, timer and local delivery.
//
// Thread safety: io_context thread only. Services must outlive the driver
// or be removed first.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "canopen/can/channel.hpp"
#include "canopen/clock.hpp"

namespace canopen::socketcan {

class ServiceDriver {
 public:
  ServiceDriver(boost::asio::io_context& io, can::Channel& channel);
  ~ServiceDriver();
  ServiceDriver(const ServiceDriver&) = delete;
  ServiceDriver& operator=(const ServiceDriver&) = delete;

  template <typename Service>
  void add(Service& s) {
    Entry e{&s, [&s](const can::Frame& f, TimePoint now) { s.on_frame(f, now); },
            [&s](TimePoint now) { s.on_time(now); }, [&s] { return s.next_deadline(); }, nullptr};
    if constexpr (requires { s.on_deadline_change(nullptr); }) {
      s.on_deadline_change([this](TimePoint next) { deadline_moved(next); });
      e.detach = [&s] { s.on_deadline_change(nullptr); };
    }
    entries_.push_back(std::move(e));
    rearm();
  }
  // The service is fed no more (and its deadline reports are no longer heard).
  void remove(const void* service);

  // Also called with every received batch, after the services (e.g. logging).
  void on_frames(can::Channel::FrameHandler tap) { tap_ = std::move(tap); }

  // A frame this process sent that its own services must also see, as if
  // received (a socket does not receive its own frames): e.g. an NMT
  // command to all nodes reaches the gateway's own NMT slave, a SYNC the
  // gateway produces drives its synchronous PDOs. Delivered later from the
  // io_context (never re-entrantly), stamped with the wall time, to every
  // service or only to `only` (a service added before), so the sender need
  // not see its own frame.
  void deliver_locally(const can::Frame& f, const void* only = nullptr);

 private:
  struct Entry {
    const void* id;
    std::function<void(const can::Frame&, TimePoint)> on_frame;
    std::function<void(TimePoint)> on_time;
    std::function<TimePoint()> next_deadline;
    std::function<void()> detach;  // removes the deadline observer, if any
  };
  // Arms the timer for the earliest deadline of all services.
  void rearm();
  // A service's report: earlier than the timer is armed for, it re-arms.
  void deadline_moved(TimePoint next);
  void arm(TimePoint at);
  void on_timer();
  void drain_local();

  can::Channel& channel_;
  boost::asio::steady_timer timer_;
  std::vector<Entry> entries_;
  can::Channel::FrameHandler tap_;
  TimePoint armed_for_ = TimePoint::max();
  std::vector<std::pair<can::Frame, const void*>> local_;
  bool drain_posted_ = false;
  bool feeding_ = false;  // inside a batch, timer or local delivery: rearm() follows
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace canopen::socketcan
