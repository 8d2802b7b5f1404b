// Identify remote slave and identify non-configured remote slave (CiA 305;
// facts C.1): any number of slaves may answer, so the whole window is
// waited for and the answer is "did anyone answer".
#include <optional>

#include "job.hpp"

namespace canopen::lss {

namespace {

class IdentifyJob final : public LssMaster::Job {
 public:
  IdentifyJob(LssMaster& m, std::vector<can::Frame> requests, std::uint8_t answer, Handler<bool> done)
      : Job(m), requests_(std::move(requests)), answer_(answer), done_(std::move(done)) {}
  void start(TimePoint now) override {
    for (std::size_t i = 0; i + 1 < requests_.size(); ++i) send_only(requests_[i]);
    send(requests_.back(), config().scan_step_timeout, now);
  }
  void on_answer(const can::Frame& f, TimePoint) override {
    if (command(f) == answer_) answered_ = true;
  }
  void on_expired(TimePoint now) override {
    result_.emplace(answered_);
    finish(now);
  }
  void fail(std::error_code ec) override { result_.emplace(ec); }
  void notify() override {
    if (done_ && result_) done_(std::move(*result_));
  }

 private:
  std::vector<can::Frame> requests_;
  std::uint8_t answer_;
  Handler<bool> done_;
  bool answered_ = false;
  std::optional<Result<bool>> result_;
};

}  // namespace

std::unique_ptr<LssMaster::Job> make_identify_remote_job(LssMaster& m, const IdentityRange& r, Handler<bool> done) {
  std::vector<can::Frame> frames{
      identify_remote_slave(cs::IdentifyVendor, r.vendor_id),
      identify_remote_slave(cs::IdentifyProduct, r.product_code),
      identify_remote_slave(cs::IdentifyRevisionLow, r.revision_low),
      identify_remote_slave(cs::IdentifyRevisionHigh, r.revision_high),
      identify_remote_slave(cs::IdentifySerialLow, r.serial_low),
      identify_remote_slave(cs::IdentifySerialHigh, r.serial_high),
  };
  return std::make_unique<IdentifyJob>(m, std::move(frames), cs::IdentifySlave, std::move(done));
}

std::unique_ptr<LssMaster::Job> make_identify_non_configured_job(LssMaster& m, Handler<bool> done) {
  return std::make_unique<IdentifyJob>(m, std::vector<can::Frame>{identify_non_configured()},
                                       cs::IdentifyNonConfiguredSlave, std::move(done));
}

}  // namespace canopen::lss
