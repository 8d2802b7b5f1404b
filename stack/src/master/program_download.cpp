#include "canopen/master/program_download.hpp"

#include <utility>
#include <vector>

#include "canopen/od/object_dictionary.hpp"
#include "canopen/sdo/abort.hpp"
#include "runs.hpp"

namespace canopen::master {

namespace {

using detail::hex32h;
using od::object_label;

// The 1F51h command of a control step.
std::uint8_t control_value(ProgramStep s) {
  switch (s) {
    case ProgramStep::StopProgram: return kProgramStop;
    case ProgramStep::ClearProgram: return kProgramClear;
    default: return kProgramStart;
  }
}

}  // namespace

std::string_view to_string(ProgramStep s) {
  switch (s) {
    case ProgramStep::StopProgram: return "stop program";
    case ProgramStep::ClearProgram: return "clear program";
    case ProgramStep::Download: return "download";
    case ProgramStep::ReadIdentification: return "read identification";
    case ProgramStep::StartProgram: return "start program";
    case ProgramStep::Done: return "done";
  }
  return "?";
}

struct ProgramDownloader::Run {
  std::uint64_t generation = 0;
  ProgramDownloadOptions options;
  Bytes image;  // moved into the download request when that step starts
  Done done;
  std::vector<ProgramStep> steps;
  std::size_t next = 0;
  std::optional<sdo::RequestId> request;
  ProgramDownloadReport report;
  bool downloaded = false;
  ProgramStep step() const { return steps[next]; }
  // What the step does, for events and errors: "clear program (1F51h sub 1 := 3)".
  std::string label() const {
    const ProgramStep s = step();
    const std::uint8_t n = options.program;
    switch (s) {
      case ProgramStep::StopProgram:
      case ProgramStep::ClearProgram:
      case ProgramStep::StartProgram:
        return std::string(to_string(s)) + " (" + object_label(kProgramControl, n) + " := " +
               std::to_string(control_value(s)) + ")";
      case ProgramStep::Download:
        return "download (" + object_label(kProgramData, n) + ", " + std::to_string(report.bytes) + " bytes)";
      case ProgramStep::ReadIdentification:
        return "read identification (" + object_label(kProgramIdentification, n) + ")";
      case ProgramStep::Done: break;
    }
    return std::string(to_string(s));
  }
};

ProgramDownloader::ProgramDownloader(sdo::SdoClient& client, EventHandler on_event, TimeSource now)
    : client_(client), on_event_(std::move(on_event)), now_(std::move(now)) {}

ProgramDownloader::~ProgramDownloader() { detail::drop_runs(client_, runs_, now_()); }

bool ProgramDownloader::busy(std::uint8_t node) const { return runs_.contains(node); }

bool ProgramDownloader::current(std::uint8_t node, std::uint64_t gen) const {
  const auto it = runs_.find(node);
  return it != runs_.end() && it->second.generation == gen;
}

void ProgramDownloader::emit(const TransferEvent& ev) {
  if (on_event_) on_event_(ev);
}

std::error_code ProgramDownloader::start(std::uint8_t node, ProgramDownloadOptions options, Bytes image, Done done,
                                         TimePoint now) {
  if (node < 1 || node > 127) return make_error_code(TransferError::BadNode);
  if (options.program < 1 || options.program > 254) return make_error_code(TransferError::BadProgramNumber);
  if (image.empty()) return make_error_code(TransferError::EmptyImage);
  if (busy(node)) return make_error_code(TransferError::Busy);
  Run run;
  run.generation = ++generation_;
  run.options = options;
  run.report.node = node;
  run.report.program = options.program;
  run.report.bytes = image.size();
  run.image = std::move(image);
  run.done = std::move(done);
  run.steps.push_back(ProgramStep::StopProgram);
  if (options.clear) run.steps.push_back(ProgramStep::ClearProgram);
  run.steps.push_back(ProgramStep::Download);
  run.steps.push_back(ProgramStep::ReadIdentification);
  if (options.start) run.steps.push_back(ProgramStep::StartProgram);
  const std::uint64_t gen = run.generation;
  runs_.emplace(node, std::move(run));
  submit_step(node, now);
  if (!current(node, gen)) return {};
  Run& r = runs_.at(node);
  if (!r.request) {
    // The very first submit was refused: nothing started.
    const std::error_code ec = r.report.error;
    runs_.erase(node);
    return ec;
  }
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::ProgramDownload;
  ev.status = TransferEvent::Status::Running;
  ev.total = r.report.bytes;
  ev.detail = r.label();
  emit(ev);
  return {};
}

void ProgramDownloader::submit_step(std::uint8_t node, TimePoint now) {
  Run& run = runs_.at(node);
  const std::uint64_t gen = run.generation;
  const std::uint8_t n = run.options.program;
  sdo::Request req;
  req.node = node;
  req.sub = n;
  req.timeout = run.options.timeout;
  req.on_done = [this, node, gen](sdo::TransferResult&& r) { on_done(node, gen, std::move(r)); };
  Result<sdo::RequestId> id = make_error_code(std::errc::invalid_argument);
  switch (run.step()) {
    case ProgramStep::StopProgram:
    case ProgramStep::ClearProgram:
    case ProgramStep::StartProgram:
      req.index = kProgramControl;
      id = client_.download(std::move(req), Bytes{control_value(run.step())}, now);
      break;
    case ProgramStep::Download: {
      req.index = kProgramData;
      const std::size_t total = run.report.bytes;
      req.on_progress = [this, node, gen, total](std::size_t done, std::optional<std::size_t>) {
        if (!current(node, gen)) return;
        TransferEvent ev;
        ev.node = node;
        ev.operation = TransferEvent::Operation::ProgramDownload;
        ev.status = TransferEvent::Status::Running;
        ev.done = done;
        ev.total = total;
        ev.detail = runs_.at(node).label();
        emit(ev);
      };
      // Auto: block above the client's threshold, segmented when refused.
      id = client_.download(std::move(req), std::move(run.image), now);
      run.image = {};
      break;
    }
    case ProgramStep::ReadIdentification:
      req.index = kProgramIdentification;
      req.expected_size = 4;
      id = client_.upload(std::move(req), now);
      break;
    case ProgramStep::Done: return;
  }
  if (!id) {
    if (run.next == 0) {
      run.report.error = id.code();  // start() returns it
      return;
    }
    fail(node, id.code(), sdo::Origin::Local, run.label() + ": " + id.code().message());
    return;
  }
  run.request = *id;
}

void ProgramDownloader::on_done(std::uint8_t node, std::uint64_t gen, sdo::TransferResult&& r) {
  if (!current(node, gen)) return;
  Run& run = runs_.at(node);
  run.request.reset();
  const ProgramStep step = run.step();
  if (r.cancelled) {
    fail(node, r.error, r.origin, run.label() + ": cancelled", true);
    return;
  }
  if (step == ProgramStep::ReadIdentification) {
    const bool none = !r.ok() && r.origin == sdo::Origin::Remote &&
                      (r.error == SdoAbort::NoSuchObject || r.error == SdoAbort::NoSuchSubIndex);
    if (r.ok()) {
      auto v = decode(DataType::Unsigned32, r.data);
      if (!v) {
        fail(node, v.code(), sdo::Origin::Local,
             run.label() + ": " + std::to_string(r.data.size()) + " bytes, expected 4");
        return;
      }
      run.report.identification = static_cast<std::uint32_t>(std::get<std::uint64_t>(v->data));
    } else if (!none) {
      std::string detail = run.label() + ": " + r.error.message();
      if (!r.detail.empty()) detail += " (" + r.detail + ")";
      fail(node, r.error, r.origin, std::move(detail));
      return;
    }
    if (const auto& want = run.options.expected_identification;
        want && (!run.report.identification || *run.report.identification != *want)) {
      fail(node, make_error_code(TransferError::WrongIdentification), sdo::Origin::Local,
           run.label() + ": " +
               (run.report.identification ? hex32h(*run.report.identification) : std::string("the device has none")) +
               ", expected " + hex32h(*want) + "; program not started");
      return;
    }
  } else if (!r.ok()) {
    std::string detail = run.label() + ": " + r.error.message();
    if (!r.detail.empty()) detail += " (" + r.detail + ")";
    if (step != ProgramStep::StartProgram) detail += "; program not started";
    fail(node, r.error, r.origin, std::move(detail));
    return;
  }
  if (step == ProgramStep::StartProgram) run.report.started = true;
  if (step == ProgramStep::Download) run.downloaded = true;
  advance(node, now_());
}

void ProgramDownloader::advance(std::uint8_t node, TimePoint now) {
  Run& run = runs_.at(node);
  const std::uint64_t gen = run.generation;
  ++run.next;
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::ProgramDownload;
  ev.total = run.report.bytes;
  ev.done = run.downloaded ? run.report.bytes : 0;
  if (run.next >= run.steps.size()) {
    run.report.step = ProgramStep::Done;
    ProgramDownloadReport report = std::move(run.report);
    Done done = std::move(run.done);
    runs_.erase(node);
    ev.status = TransferEvent::Status::Done;
    ev.detail = "program " + std::to_string(report.program) + (report.started ? " started" : " downloaded, not started");
    if (report.identification) ev.detail += ", identification " + hex32h(*report.identification);
    emit(ev);
    if (done) done(report);
    return;
  }
  ev.status = TransferEvent::Status::Running;
  ev.detail = run.label();
  emit(ev);
  if (!current(node, gen)) return;  // the handler cancelled it
  submit_step(node, now);
}

void ProgramDownloader::fail(std::uint8_t node, std::error_code ec, sdo::Origin origin, std::string detail,
                             bool cancelled) {
  Run& run = runs_.at(node);
  ProgramDownloadReport report = std::move(run.report);
  report.step = run.step();
  report.error = ec ? ec : make_error_code(SdoAbort::GeneralError);
  report.origin = origin;
  report.detail = std::move(detail);
  report.cancelled = cancelled;
  Done done = std::move(run.done);
  runs_.erase(node);
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::ProgramDownload;
  ev.status = TransferEvent::Status::Failed;
  ev.total = report.bytes;
  ev.error = report.error;
  ev.detail = report.detail;
  emit(ev);
  if (done) done(report);
}

bool ProgramDownloader::cancel(std::uint8_t node, TimePoint now) {
  const auto it = runs_.find(node);
  if (it == runs_.end()) return false;
  if (it->second.request) {
    // The client calls the handler with cancelled = true: it fails the run.
    const sdo::RequestId id = *it->second.request;
    if (client_.cancel(id, now)) return true;
  }
  fail(node, make_error_code(SdoAbort::GeneralError), sdo::Origin::Local, it->second.label() + ": cancelled", true);
  return true;
}

}  // namespace canopen::master
