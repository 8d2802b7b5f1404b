// The running service of an LssMaster (private to stack/src/lss): sends
// through the master, waits for answers or the end of its window, ends by
// storing its result and calling finish(); notify() then calls the
// caller's handler, outside the job's own code.
#pragma once

#include <memory>

#include "canopen/lss/master.hpp"

namespace canopen::lss {

class LssMaster::Job {
 public:
  explicit Job(LssMaster& master) : master_(master) {}
  virtual ~Job() = default;
  Job(const Job&) = delete;
  Job& operator=(const Job&) = delete;

  virtual void start(TimePoint now) = 0;
  // A well-formed slave frame (7E4h) while this job runs.
  virtual void on_answer(const can::Frame& f, TimePoint now) = 0;
  // The timeout or window of the last send() ended.
  virtual void on_expired(TimePoint now) = 0;
  // Ends without running (cancelled, or dropped from the queue): store ec
  // as the result; notify() follows.
  virtual void fail(std::error_code ec) = 0;
  // Calls the caller's handler with the stored result.
  virtual void notify() = 0;

 protected:
  // Sends f and waits `window` (zero: on_expired at the next on_time()).
  void send(const can::Frame& f, Duration window, TimePoint now) {
    send_only(f);
    master_.deadline_ = now + window;
  }
  // Sends f without waiting for anything.
  void send_only(const can::Frame& f) {
    ++frames_sent_;
    if (master_.sink_) master_.sink_(f);
  }
  // The result is stored: the master calls notify() and starts the next service.
  void finish(TimePoint now) { master_.finish_current(now); }
  const MasterConfig& config() const { return master_.config_; }
  std::size_t frames_sent() const { return frames_sent_; }

 private:
  LssMaster& master_;
  std::size_t frames_sent_ = 0;
};

// Makers of each service group's jobs (master_switch.cpp,
// master_configure.cpp, master_identify.cpp, master_fastscan.cpp).
std::unique_ptr<LssMaster::Job> make_unconfirmed_job(LssMaster& m, can::Frame frame, Handler<Ack> done);
std::unique_ptr<LssMaster::Job> make_switch_selective_job(LssMaster& m, const Identity& id, Handler<Ack> done);
std::unique_ptr<LssMaster::Job> make_configure_job(LssMaster& m, can::Frame request, Handler<Ack> done);
std::unique_ptr<LssMaster::Job> make_inquire_job(LssMaster& m, Part part, Handler<std::uint32_t> done);
std::unique_ptr<LssMaster::Job> make_inquire_address_job(LssMaster& m, Handler<Identity> done);
std::unique_ptr<LssMaster::Job> make_inquire_node_id_job(LssMaster& m, Handler<std::uint8_t> done);
std::unique_ptr<LssMaster::Job> make_identify_remote_job(LssMaster& m, const IdentityRange& r, Handler<bool> done);
std::unique_ptr<LssMaster::Job> make_identify_non_configured_job(LssMaster& m, Handler<bool> done);
std::unique_ptr<LssMaster::Job> make_fastscan_job(LssMaster& m, const FastscanRequest& r, FastscanHandler done);
std::unique_ptr<LssMaster::Job> make_assign_all_job(LssMaster& m, const AssignAllRequest& r,
                                                    std::vector<std::uint8_t> ids, AssignAllHandler done);
// Whether the protocol can do these part choices (see PartScan).
bool valid_fastscan_parts(const FastscanRequest& r);

}  // namespace canopen::lss
