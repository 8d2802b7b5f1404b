// Configure node-ID, configure bit timing, store configuration and the
// inquire services, all answered by the one slave in configuration state
// (CiA 305; facts C.1).
#include <array>
#include <optional>

#include "confirmed_job.hpp"

namespace canopen::lss {

namespace {

// Byte 1 of a configure answer: 0 ok, else the CiA 305 error (byte 2 holds
// the manufacturer's own code when byte 1 is FFh).
Result<Ack> configure_result(const can::Frame& f) {
  const std::uint8_t error = f.data[1];
  if (error == 0) return Ack{};
  std::string detail;
  if (error == 0xFF) detail = "manufacturer-specific error code " + std::to_string(f.data[2]);
  return Error{slave_error(command(f), error), detail};
}

// Asks the four parts of the address in turn: four confirmed exchanges.
class InquireAddressJob final : public LssMaster::Job {
 public:
  InquireAddressJob(LssMaster& m, Handler<Identity> done) : Job(m), done_(std::move(done)) {}
  void start(TimePoint now) override { ask(now); }
  void on_answer(const can::Frame& f, TimePoint now) override {
    const auto part = static_cast<Part>(next_);
    if (command(f) != inquire_identity(part).data[0]) return;
    identity_.set_part(part, u32(f));
    if (++next_ == 4) {
      result_.emplace(identity_);
      finish(now);
      return;
    }
    ask(now);
  }
  void on_expired(TimePoint now) override {
    result_.emplace(make_error_code(LssError::Timeout));
    finish(now);
  }
  void fail(std::error_code ec) override { result_.emplace(ec); }
  void notify() override {
    if (done_ && result_) done_(std::move(*result_));
  }

 private:
  void ask(TimePoint now) { send(inquire_identity(static_cast<Part>(next_)), config().timeout, now); }

  Handler<Identity> done_;
  Identity identity_;
  int next_ = 0;
  std::optional<Result<Identity>> result_;
};

}  // namespace

std::unique_ptr<LssMaster::Job> make_configure_job(LssMaster& m, can::Frame request, Handler<Ack> done) {
  const std::uint8_t answer = command(request);  // 11h, 13h, 17h: answered with the same cs
  return std::make_unique<ConfirmedJob<Ack>>(m, std::vector<can::Frame>{request}, answer, configure_result,
                                             std::move(done));
}

std::unique_ptr<LssMaster::Job> make_inquire_job(LssMaster& m, Part part, Handler<std::uint32_t> done) {
  const can::Frame request = inquire_identity(part);
  return std::make_unique<ConfirmedJob<std::uint32_t>>(
      m, std::vector<can::Frame>{request}, command(request),
      [](const can::Frame& f) { return Result<std::uint32_t>(u32(f)); }, std::move(done));
}

std::unique_ptr<LssMaster::Job> make_inquire_address_job(LssMaster& m, Handler<Identity> done) {
  return std::make_unique<InquireAddressJob>(m, std::move(done));
}

std::unique_ptr<LssMaster::Job> make_inquire_node_id_job(LssMaster& m, Handler<std::uint8_t> done) {
  return std::make_unique<ConfirmedJob<std::uint8_t>>(
      m, std::vector<can::Frame>{inquire_node_id()}, cs::InquireNodeId,
      [](const can::Frame& f) { return Result<std::uint8_t>(f.data[1]); }, std::move(done));
}

}  // namespace canopen::lss
