#include "canopen/pdo/config_reader.hpp"

#include <utility>

#include "canopen/od/object_dictionary.hpp"
#include "canopen/sdo/abort.hpp"

namespace canopen::pdo {

namespace {

std::string label(PdoKey k) {
  return (k.direction == Direction::Transmit ? "TPDO" : "RPDO") + std::to_string(k.number);
}

}  // namespace

std::size_t PdoReadReport::read_count() const {
  std::size_t n = 0;
  for (const auto& p : pdos) n += p.parameters ? 1 : 0;
  return n;
}

std::string PdoReadReport::summary() const {
  std::string s = std::to_string(read_count()) + " of " + std::to_string(pdos.size()) + " PDOs read from the device";
  if (cancelled) s += " (cancelled)";
  for (const auto& p : pdos) {
    if (p.parameters || p.error == std::errc::operation_canceled) continue;
    s += "; " + p.detail;
    if (stopped) break;  // the rest failed the same way
  }
  return s;
}

PdoConfigReader::PdoConfigReader(sdo::SdoClient& client, TimeSource now) : client_(client), now_(std::move(now)) {}

PdoConfigReader::~PdoConfigReader() {
  std::vector<sdo::RequestId> running;
  for (const auto& [node, run] : runs_)
    if (run.request) running.push_back(*run.request);
  runs_.clear();  // the cancelled transfers' handlers find nothing to do
  for (const auto id : running) client_.cancel(id, now_());
}

std::error_code PdoConfigReader::read(std::uint8_t node, std::vector<PdoReadPlan> plan, Done done, TimePoint now) {
  if (node < 1 || node > 127) return std::make_error_code(std::errc::invalid_argument);
  if (auto it = runs_.find(node); it != runs_.end()) {
    it->second.waiters.push_back(std::move(done));
    return {};
  }
  if (plan.empty()) {
    PdoReadReport empty;
    empty.node = node;
    if (done) done(empty);
    return {};
  }
  Run run;
  run.generation = ++generation_;
  run.plan = std::move(plan);
  run.report.node = node;
  run.waiters.push_back(std::move(done));
  begin_pdo(run);
  Run& r = runs_[node] = std::move(run);
  if (auto ec = submit(node, r, now)) {
    runs_.erase(node);
    return ec;
  }
  return {};
}

void PdoConfigReader::begin_pdo(Run& run) {
  const PdoReadPlan& p = run.plan[run.pdo];
  const std::uint16_t comm = comm_index(p.key.direction, p.key.number);
  run.ops.clear();
  run.next = 0;
  run.current = PdoParameters{};
  run.ops.push_back({comm, 1, false});
  run.ops.push_back({comm, 2, false});
  for (const auto sub : p.optional_comm_subs)
    if (sub == 3 || sub == 5 || sub == 6) run.ops.push_back({comm, sub, true});
  run.ops.push_back({mapping_index(p.key.direction, p.key.number), 0, false});
}

std::error_code PdoConfigReader::submit(std::uint8_t node, Run& run, TimePoint now) {
  const Op& op = run.ops[run.next];
  sdo::Request req;
  req.node = node;
  req.index = op.index;
  req.sub = op.sub;
  req.expected_size = 4;
  req.on_done = [this, node, gen = run.generation](sdo::TransferResult&& r) { on_done(node, gen, std::move(r)); };
  auto id = client_.upload(std::move(req), now);
  if (!id) return id.code();
  run.request = *id;
  return {};
}

void PdoConfigReader::step(std::uint8_t node, TimePoint now) {
  for (;;) {
    auto it = runs_.find(node);
    if (it == runs_.end()) return;
    Run& run = it->second;
    if (run.next < run.ops.size()) {
      if (auto ec = submit(node, run, now)) {
        // The node's SDO queue is full: give up rather than spin.
        run.report.stopped = ec;
        for (std::size_t i = run.pdo; i < run.plan.size(); ++i)
          run.report.pdos.push_back({run.plan[i].key, std::nullopt, ec, label(run.plan[i].key) + ": not read: " + ec.message()});
        finish(node, false);
      }
      return;
    }
    run.report.pdos.push_back({run.plan[run.pdo].key, std::move(run.current), {}, {}});
    if (++run.pdo == run.plan.size()) {
      finish(node, false);
      return;
    }
    begin_pdo(run);
  }
}

void PdoConfigReader::on_done(std::uint8_t node, std::uint64_t generation, sdo::TransferResult&& r) {
  auto it = runs_.find(node);
  if (it == runs_.end() || it->second.generation != generation) return;
  Run& run = it->second;
  run.request.reset();
  const Op op = run.ops[run.next];
  const PdoKey key = run.plan[run.pdo].key;
  const TimePoint now = now_();
  auto fail_pdo = [&](std::error_code ec, std::string detail) {
    run.report.pdos.push_back({key, std::nullopt, ec, label(key) + ": " + od::object_label(op.index, op.sub) + ": " + detail});
    if (++run.pdo == run.plan.size()) return finish(node, false);
    begin_pdo(run);
    step(node, now);
  };
  if (!r.ok()) {
    std::string detail = r.error.message();
    if (!r.detail.empty()) detail += " (" + r.detail + ")";
    if (r.origin == sdo::Origin::Remote) {
      if (op.optional) {  // e.g. no inhibit time on this device: the earlier value stays
        ++run.next;
        return step(node, now);
      }
      return fail_pdo(r.error, detail);
    }
    // Local (timeout, malformed answer): the rest is not asked for.
    run.report.stopped = r.error;
    run.report.pdos.push_back({key, std::nullopt, r.error, label(key) + ": " + od::object_label(op.index, op.sub) + ": " + detail});
    for (std::size_t i = run.pdo + 1; i < run.plan.size(); ++i)
      run.report.pdos.push_back({run.plan[i].key, std::nullopt, r.error, label(run.plan[i].key) + ": not read: " + detail});
    return finish(node, false);
  }
  if (r.data.empty() || r.data.size() > 4)
    return fail_pdo(make_error_code(SdoAbort::LengthMismatch),
                    "the device answered " + std::to_string(r.data.size()) + " bytes");
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < r.data.size(); ++i) v |= std::uint32_t{r.data[i]} << (8 * i);
  PdoParameters& p = run.current;
  const bool mapping = op.index == mapping_index(key.direction, key.number);
  if (!mapping) {
    switch (op.sub) {
      case 1: p.comm.cob_id.raw = v; break;
      case 2: p.comm.transmission_type = static_cast<std::uint8_t>(v); break;
      case 3: p.comm.inhibit_time = static_cast<std::uint16_t>(v); break;
      case 5: p.comm.event_timer = static_cast<std::uint16_t>(v); break;
      default: p.comm.sync_start = static_cast<std::uint8_t>(v); break;
    }
  } else if (op.sub == 0) {
    p.count = static_cast<std::uint8_t>(v);
    if (v > kMaxMappedEntries && v != 0xFE && v != 0xFF)
      return fail_pdo(make_error_code(SdoAbort::PdoLengthExceeded), std::to_string(v) + " mapped objects");
    if (v <= kMaxMappedEntries)
      for (std::uint32_t s = 1; s <= v; ++s) run.ops.push_back({op.index, static_cast<std::uint8_t>(s), false});
  } else {
    p.entries[op.sub] = v;
  }
  ++run.next;
  step(node, now);
}

void PdoConfigReader::finish(std::uint8_t node, bool cancelled) {
  auto it = runs_.find(node);
  if (it == runs_.end()) return;
  Run run = std::move(it->second);
  runs_.erase(it);
  complete(std::move(run), cancelled);
}

void PdoConfigReader::complete(Run run, bool cancelled) {
  for (std::size_t i = run.report.pdos.size(); i < run.plan.size(); ++i)
    run.report.pdos.push_back({run.plan[i].key, std::nullopt, std::make_error_code(std::errc::operation_canceled),
                               label(run.plan[i].key) + ": not read: cancelled"});
  run.report.cancelled = cancelled;
  for (auto& done : run.waiters)
    if (done) done(run.report);
}

void PdoConfigReader::cancel(std::uint8_t node, TimePoint now) {
  auto it = runs_.find(node);
  if (it == runs_.end()) return;
  // Taken out first: the cancelled transfer's handler then finds no run.
  Run run = std::move(it->second);
  runs_.erase(it);
  if (run.request) client_.cancel(*run.request, now);
  complete(std::move(run), true);
}

}  // namespace canopen::pdo
