// Switch state global and activate bit timing (unconfirmed) and switch
// state selective (CiA 305; facts C.1).
#include <optional>

#include "confirmed_job.hpp"

namespace canopen::lss {

namespace {

// One frame, no answer: done when sent; the handler runs at the next on_time().
class UnconfirmedJob final : public LssMaster::Job {
 public:
  UnconfirmedJob(LssMaster& m, can::Frame frame, Handler<Ack> done)
      : Job(m), frame_(frame), done_(std::move(done)) {}
  void start(TimePoint now) override { send(frame_, Duration::zero(), now); }
  void on_answer(const can::Frame&, TimePoint) override {}
  void on_expired(TimePoint now) override {
    result_.emplace(Ack{});
    finish(now);
  }
  void fail(std::error_code ec) override { result_.emplace(ec); }
  void notify() override {
    if (done_ && result_) done_(std::move(*result_));
  }

 private:
  can::Frame frame_;
  Handler<Ack> done_;
  std::optional<Result<Ack>> result_;
};

}  // namespace

std::unique_ptr<LssMaster::Job> make_unconfirmed_job(LssMaster& m, can::Frame frame, Handler<Ack> done) {
  return std::make_unique<UnconfirmedJob>(m, frame, std::move(done));
}

std::unique_ptr<LssMaster::Job> make_switch_selective_job(LssMaster& m, const Identity& id, Handler<Ack> done) {
  // Four frames (40h..43h); only the slave matching all four answers 44h.
  std::vector<can::Frame> frames;
  for (const Part p : {Part::Vendor, Part::Product, Part::Revision, Part::Serial})
    frames.push_back(switch_state_selective(p, id.part(p)));
  return std::make_unique<ConfirmedJob<Ack>>(
      m, std::move(frames), cs::SwitchSelectiveResponse, [](const can::Frame&) { return Result<Ack>(Ack{}); },
      std::move(done));
}

}  // namespace canopen::lss
