// LssMaster: the queue and the one running service; the services
// themselves are in master_switch/_configure/_identify/_fastscan.cpp.
#include "canopen/lss/master.hpp"

#include <algorithm>

#include "job.hpp"

namespace canopen::lss {

namespace {
std::error_code invalid() { return std::make_error_code(std::errc::invalid_argument); }
bool valid_node_id(std::uint8_t id) { return id >= 1 && id <= 127; }
}  // namespace

LssMaster::LssMaster(MasterConfig config, FrameSink sink) : config_(config), sink_(std::move(sink)) {}
LssMaster::~LssMaster() = default;

std::error_code LssMaster::submit(std::unique_ptr<Job> job, TimePoint now) {
  Report<LssMaster> r(*this);
  if (!in_call_) retired_.reset();
  if (current_ && queue_.size() >= config_.queue_limit) return make_error_code(LssError::QueueFull);
  queue_.push_back(std::move(job));
  start_next(now);
  return {};
}

void LssMaster::start_next(TimePoint now) {
  if (current_ || queue_.empty()) return;
  current_ = std::move(queue_.front());
  queue_.pop_front();
  deadline_ = TimePoint::max();
  current_->start(now);
}

void LssMaster::finish_current(TimePoint now) {
  // The job is still on the call stack (it called finish()): it is kept
  // alive until the next call from outside.
  retired_ = std::move(current_);
  deadline_ = TimePoint::max();
  if (retired_) retired_->notify();  // may submit: the new service queues or starts
  start_next(now);
}

void LssMaster::cancel_all(TimePoint now) {
  Report<LssMaster> r(*this);
  std::deque<std::unique_ptr<Job>> ended;
  if (current_) ended.push_back(std::move(current_));
  for (auto& j : queue_) ended.push_back(std::move(j));
  queue_.clear();
  deadline_ = TimePoint::max();
  for (auto& j : ended) {
    j->fail(make_error_code(LssError::Cancelled));
    j->notify();
  }
  start_next(now);  // handlers may have submitted new services
}

bool LssMaster::on_frame(const can::Frame& frame, TimePoint now) {
  if (!is_slave_frame(frame)) return false;
  retired_.reset();
  const CallScope scope(in_call_);
  // Answers outside a service (late, or another master's) change nothing.
  if (current_) current_->on_answer(frame, now);
  return true;
}

void LssMaster::on_time(TimePoint now) {
  retired_.reset();
  if (!current_ || now < deadline_) return;
  const CallScope scope(in_call_);
  deadline_ = TimePoint::max();
  current_->on_expired(now);
}

TimePoint LssMaster::next_deadline() const { return current_ ? deadline_ : TimePoint::max(); }

bool LssMaster::busy() const { return static_cast<bool>(current_); }
std::size_t LssMaster::pending() const { return queue_.size() + (current_ ? 1 : 0); }

std::error_code LssMaster::switch_state_global(Mode mode, Handler<Ack> done, TimePoint now) {
  if (mode != Mode::Waiting && mode != Mode::Configuration) return invalid();
  return submit(make_unconfirmed_job(*this, lss::switch_state_global(mode), std::move(done)), now);
}

std::error_code LssMaster::switch_state_selective(const Identity& id, Handler<Ack> done, TimePoint now) {
  return submit(make_switch_selective_job(*this, id, std::move(done)), now);
}

std::error_code LssMaster::configure_node_id(std::uint8_t node_id, Handler<Ack> done, TimePoint now) {
  if (!valid_node_id(node_id) && node_id != kUnconfiguredNodeId) return invalid();
  return submit(make_configure_job(*this, lss::configure_node_id(node_id), std::move(done)), now);
}

std::error_code LssMaster::configure_bit_timing(std::uint8_t table, std::uint8_t index, Handler<Ack> done,
                                                TimePoint now) {
  return submit(make_configure_job(*this, lss::configure_bit_timing(table, index), std::move(done)), now);
}

std::error_code LssMaster::activate_bit_timing(std::uint16_t switch_delay_ms, Handler<Ack> done, TimePoint now) {
  return submit(make_unconfirmed_job(*this, lss::activate_bit_timing(switch_delay_ms), std::move(done)), now);
}

std::error_code LssMaster::store_configuration(Handler<Ack> done, TimePoint now) {
  return submit(make_configure_job(*this, lss::store_configuration(), std::move(done)), now);
}

std::error_code LssMaster::inquire_identity(Part part, Handler<std::uint32_t> done, TimePoint now) {
  if (static_cast<std::uint8_t>(part) > static_cast<std::uint8_t>(Part::Serial)) return invalid();
  return submit(make_inquire_job(*this, part, std::move(done)), now);
}

std::error_code LssMaster::inquire_address(Handler<Identity> done, TimePoint now) {
  return submit(make_inquire_address_job(*this, std::move(done)), now);
}

std::error_code LssMaster::inquire_node_id(Handler<std::uint8_t> done, TimePoint now) {
  return submit(make_inquire_node_id_job(*this, std::move(done)), now);
}

std::error_code LssMaster::identify_remote_slave(const IdentityRange& range, Handler<bool> done, TimePoint now) {
  if (range.revision_low > range.revision_high || range.serial_low > range.serial_high) return invalid();
  return submit(make_identify_remote_job(*this, range, std::move(done)), now);
}

std::error_code LssMaster::identify_non_configured(Handler<bool> done, TimePoint now) {
  return submit(make_identify_non_configured_job(*this, std::move(done)), now);
}

std::error_code LssMaster::fastscan(const FastscanRequest& request, FastscanHandler done, TimePoint now) {
  if (!valid_fastscan_parts(request)) return invalid();
  return submit(make_fastscan_job(*this, request, std::move(done)), now);
}

std::error_code LssMaster::assign_all(const AssignAllRequest& request, AssignAllHandler done, TimePoint now) {
  std::vector<std::uint8_t> ids;
  if (!request.node_ids.empty()) {
    if (!std::all_of(request.node_ids.begin(), request.node_ids.end(), valid_node_id)) return invalid();
    ids = request.node_ids;
  } else {
    if (!valid_node_id(request.first_node_id)) return invalid();
    for (int id = request.first_node_id; id <= 127; ++id) {
      const auto n = static_cast<std::uint8_t>(id);
      if (std::find(request.in_use.begin(), request.in_use.end(), n) == request.in_use.end()) ids.push_back(n);
    }
  }
  return submit(make_assign_all_job(*this, request, std::move(ids), std::move(done)), now);
}

}  // namespace canopen::lss
