// LSS (CiA 305) in the request core: every LSS command (contract "LSS
// master") as single services on the network's LSS master, one operation
// per network at a time, and what the last scan found.
#include <deque>
#include <memory>

#include "core/core_helpers.hpp"
#include "core/format.hpp"
#include "core/operation.hpp"
#include "core/request_core.hpp"

namespace gateway::core {

using detail::problem;
using detail::requester;

// ---- LSS (CiA 305) -----------------------------------------------------------
// Each LSS command becomes a list of LssSteps sent one after the other on
// the network's LSS master; the network is held (lss_busy_) from the first
// step to the answer. A multi-step command that fails after selecting a
// device still switches all back to waiting before it answers, so no device
// is left in configuration state.

namespace {

std::string_view step_name(const LssStep& step) {
  struct Visitor {
    std::string_view operator()(const LssSwitchGlobal& s) const {
      return s.configuration ? "switch state global (configuration)" : "switch state global (waiting)";
    }
    std::string_view operator()(const LssSwitchSelective&) const { return "switch state selective"; }
    std::string_view operator()(const LssSetNodeId&) const { return "configure node-ID"; }
    std::string_view operator()(const LssSetBitTiming&) const { return "configure bit timing"; }
    std::string_view operator()(const LssActivateBitTiming&) const { return "activate bit timing"; }
    std::string_view operator()(const LssStore&) const { return "store configuration"; }
    std::string_view operator()(const LssInquiry&) const { return "inquire identity"; }
    std::string_view operator()(const LssFastscan&) const { return "fastscan"; }
  };
  return std::visit(Visitor{}, step);
}

// A slave's error code with the meaning CiA 305 gives it for the service (facts C.1).
Problem lss_refusal(const LssStep& step, const LssOutcome& o) {
  Problem p = problem(422, "");
  p.title = "LSS error";
  std::string meaning;
  if (o.error == 0xFF) {
    p.lss_error = LssError::manufacturer;
    meaning = "manufacturer-specific error (error code FFh)" + (o.detail.empty() ? std::string() : ": " + o.detail);
  } else if (std::holds_alternative<LssSetNodeId>(step) && o.error == 1) {
    p.lss_error = LssError::node_id_not_supported;
    meaning = "node-ID " + std::to_string(std::get<LssSetNodeId>(step).node_id) + " is out of range (error code 1)";
  } else if (std::holds_alternative<LssSetBitTiming>(step) && o.error == 1) {
    p.lss_error = LssError::bitrate_not_supported;
    meaning = "bit rate not supported (error code 1)";
  } else if (std::holds_alternative<LssStore>(step) && o.error == 1) {
    p.lss_error = LssError::store_not_supported;
    meaning = "storing the configuration is not supported (error code 1)";
  } else if (std::holds_alternative<LssStore>(step) && o.error == 2) {
    p.lss_error = LssError::store_media_error;
    meaning = "storage media access error (error code 2)";
  } else {
    p.lss_error = LssError::other;
    meaning = "reserved error code " + std::to_string(o.error);
  }
  p.detail = "the device refused " + std::string(step_name(step)) + ": " + meaning;
  return p;
}

std::optional<Problem> lss_invalid(const Command& cmd, std::uint8_t own_node) {
  if (const auto* c = std::get_if<LssConfigure>(&cmd)) {
    if (c->node_id < 1 || c->node_id > 127)
      return problem(400, "nodeId must be 1..127, not " + std::to_string(c->node_id));
    if (c->node_id == own_node)
      return problem(400, "node-ID " + std::to_string(c->node_id) + " is the gateway's own on this network");
    if (c->bitrate && !canopen::lss::bit_timing_index(*c->bitrate))
      return problem(400, "bitrate " + std::to_string(*c->bitrate) +
                              " is not in the CiA 301 table (1000000, 800000, 500000, 250000, 125000, 50000, 20000, "
                              "10000)");
  } else if (const auto* a = std::get_if<LssAssignAll>(&cmd)) {
    if (a->first_node_id < 1 || a->first_node_id > 127)
      return problem(400, "firstNodeId must be 1..127, not " + std::to_string(a->first_node_id));
  } else if (const auto* n = std::get_if<LssSetNodeId>(&cmd)) {
    if ((n->node_id < 1 || n->node_id > 127) && n->node_id != 0xFF)
      return problem(400, "node-ID must be 1..127 or 255 (unconfigured), not " + std::to_string(n->node_id));
  }
  return std::nullopt;
}

}  // namespace

struct RequestCore::LssRun {
  Context c;
  Command cmd;
  std::string line;              // audit line, without the outcome
  std::deque<LssStep> steps;     // still to send
  bool cleaning_up = false;      // the steps left only switch back to waiting
  std::optional<Problem> failed;  // answered once the clean-up is done
  LssAddress found;
  LssAssignment pending;         // the assignment under way
  bool node_set = false;         // its node-ID was configured
  LssAssigned assigned;
  std::uint8_t next_id = 1;      // assign-all: the next node-ID to try
  LssInquired inquired;
};

void RequestCore::lss(Context& c, const Command& cmd) {
  if (std::holds_alternative<LssDevices>(cmd)) return c.done(LssDeviceList{c.network, lss_found_[c.network]});
  if (auto p = lss_invalid(cmd, net_.own_node_id(c.network))) return c.done(std::move(*p));
  if (auto p = bus_refused(c)) return c.done(std::move(*p));
  const std::string who = requester(c.caller.who);
  const std::string net = "net " + std::to_string(c.network);
  if (lss_busy_[c.network]) {
    ++counters_.lss_busy;
    return c.done(problem(409, "another LSS operation runs on network " + std::to_string(c.network) +
                                   "; send this one when it has finished"));
  }
  auto run = std::make_shared<LssRun>();
  run->c = c;
  run->cmd = cmd;
  run->inquired.network = c.network;
  run->assigned.network = c.network;
  auto& steps = run->steps;
  const LssSwitchGlobal waiting{false};
  // Each LSS command's audit line and steps; a non-LSS command never gets here (execute).
  const bool planned = std::visit(
      Overloaded{
          [&](const LssFastscan& f) {
            run->line = "LSS fastscan by " + who + ": " + net;
            steps = {waiting, f};
            return true;
          },
          [&](const LssConfigure& k) {
            run->line = "LSS configure by " + who + ": " + net + " " + canopen::lss::to_string(k.address) +
                        " -> node-ID " + std::to_string(k.node_id) +
                        (k.bitrate ? ", " + std::to_string(*k.bitrate) + " bit/s" : "") + (k.store ? ", store" : "");
            run->pending = LssAssignment{k.address, k.node_id, k.bitrate, false};
            steps = {waiting, LssSwitchSelective{k.address}, LssSetNodeId{k.node_id}};
            if (k.bitrate) steps.push_back(LssSetBitTiming{0, *canopen::lss::bit_timing_index(*k.bitrate)});
            if (k.store) steps.push_back(LssStore{});
            steps.push_back(waiting);
            return true;
          },
          [&](const LssAssignAll& a) {
            run->line = "LSS assign-all by " + who + ": " + net + " from node-ID " + std::to_string(a.first_node_id) +
                        (a.store ? ", store" : "");
            run->next_id = a.first_node_id;
            steps = {waiting, LssFastscan{a.timeout}};
            return true;
          },
          [&](const LssDevices&) { return false; },  // answered above
          [&](const LssSwitchGlobal& g) {
            run->line = "LSS switch state global " + std::string(g.configuration ? "configuration" : "waiting") +
                        " by " + who + ": " + net;
            steps = {g};
            return true;
          },
          [&](const LssSwitchSelective& sel) {
            run->line = "LSS switch state selective by " + who + ": " + net + " " + canopen::lss::to_string(sel.address);
            steps = {sel};
            return true;
          },
          [&](const LssSetNodeId& n) {
            run->line = "LSS configure node-ID " + std::to_string(n.node_id) + " by " + who + ": " + net;
            steps = {n};
            return true;
          },
          [&](const LssSetBitTiming& b) {
            run->line = "LSS configure bit timing " + std::to_string(b.table) + "/" + std::to_string(b.index) +
                        " by " + who + ": " + net;
            steps = {b};
            return true;
          },
          [&](const LssActivateBitTiming& act) {
            run->line = "LSS activate bit timing (delay " + std::to_string(act.delay_ms) + " ms) by " + who + ": " + net;
            steps = {act};
            return true;
          },
          [&](const LssStore&) {
            run->line = "LSS store configuration by " + who + ": " + net;
            steps = {LssStore{}};
            return true;
          },
          [&](const LssInquire& q) {
            run->line = "LSS inquire by " + who + ": " + net;
            run->inquired.what = q.what;
            if (q.what) {
              steps = {*q.what};
            } else {
              steps = {LssInquiry::vendor_id, LssInquiry::product_code, LssInquiry::revision, LssInquiry::serial};
            }
            return true;
          },
          []<typename T>(const T&)
            requires(!is_lss_command<T>)
          { return false; },
      },
      cmd);
  if (!planned) return c.done(problem(500, "not an LSS command"));
  // CiA 305: configure, store, activate and inquire address the device in
  // configuration state; with none there is nobody to wait for.
  const bool needs_selected = std::holds_alternative<LssSetNodeId>(cmd) ||
                              std::holds_alternative<LssSetBitTiming>(cmd) ||
                              std::holds_alternative<LssActivateBitTiming>(cmd) ||
                              std::holds_alternative<LssStore>(cmd) || std::holds_alternative<LssInquire>(cmd);
  if (needs_selected && !lss_selected_[c.network]) {
    ++counters_.lss_refused;
    return c.done(problem(409, "no device is in LSS configuration state on network " + std::to_string(c.network) +
                                   ": select one first (switch state selective, switch state global configuration, "
                                   "or a fastscan)"));
  }
  lss_busy_[c.network] = true;
  lss_next(std::move(run));
}

void RequestCore::lss_next(std::shared_ptr<LssRun> run) {
  if (run->steps.empty()) {
    if (run->failed) return lss_finish(run, *run->failed);
    const Command& cmd = run->cmd;
    if (std::holds_alternative<LssFastscan>(cmd)) return lss_finish(run, LssFound{run->c.network, run->found});
    if (std::holds_alternative<LssConfigure>(cmd) || std::holds_alternative<LssAssignAll>(cmd))
      return lss_finish(run, run->assigned);
    if (std::holds_alternative<LssInquire>(cmd)) return lss_finish(run, run->inquired);
    return lss_finish(run, LssDone{run->c.network});
  }
  const LssStep step = run->steps.front();
  run->steps.pop_front();
  auto ec = net_.lss(run->c.network, step, [this, run, step](const LssOutcome& o) {
    using S = LssOutcome::Status;
    // Which device is in configuration state, as far as the gateway's own
    // services tell.
    bool& selected = lss_selected_[run->c.network];
    if (const auto* g = std::get_if<LssSwitchGlobal>(&step)) {
      if (o.status == S::ok) selected = g->configuration;
    } else if (std::holds_alternative<LssSwitchSelective>(step) || std::holds_alternative<LssFastscan>(step)) {
      selected = o.status == S::ok;
    }
    if (run->cleaning_up) return lss_next(run);  // its outcome changes nothing: the answer is the failure
    if (o.status != S::ok) {
      const bool assign_all = std::holds_alternative<LssAssignAll>(run->cmd);
      if (o.status == S::none_found && assign_all) {
        run->steps.clear();  // every unconfigured device has its node-ID
        return lss_next(run);
      }
      Problem p;
      switch (o.status) {
        case S::none_found:
          ++counters_.lss_none_found;
          p = problem(404, "no unconfigured device answered (fastscan; devices with a node-ID are not scanned)");
          break;
        case S::timeout:
          ++counters_.lss_timeouts;
          p = problem(504, std::holds_alternative<LssSwitchSelective>(step)
                               ? "no device with " + canopen::lss::to_string(std::get<LssSwitchSelective>(step).address) +
                                     " answered (switch state selective)"
                               : "no device answered " + std::string(step_name(step)) + " in time");
          p.title = "LSS timeout";
          break;
        case S::refused:
          ++counters_.lss_refused;
          p = lss_refusal(step, o);
          break;
        default:
          ++counters_.lss_failed;
          p = problem(502, std::string(step_name(step)) + " failed: " + o.detail);
          break;
      }
      if (assign_all && !run->assigned.assignments.empty())
        p.detail += " (after assigning " + std::to_string(run->assigned.assignments.size()) + " device(s))";
      run->failed = std::move(p);
      run->steps.clear();
      // A device may be in configuration state: back to waiting (a single
      // service changes nothing it was not asked to).
      const bool multi = std::holds_alternative<LssConfigure>(run->cmd) || assign_all ||
                         std::holds_alternative<LssFastscan>(run->cmd);
      if (multi && !std::holds_alternative<LssSwitchGlobal>(step)) {
        run->cleaning_up = true;
        run->steps.push_back(LssSwitchGlobal{false});
      }
      return lss_next(run);
    }
    // Success of one step.
    if (const auto* f = std::get_if<LssFastscan>(&step)) {
      run->found = o.address;
      if (const auto* a = std::get_if<LssAssignAll>(&run->cmd)) {
        std::uint8_t id = run->next_id;
        while (id <= 127 && net_.node_in_use(run->c.network, id)) ++id;
        if (id > 127) {
          ++counters_.lss_failed;
          run->failed = problem(409, "no free node-ID left from " + std::to_string(run->next_id) + " for " +
                                         canopen::lss::to_string(o.address) + " (after assigning " +
                                         std::to_string(run->assigned.assignments.size()) + " device(s))");
          run->cleaning_up = true;
          run->steps = {LssSwitchGlobal{false}};
          return lss_next(run);
        }
        run->next_id = static_cast<std::uint8_t>(id + 1);
        run->pending = LssAssignment{o.address, id, std::nullopt, false};
        run->steps.push_back(LssSetNodeId{id});
        if (a->store) run->steps.push_back(LssStore{});
        run->steps.push_back(LssSwitchGlobal{false});
        run->steps.push_back(*f);  // the next one
      }
    } else if (std::holds_alternative<LssSetNodeId>(step)) {
      run->node_set = true;
    } else if (std::holds_alternative<LssStore>(step)) {
      run->pending.stored = true;
    } else if (const auto* q = std::get_if<LssInquiry>(&step)) {
      run->inquired.value = o.value;
      switch (*q) {
        case LssInquiry::vendor_id: run->inquired.address.vendor_id = o.value; break;
        case LssInquiry::product_code: run->inquired.address.product_code = o.value; break;
        case LssInquiry::revision: run->inquired.address.revision = o.value; break;
        case LssInquiry::serial: run->inquired.address.serial = o.value; break;
        case LssInquiry::node_id: break;
      }
    } else if (const auto* g = std::get_if<LssSwitchGlobal>(&step); g != nullptr && !g->configuration) {
      // Back to waiting after a node-ID was configured: that assignment is done.
      if (run->node_set) {
        ++counters_.lss_assigned;
        run->assigned.assignments.push_back(run->pending);
        run->pending = {};
        run->node_set = false;
      }
    }
    lss_next(run);
  });
  if (!ec) return;
  ++counters_.lss_failed;
  lss_finish(run, problem(503, "the LSS master of network " + std::to_string(run->c.network) +
                                   " cannot send " + std::string(step_name(step)) + ": " + ec.message()));
}

void RequestCore::lss_finish(const std::shared_ptr<LssRun>& run, Result result) {
  lss_busy_[run->c.network] = false;
  auto& found = lss_found_[run->c.network];
  const Command& cmd = run->cmd;
  std::string outcome;
  if (const auto* p = std::get_if<Problem>(&result)) {
    outcome = std::to_string(p->status) + " " + p->detail;
    if (p->status == 404 && std::holds_alternative<LssFastscan>(cmd)) found.clear();
  } else {
    ++counters_.lss_ok;
    outcome = "ok";
    if (std::holds_alternative<LssFastscan>(cmd)) {
      found = {LssDeviceSeen{run->found, std::nullopt}};
      outcome = "found " + canopen::lss::to_string(run->found);
    } else if (const auto* a = std::get_if<LssAssigned>(&result)) {
      if (std::holds_alternative<LssAssignAll>(cmd)) found.clear();
      for (const auto& as : a->assignments) {
        auto it = std::find_if(found.begin(), found.end(), [&](const LssDeviceSeen& d) { return d.address == as.address; });
        if (it != found.end()) {
          it->node_id = as.node_id;
        } else if (std::holds_alternative<LssAssignAll>(cmd)) {
          found.push_back({as.address, as.node_id});
        }
      }
      if (std::holds_alternative<LssAssignAll>(cmd)) {
        outcome = std::to_string(a->assignments.size()) + " assigned";
        for (const auto& as : a->assignments)
          outcome += "; " + canopen::lss::to_string(as.address) + " -> node-ID " + std::to_string(as.node_id);
      }
    } else if (const auto* q = std::get_if<LssInquired>(&result)) {
      outcome = q->what ? "answered 0x" + hex_number(q->value, 8) : "answered " + canopen::lss::to_string(q->address);
    }
  }
  audit_(run->line + ": " + outcome);
  run->c.done(std::move(result));
}

}  // namespace gateway::core
