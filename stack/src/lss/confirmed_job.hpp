// A service of one or more request frames answered by one frame of the
// slave in configuration state (private to stack/src/lss).
#pragma once

#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "job.hpp"

namespace canopen::lss {

template <typename T>
class ConfirmedJob final : public LssMaster::Job {
 public:
  // parse: the result of the answer with cs `answer`.
  using Parse = std::function<Result<T>(const can::Frame&)>;
  ConfirmedJob(LssMaster& m, std::vector<can::Frame> requests, std::uint8_t answer, Parse parse, Handler<T> done)
      : Job(m), requests_(std::move(requests)), answer_(answer), parse_(std::move(parse)), done_(std::move(done)) {}

  void start(TimePoint now) override {
    for (std::size_t i = 0; i + 1 < requests_.size(); ++i) send_only(requests_[i]);
    send(requests_.back(), config().timeout, now);
  }
  void on_answer(const can::Frame& f, TimePoint now) override {
    if (command(f) != answer_) return;  // another service's answer: not ours
    result_.emplace(parse_(f));
    finish(now);
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
  std::vector<can::Frame> requests_;
  std::uint8_t answer_;
  Parse parse_;
  Handler<T> done_;
  std::optional<Result<T>> result_;
};

}  // namespace canopen::lss
