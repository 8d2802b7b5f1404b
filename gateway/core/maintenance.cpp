// Remote maintenance in the request core (contract "Remote configuration
// and maintenance"): DCF read-back and apply, store/restore (CiA 301
// 7.5.2.13/14) and program download (CiA 302-3). The transfers themselves
// are the network's (Networks::dcf_read/dcf_apply/program_download, which
// report progress as `transfer` events); here: the checks, one operation per
// node at a time, the caller's share of the node's SDO queue, audit lines,
// counters, and the answer.
#include <optional>
#include <system_error>

#include "canopen/eds/eds.hpp"
#include "canopen/sdo/abort.hpp"
#include "core/core_helpers.hpp"
#include "core/format.hpp"
#include "core/request_core.hpp"

namespace gateway::core {

namespace {

using detail::problem;
using detail::requester;

// CiA 301 7.5.2.13 / 7.5.2.14: the signatures written to sub 1 ("save" and
// "load" read as UNSIGNED32, little-endian on the bus).
constexpr std::uint32_t kSave = 0x65766173;
constexpr std::uint32_t kLoad = 0x64616F6C;

canopen::Bytes le32(std::uint32_t v) {
  return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16),
          static_cast<std::uint8_t>(v >> 24)};
}

std::string node_text(std::uint32_t net, std::uint8_t node) {
  return "net " + std::to_string(net) + " node " + std::to_string(node);
}

// A transfer that stopped, as the answer: busy 409; an SDO abort as any SDO
// transfer's (422 the device's, 504 timeout, 502 other), naming the step.
Problem stopped(const TransferOutcome& o) {
  if (o.error == make_error_code(canopen::SdoAbort::NoSdoConnection) && !o.remote) {
    auto p = problem(429, "too many SDO requests queued for the node");
    p.retry_after = 1;
    return p;
  }
  if (o.error == std::errc::device_or_resource_busy)
    return problem(409, (o.detail.empty() ? std::string("another transfer runs for the node") : o.detail) +
                            "; send this one when it has finished");
  std::string context = o.step;
  if (!o.detail.empty()) context += (context.empty() ? "" : ": ") + o.detail;
  if (&o.error.category() == &canopen::sdo_abort_category()) return sdo_problem(o.error, o.remote, context);
  return problem(502, (context.empty() ? std::string() : context + ": ") + o.error.message());
}

// What a Networks call that refused to start answers; `nothing`: the
// detail of the 400 when there was nothing to transfer.
Problem not_started(std::error_code ec, std::string_view nothing = "nothing to transfer") {
  if (ec == std::errc::invalid_argument) return problem(400, std::string(nothing));
  TransferOutcome o;
  o.error = ec;
  return stopped(o);
}

}  // namespace

struct RequestCore::MaintenanceRun {
  Context c;
  std::uint8_t node = 0;
  Counters::MaintenanceKind kind = Counters::dcf_read;
  std::string line;  // the audit line without the outcome
};

std::optional<Problem> RequestCore::maintenance_start(const Context& c, std::uint8_t node,
                                                      Counters::MaintenanceKind kind, const std::string& line) {
  if (auto p = bus_refused(c)) {
    audit_(line + ": " + std::to_string(p->status) + " " + p->detail);
    return p;
  }
  auto& busy = maintenance_busy_[detail::sdo_queue_key(c.network, node)];
  if (busy) {
    ++counters_.maintenance[kind][Counters::busy];
    auto p = problem(409, "another DCF transfer, store/restore or program download runs for node " +
                              std::to_string(node) + "; send this one when it has finished");
    audit_(line + ": 409 " + p.detail);
    return p;
  }
  if (auto full = take_sdo_place(c, node)) {
    audit_(line + ": " + std::to_string(full->status) + " (" + c.caller.key + " has its share of the node's SDO queue)");
    return full;
  }
  busy = true;
  return std::nullopt;
}

void RequestCore::maintenance_end(const MaintenanceRun& run, Result result, const std::string& outcome) {
  maintenance_busy_.erase(detail::sdo_queue_key(run.c.network, run.node));
  place_freed(run.c.network, run.node, run.c.caller.key);
  const auto* p = std::get_if<Problem>(&result);
  if (p != nullptr && p->status == 409) {
    ++counters_.maintenance[run.kind][Counters::busy];
  } else {
    ++counters_.maintenance[run.kind][p != nullptr ? Counters::failed : Counters::ok];
  }
  audit_(run.line + ": " + (p != nullptr ? std::to_string(p->status) + " " + p->detail : outcome));
  run.c.done(std::move(result));
}

// Refusals before a run: the gateway's own node is configured by its file,
// not remotely; a node without EDS/DCF has no list of configurable objects.
namespace {
std::optional<Problem> own_node_refused(std::uint8_t node, std::uint8_t own, std::string_view what) {
  if (node != own) return std::nullopt;
  return problem(400, "node " + std::to_string(node) + " is the gateway's own node: " + std::string(what) +
                          " is for remote devices (the gateway's settings are its configuration file)");
}
}  // namespace

void RequestCore::dcf_read(Context& c, const DcfRead& cmd) {
  if (auto p = own_node_refused(cmd.node, net_.own_node_id(c.network), "DCF read-back")) return c.done(std::move(*p));
  if (net_.description(c.network, cmd.node) == nullptr)
    return c.done(problem(404, "node " + std::to_string(cmd.node) + " on network " + std::to_string(c.network) +
                                   " has no EDS/DCF, so which objects to read is unknown (give it one: PUT .../eds)"));
  auto run = std::make_shared<MaintenanceRun>(
      MaintenanceRun{c, cmd.node, Counters::dcf_read,
                     "DCF read by " + requester(c.caller.who) + ": " + node_text(c.network, cmd.node)});
  if (auto p = maintenance_start(c, cmd.node, run->kind, run->line)) return c.done(std::move(*p));
  auto ec = net_.dcf_read(c.network, cmd.node, [this, run](TransferOutcome o) {
    if (o.error) return maintenance_end(*run, stopped(o), "");
    DcfDocument doc{run->c.network, run->node, std::move(o.text), o.read, std::move(o.objects)};
    const std::string outcome =
        std::to_string(doc.objects) + " objects read, " + std::to_string(doc.failed.size()) + " failed";
    maintenance_end(*run, std::move(doc), outcome);
  });
  if (ec && ec == std::errc::invalid_argument) {
    return maintenance_end(*run, problem(404, "the EDS/DCF of node " + std::to_string(cmd.node) +
                                                   " lists no readable configurable object"), "");
  }
  if (ec) maintenance_end(*run, not_started(ec), "");
}

void RequestCore::dcf_apply(Context& c, const DcfApply& cmd) {
  if (auto p = own_node_refused(cmd.node, net_.own_node_id(c.network), "DCF apply")) return c.done(std::move(*p));
  // The gateway's EDS reader, as `canopen-eds check` (400 "FILE:LINE:
  // reason"); $NODEID is this node's. Nothing goes on the bus for a bad file.
  std::optional<canopen::eds::DeviceDescription> dcf;
  const std::string file = "node" + std::to_string(cmd.node) + ".dcf";
  try {
    dcf.emplace(canopen::eds::parse_device_description(cmd.text, file, cmd.node));
  } catch (const canopen::eds::EdsError& e) {
    return c.done(problem(400, e.what()));
  }
  const std::string flags = std::string(cmd.store ? ", then store" : "") + (cmd.reset ? ", then reset node" : "");
  auto run = std::make_shared<MaintenanceRun>(
      MaintenanceRun{c, cmd.node, Counters::dcf_apply,
                     "DCF apply by " + requester(c.caller.who) + ": " + node_text(c.network, cmd.node) + flags});
  if (auto p = maintenance_start(c, cmd.node, run->kind, run->line)) return c.done(std::move(*p));
  auto ec = net_.dcf_apply(c.network, cmd.node, *dcf, cmd.store, cmd.reset, [this, run](TransferOutcome o) {
    if (o.error) return maintenance_end(*run, stopped(o), "");
    // Objects the device refused are results, not a failure: one outcome
    // per object; a refused save is reported with them (stored false).
    DcfApplied a{run->c.network, run->node, std::move(o.objects), o.stored, o.reset, std::move(o.store_error)};
    std::size_t failed = 0;
    for (const auto& obj : a.objects) failed += obj.error ? 1 : 0;
    std::string outcome = std::to_string(a.objects.size() - failed) + " objects written, " + std::to_string(failed) +
                          " failed" + (a.stored ? ", stored" : "") + (a.reset ? ", reset" : "");
    if (a.store_error) outcome += ", store refused: " + a.store_error->error.message();
    maintenance_end(*run, std::move(a), outcome);
  });
  if (ec) maintenance_end(*run, not_started(ec, "the DCF has no value to write (no writable configurable object with "
                                                "a ParameterValue) and neither store nor reset was asked"), "");
}

void RequestCore::node_store(Context& c, const NodeStore& cmd) {
  const std::uint16_t index = cmd.restore ? 0x1011 : 0x1010;
  const std::uint32_t signature = cmd.restore ? kLoad : kSave;
  // The restore's reset node needs admin as a plain NMT request; here it is
  // part of the operator's restore (CiA 301 7.5.2.14: the defaults take
  // effect after a reset), and the audit line says so.
  const std::string line = std::string(cmd.restore ? "restore" : "store") + " by " + requester(c.caller.who) + ": " +
                           node_text(c.network, cmd.node) + " " + index_text(index) + " sub 1 = \"" +
                           (cmd.restore ? "load" : "save") + "\"" +
                           (cmd.restore ? " then NMT reset node (part of the restore)" : "");
  auto run = std::make_shared<MaintenanceRun>(
      MaintenanceRun{c, cmd.node, cmd.restore ? Counters::restore : Counters::store, line});
  const bool restore = cmd.restore;
  auto written = [this, run, restore] {
    if (restore) net_.send_nmt(run->c.network, canopen::NmtCommand::ResetNode, run->node);
    maintenance_end(*run, NodeStored{run->c.network, run->node, restore}, "ok");
  };
  if (cmd.node == net_.own_node_id(c.network)) {
    // The gateway's own dictionary, as an SDO download would write it.
    ++counters_.sdo_requests;
    if (auto ec = net_.write_own(c.network, index, 1, le32(signature))) {
      audit_(line + ": " + ec.message());
      ++counters_.maintenance[run->kind][Counters::failed];
      return c.done(sdo_problem(ec, true, index_text(index) + " sub 1"));
    }
    if (restore) net_.send_nmt(c.network, canopen::NmtCommand::ResetNode, cmd.node);
    audit_(line + ": ok");
    ++counters_.maintenance[run->kind][Counters::ok];
    return c.done(NodeStored{c.network, cmd.node, restore});
  }
  if (auto p = maintenance_start(c, cmd.node, run->kind, line)) return c.done(std::move(*p));
  ++counters_.sdo_requests;
  canopen::sdo::Request r;
  r.node = cmd.node;
  r.index = index;
  r.sub = 1;
  r.on_done = [this, run, written, t0 = net_.now()](canopen::sdo::TransferResult&& res) {
    sdo_finished(t0);
    if (!res.ok()) {
      // 422 with the abort when the device refuses (e.g. 08000020h: cannot store).
      return maintenance_end(*run, transfer_failed(res), "");
    }
    written();
  };
  if (auto id = net_.sdo_download(c.network, std::move(r), le32(signature)); !id)
    maintenance_end(*run, not_started(id.error().code), "");
}

void RequestCore::program_download(Context& c, ProgramDownload cmd) {
  if (auto p = own_node_refused(cmd.node, net_.own_node_id(c.network), "program download"))
    return c.done(std::move(*p));
  if (cmd.program == 0 || cmd.program > 254)
    return c.done(problem(400, "program number must be 1..254 (1F50h sub-index), not " + std::to_string(cmd.program)));
  if (cmd.image.empty()) return c.done(problem(400, "the program image is empty"));
  const std::size_t size = cmd.image.size();
  auto run = std::make_shared<MaintenanceRun>(MaintenanceRun{
      c, cmd.node, Counters::program_download,
      "program download by " + requester(c.caller.who) + ": " + node_text(c.network, cmd.node) + " program " +
          std::to_string(cmd.program) + ", " + std::to_string(size) + " bytes"});
  if (auto p = maintenance_start(c, cmd.node, run->kind, run->line)) return c.done(std::move(*p));
  auto ec = net_.program_download(
      c.network, cmd.node, cmd.program, std::move(cmd.image), [this, run, program = cmd.program](TransferOutcome o) {
        if (o.error) return maintenance_end(*run, stopped(o), "");
        ProgramDownloaded d{run->c.network, run->node, program, o.bytes, o.identification};
        const std::string outcome =
            "ok, started" + (d.identification ? ", identification 0x" + hex_number(*d.identification, 8) : std::string());
        maintenance_end(*run, d, outcome);
      });
  if (ec) maintenance_end(*run, not_started(ec), "");
}

}  // namespace gateway::core
