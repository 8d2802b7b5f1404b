// Fastscan and assign-all (CiA 305; facts C.2 and C.4 item 1).
#include <deque>
#include <functional>
#include <optional>

#include "job.hpp"

namespace canopen::lss {

namespace {

// The next part after `p` that is not skipped; nullopt when p is the last.
std::optional<std::uint8_t> next_part(const FastscanRequest& r, int p) {
  for (int q = p + 1; q < 4; ++q)
    if (r.parts[static_cast<std::size_t>(q)] != PartScan::Skip) return static_cast<std::uint8_t>(q);
  return std::nullopt;
}

// One fastscan, as a sequence of step windows. Used by FastscanJob and by
// AssignAllJob; it sends through the job that owns it.
class FastscanEngine {
 public:
  // The protocol step the last request was.
  enum class Step : std::uint8_t {
    Reset,     // BitChecked 80h: does any unconfigured slave listen?
    BitCheck,  // bits [31..bit] of the part: an answer means bit is 0
    Verify,    // the whole part with BitChecked 0: matching slaves move to LSSNext
  };
  using Send = std::function<void(const can::Frame&, Duration, TimePoint)>;
  using SendOnly = std::function<void(const can::Frame&)>;
  using Done = std::function<void(const FastscanResult&, TimePoint)>;

  FastscanEngine(const FastscanRequest& r, Duration step, unsigned max_restarts, Send send, SendOnly send_only,
                 Done done)
      : request_(r), step_(step), max_restarts_(max_restarts), send_(std::move(send)),
        send_only_(std::move(send_only)), done_(std::move(done)) {}

  void start(TimePoint now) { reset(now); }

  void on_answer(const can::Frame& f) {
    if (command(f) == cs::IdentifySlave) answered_ = true;
  }

  // The step window ended: decide from whether anyone answered in it.
  // done_ is the last thing called: the owner may end with it.
  void on_expired(TimePoint now) {
    switch (step_kind_) {
      case Step::Reset:
        if (!answered_) return end(make_error_code(LssError::NoUnconfiguredSlave), now);
        return begin_part(0, now);
      case Step::BitCheck:
        if (!answered_) id_number_ |= 1U << bit_;  // nobody has 0 there: the bit is 1
        if (bit_ == 0) return verify(now);
        --bit_;
        return check_bit(now);
      case Step::Verify: {
        if (!answered_) {
          // A lost answer in a bit step made the value wrong (or the verify's
          // own answer was lost): start again from the reset.
          if (result_.restarts >= max_restarts_) return end(make_error_code(LssError::ScanFailed), now);
          ++result_.restarts;
          // The one found may already be in configuration state (its last
          // verify answer lost): back to waiting, where fastscan is served.
          send_only_(switch_state_global(Mode::Waiting));
          return reset(now);
        }
        result_.identity.set_part(static_cast<Part>(part_), id_number_);
        const auto next = next_part(request_, part_);
        if (!next) return end({}, now);  // the last verify put the slave into configuration state
        return begin_part(*next, now);
      }
    }
  }

  const FastscanResult& result() const { return result_; }
  void fail(std::error_code ec) { result_.error = ec; }

 private:
  void request(const FastscanFields& f, Step s, TimePoint now) {
    step_kind_ = s;
    answered_ = false;
    ++result_.exchanges;
    send_(fastscan(f), step_, now);
  }
  void reset(TimePoint now) {
    result_.identity = {};
    request({0, kFastscanReset, 0, 0}, Step::Reset, now);
  }
  void begin_part(std::uint8_t p, TimePoint now) {
    part_ = p;
    if (request_.parts[p] == PartScan::Match) {
      id_number_ = request_.known.part(static_cast<Part>(p));
      return verify(now);
    }
    id_number_ = 0;
    bit_ = 31;
    check_bit(now);
  }
  void check_bit(TimePoint now) { request({id_number_, bit_, part_, part_}, Step::BitCheck, now); }
  void verify(TimePoint now) {
    // After the last part, LSSNext goes back to the vendor-ID: LSSNext <
    // LSSSub tells the slave the scan is complete.
    const std::uint8_t next = next_part(request_, part_).value_or(0);
    request({id_number_, 0, part_, next}, Step::Verify, now);
  }
  void end(std::error_code ec, TimePoint now) {
    result_.error = ec;
    done_(result_, now);
  }

  FastscanRequest request_;
  Duration step_;
  unsigned max_restarts_;
  Send send_;
  SendOnly send_only_;
  Done done_;
  Step step_kind_ = Step::Reset;
  bool answered_ = false;
  std::uint8_t part_ = 0;
  std::uint8_t bit_ = 31;
  std::uint32_t id_number_ = 0;
  FastscanResult result_;
};

class FastscanJob final : public LssMaster::Job {
 public:
  FastscanJob(LssMaster& m, const FastscanRequest& r, FastscanHandler done)
      : Job(m), request_(r), done_(std::move(done)) {}
  void start(TimePoint now) override {
    engine_.emplace(
        request_, request_.step_timeout.value_or(config().scan_step_timeout), config().fastscan_restarts,
        [this](const can::Frame& f, Duration w, TimePoint t) { send(f, w, t); },
        [this](const can::Frame& f) { send_only(f); },
        [this](const FastscanResult& r, TimePoint t) {
          result_ = r;
          finish(t);
        });
    engine_->start(now);
  }
  void on_answer(const can::Frame& f, TimePoint) override { engine_->on_answer(f); }
  void on_expired(TimePoint now) override { engine_->on_expired(now); }
  void fail(std::error_code ec) override {
    if (engine_) result_ = engine_->result();
    result_.error = ec;
  }
  void notify() override {
    if (done_) done_(result_);
  }

 private:
  FastscanRequest request_;
  FastscanHandler done_;
  std::optional<FastscanEngine> engine_;
  FastscanResult result_;
};

class AssignAllJob final : public LssMaster::Job {
 public:
  // The step the job waits in.
  enum class Step : std::uint8_t { Fastscan, ConfigureNodeId, StoreConfiguration };

  AssignAllJob(LssMaster& m, const AssignAllRequest& r, std::vector<std::uint8_t> ids, AssignAllHandler done)
      : Job(m), request_(r), ids_(std::move(ids)), done_(std::move(done)) {}

  void start(TimePoint now) override {
    send_only(switch_state_global(Mode::Waiting));
    scan(now);
  }
  void on_answer(const can::Frame& f, TimePoint now) override {
    switch (step_) {
      case Step::Fastscan: engines_.back().on_answer(f); return;
      case Step::ConfigureNodeId:
        if (command(f) != cs::ConfigureNodeId) return;
        if (f.data[1] != 0) {
          send_only(switch_state_global(Mode::Waiting));
          return end(slave_error(cs::ConfigureNodeId, f.data[1]), now);
        }
        if (request_.store) {
          step_ = Step::StoreConfiguration;
          send(store_configuration(), config().timeout, now);
          return;
        }
        return next_device(now);
      case Step::StoreConfiguration:
        if (command(f) != cs::StoreConfiguration) return;
        current_.stored = f.data[1] == 0;
        if (!current_.stored) current_.store_error = slave_error(cs::StoreConfiguration, f.data[1]);
        return next_device(now);
    }
  }
  void on_expired(TimePoint now) override {
    switch (step_) {
      case Step::Fastscan: engines_.back().on_expired(now); return;
      case Step::ConfigureNodeId:
        send_only(switch_state_global(Mode::Waiting));
        return end(make_error_code(LssError::Timeout), now);
      case Step::StoreConfiguration:
        current_.store_error = make_error_code(LssError::Timeout);
        return next_device(now);
    }
  }
  void fail(std::error_code ec) override {
    result_.error = ec;
    result_.exchanges = frames_sent();
  }
  void notify() override {
    if (done_) done_(result_);
  }

 private:
  void scan(TimePoint now) {
    step_ = Step::Fastscan;
    FastscanRequest fr;
    // Engines stay alive until the job ends: the one that reported may still
    // be on the call stack when the next one starts.
    engines_.emplace_back(
        fr, request_.step_timeout.value_or(config().scan_step_timeout), config().fastscan_restarts,
        [this](const can::Frame& f, Duration w, TimePoint t) { send(f, w, t); },
        [this](const can::Frame& f) { send_only(f); },
        [this](const FastscanResult& r, TimePoint t) { on_scanned(r, t); });
    engines_.back().start(now);
  }
  void on_scanned(const FastscanResult& r, TimePoint now) {
    if (r.error == make_error_code(LssError::NoUnconfiguredSlave)) return end({}, now);  // all done
    if (r.error) return end(r.error, now);
    if (next_id_ >= ids_.size()) {
      send_only(switch_state_global(Mode::Waiting));
      return end(make_error_code(LssError::NoFreeNodeId), now);
    }
    current_ = Assignment{r.identity, ids_[next_id_], false, {}};
    step_ = Step::ConfigureNodeId;
    send(configure_node_id(current_.node_id), config().timeout, now);
  }
  void next_device(TimePoint now) {
    result_.assigned.push_back(current_);
    ++next_id_;
    // Leaving configuration state, the slave takes its new node-ID and boots.
    send_only(switch_state_global(Mode::Waiting));
    scan(now);
  }
  void end(std::error_code ec, TimePoint now) {
    result_.error = ec;
    result_.exchanges = frames_sent();
    finish(now);
  }

  AssignAllRequest request_;
  std::vector<std::uint8_t> ids_;
  std::size_t next_id_ = 0;
  AssignAllHandler done_;
  Step step_ = Step::Fastscan;
  std::deque<FastscanEngine> engines_;
  Assignment current_;
  AssignAllResult result_;
};

}  // namespace

bool valid_fastscan_parts(const FastscanRequest& r) {
  if (r.parts[0] == PartScan::Skip) return false;  // slaves start every scan at the vendor-ID
  // The last verify must have LSSNext (0) < LSSSub: some part after the vendor-ID.
  return r.parts[1] != PartScan::Skip || r.parts[2] != PartScan::Skip || r.parts[3] != PartScan::Skip;
}

std::unique_ptr<LssMaster::Job> make_fastscan_job(LssMaster& m, const FastscanRequest& r, FastscanHandler done) {
  return std::make_unique<FastscanJob>(m, r, std::move(done));
}

std::unique_ptr<LssMaster::Job> make_assign_all_job(LssMaster& m, const AssignAllRequest& r,
                                                    std::vector<std::uint8_t> ids, AssignAllHandler done) {
  return std::make_unique<AssignAllJob>(m, r, std::move(ids), std::move(done));
}

}  // namespace canopen::lss
