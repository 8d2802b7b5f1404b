#include "core/request_core.hpp"

#include <algorithm>
#include <deque>

#include "canopen/eds/eds.hpp"
#include "canopen/json_value.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "core/format.hpp"
#include "rest_parse.hpp"

namespace gateway::core {

namespace {

// Who asked, for the audit log.
std::string requester(std::string_view who) { return who.empty() ? std::string("anonymous") : std::string(who); }

// The queue key of QueueShares for a node's SDO queue.
std::uint64_t sdo_queue_key(std::uint32_t network, std::uint8_t node) { return std::uint64_t{network} << 8 | node; }

Problem problem(int status, std::string detail, bool command_read = true) {
  Problem p;
  p.status = status;
  p.detail = std::move(detail);
  p.command_read = command_read;
  return p;
}

// The node a command addresses (0: the whole network, or NMT to all).
std::uint8_t node_of(const Command& command) {
  return std::visit(
      [](const auto& c) -> std::uint8_t {
        if constexpr (requires { c.node; }) {
          return c.node;
        } else {
          return 0;
        }
      },
      command);
}

struct OperationOf {
  Operation operator()(const SdoRead&) const { return Operation::sdo_read; }
  Operation operator()(const SdoWrite&) const { return Operation::sdo_write; }
  Operation operator()(const Nmt&) const { return Operation::nmt; }
  Operation operator()(const RpdoWrite&) const { return Operation::rpdo_write; }
  Operation operator()(const Sync&) const { return Operation::sync; }
  Operation operator()(const PdoConfigRead&) const { return Operation::pdo_config_read; }
  Operation operator()(const Undecodable& u) const { return u.operation; }
  Operation operator()(const NodeConfigRead&) const { return Operation::config_read; }
  Operation operator()(const NodeConfigWrite&) const { return Operation::config_write; }
  Operation operator()(const NodeEdsWrite&) const { return Operation::config_write; }
  Operation operator()(const DcfRead&) const { return Operation::dcf_read; }
  Operation operator()(const DcfApply&) const { return Operation::dcf_write; }
  Operation operator()(const NodeStore&) const { return Operation::store; }
  Operation operator()(const ProgramDownload&) const { return Operation::program; }
  Operation operator()(const auto&) const { return Operation::lss; }  // the LSS commands
};

Operation operation_of(const Command& command) { return std::visit(OperationOf{}, command); }

// What a role refusal's audit line says was refused.
std::string_view operation_text(Operation op) {
  switch (op) {
    case Operation::sdo_read: return "SDO read";
    case Operation::sdo_write: return "SDO write";
    case Operation::nmt: return "NMT";
    case Operation::rpdo_write: return "RPDO write";
    case Operation::sync: return "SYNC";
    case Operation::pdo_config_read: return "PDO configuration read";
    case Operation::lss: return "LSS";
    case Operation::config_read: return "configuration read";
    case Operation::config_write: return "configuration change";
    case Operation::dcf_read: return "DCF read";
    case Operation::dcf_write: return "DCF apply";
    case Operation::store: return "store/restore";
    case Operation::program: return "program download";
  }
  return "request";
}

// The type of index/sub: the request's, else the node's EDS/DCF entry's;
// DOMAIN (raw hex) when neither knows. The 404 when the EDS lacks it.
std::optional<Problem> resolve_type(const canopen::eds::DeviceDescription* desc, std::uint16_t index,
                                    std::uint8_t sub, std::optional<canopen::DataType> requested,
                                    canopen::DataType& out, const canopen::od::SubEntry** entry) {
  *entry = desc != nullptr ? desc->od.find(index, sub) : nullptr;
  if (requested) {
    out = *requested;
    return std::nullopt;
  }
  if (desc == nullptr) {
    out = canopen::DataType::Domain;  // no EDS: raw bytes as hex
    return std::nullopt;
  }
  if (*entry == nullptr)
    return problem(404, "the node's EDS/DCF has no object " + object_label(index, sub) +
                            " (give ?type= to ask anyway)");
  out = (*entry)->type;
  return std::nullopt;
}

// The same for the gateway's own dictionary.
std::optional<Problem> resolve_own_type(const canopen::od::ObjectDictionary& od, std::uint16_t index,
                                        std::uint8_t sub, std::optional<canopen::DataType> requested,
                                        canopen::DataType& out, const canopen::od::SubEntry** entry) {
  *entry = od.find(index, sub);
  if (*entry == nullptr) {
    // As the device would answer (7.2.4.3.17): the object does not exist.
    const auto code = od.find(index) == nullptr ? canopen::SdoAbort::NoSuchObject : canopen::SdoAbort::NoSuchSubIndex;
    return sdo_problem(make_error_code(code), true);
  }
  out = requested.value_or((*entry)->type);
  return std::nullopt;
}

}  // namespace

RequestCore::RequestCore(Networks& networks, const auth::TokenStore& tokens, Settings settings, AuditSink audit)
    : net_(networks),
      tokens_(tokens),
      settings_(settings),
      audit_(std::move(audit)),
      limiter_(settings.rate_limit, settings.rate_burst),
      shares_(auth::caller_share(settings.sdo_queue_limit)) {}

void RequestCore::execute(Request request, Done done) {
  Context c{std::move(request.caller), request.network, request.check_bus, std::move(done)};
  const Command& command = request.command;
  const Operation op = operation_of(command);
  const std::uint8_t node = node_of(command);
  if (!c.caller.authenticated) {
    const auto denial = auth::identify(c.caller, tokens_, settings_.anonymous_role);
    // Per caller, as the HTTP authorizer does per address, and before
    // anything is logged or done: a flood with bad tokens is limited too.
    if (!limiter_.allow(c.caller.key, net_.now())) {
      ++counters_.requests_rate_limited;
      auto p = problem(429, "too many requests from " + c.caller.key + "; slow down (http.rate-limit)", false);
      p.retry_after = 1;
      return c.done(std::move(p));
    }
    if (const auto& d = denial) {
      ++counters_.auth_failures;
      audit_("auth failure: " + requester(c.caller.who) + ": request to net " + std::to_string(c.network) + " node " +
             std::to_string(node) + ": " + std::to_string(d->status) + " " + d->detail);
      return c.done(problem(d->status, d->detail, false));
    }
  }
  if (c.network == 0 || c.network > net_.count()) {
    return c.done(problem(404,
                          "network " + std::to_string(c.network) + " is not configured (networks are 1.." +
                              std::to_string(net_.count()) + ")",
                          false));
  }
  const auto* bad = std::get_if<Undecodable>(&command);
  if (bad != nullptr && bad->in_address) return c.done(problem(400, bad->detail, false));
  const bool sdo_or_nmt = op == Operation::sdo_read || op == Operation::sdo_write || op == Operation::nmt;
  if (sdo_or_nmt) {
    if (auto p = bus_refused(c)) return c.done(std::move(*p));
  }
  if (op != Operation::sync && op != Operation::lss && (node > 127 || (node == 0 && op != Operation::nmt)))
    return c.done(problem(400, "node-ID " + std::to_string(node) + " is out of range 1..127", false));
  // NMT: once its command is known.
  if (op != Operation::nmt) {
    if (auto p = refused(c, required_role(op), operation_text(op), node, false)) return c.done(std::move(*p));
  }
  if (bad != nullptr) return c.done(problem(400, bad->detail, false));

  std::visit(
      [&](const auto& cmd) {
        using T = std::decay_t<decltype(cmd)>;
        if constexpr (std::is_same_v<T, SdoRead>) sdo_read(c, cmd);
        else if constexpr (std::is_same_v<T, SdoWrite>) sdo_write(c, cmd);
        else if constexpr (std::is_same_v<T, Nmt>) nmt(c, cmd);
        else if constexpr (std::is_same_v<T, RpdoWrite>) rpdo_write(c, cmd);
        else if constexpr (std::is_same_v<T, Sync>) sync(c, cmd);
        else if constexpr (std::is_same_v<T, PdoConfigRead>) pdo_config_read(c, cmd);
        else if constexpr (std::is_same_v<T, Undecodable>) {}  // answered above
        else if constexpr (std::is_same_v<T, NodeConfigRead> || std::is_same_v<T, NodeConfigWrite> ||
                           std::is_same_v<T, NodeEdsWrite>)
          c.done(problem(501, "not implemented yet (issue 17 in progress)"));
        // Remote maintenance (maintenance.cpp).
        else if constexpr (std::is_same_v<T, DcfRead>) dcf_read(c, cmd);
        else if constexpr (std::is_same_v<T, DcfApply>) dcf_apply(c, cmd);
        else if constexpr (std::is_same_v<T, NodeStore>) node_store(c, cmd);
        else if constexpr (std::is_same_v<T, ProgramDownload>)  // the image moves on, not copied
          program_download(c, std::move(std::get<ProgramDownload>(request.command)));
        else lss(c, command);  // the LSS commands
      },
      command);
}

// ---- SDO ---------------------------------------------------------------------

void RequestCore::sdo_read(Context& c, const SdoRead& cmd) {
  canopen::DataType type{};
  const canopen::od::SubEntry* entry = nullptr;
  if (cmd.node == net_.own_node_id(c.network)) {
    // The gateway's own node: its socket does not hear its own SDO request,
    // so the dictionary answers directly, with the same access rules.
    const auto& od = net_.own_dictionary(c.network);
    if (auto err = resolve_own_type(od, cmd.index, cmd.sub, cmd.type, type, &entry)) return c.done(std::move(*err));
    ++counters_.sdo_requests;
    auto bytes = od.read(cmd.index, cmd.sub);
    if (!bytes) return c.done(sdo_problem(bytes.error().code, true, bytes.error().detail));
    auto v = canopen::decode(type, *bytes);
    if (!v) {
      return c.done(problem(400, object_label(cmd.index, cmd.sub) + ": the value read is not a " +
                                     std::string(canopen::cia309_name(type)) + ": " + v.error().detail));
    }
    return c.done(SdoValue{std::move(*v)});
  }
  if (auto err = resolve_type(net_.description(c.network, cmd.node), cmd.index, cmd.sub, cmd.type, type, &entry))
    return c.done(std::move(*err));
  canopen::sdo::Request r;
  r.node = cmd.node;
  r.index = cmd.index;
  r.sub = cmd.sub;
  // The reply must decode as `type`, so a fixed-size type is the size to
  // expect: small objects then skip the block initiate (7.2.4.3.13), which
  // costs devices without block transfer a refusal. Strings and domains
  // stay unknown.
  r.expected_size = canopen::fixed_size(type);
  r.timeout = cmd.timeout;
  if (cmd.block) r.mode = *cmd.block ? canopen::sdo::Mode::Block : canopen::sdo::Mode::Segmented;
  if (auto full = take_sdo_place(c, cmd.node)) return c.done(std::move(*full));
  ++counters_.sdo_requests;
  r.on_done = [this, type, done = c.done, net = c.network, node = cmd.node, key = c.caller.key,
               t0 = net_.now()](canopen::sdo::TransferResult&& res) {
    place_freed(net, node, key);
    sdo_finished(t0);
    if (!res.ok()) return done(transfer_failed(res));
    auto v = canopen::decode(type, res.data);
    if (!v) {
      return done(problem(502, "the device answered " + std::to_string(res.data.size()) + " bytes, which is not a " +
                                   std::string(canopen::cia309_name(type)) + ": " + v.error().detail));
    }
    done(SdoValue{std::move(*v)});
  };
  if (auto full = submitted(c, net_.sdo_upload(c.network, std::move(r)), cmd.node)) c.done(std::move(*full));
}

void RequestCore::sdo_write(Context& c, const SdoWrite& cmd) {
  canopen::DataType type{};
  const canopen::od::SubEntry* entry = nullptr;
  const bool own = cmd.node == net_.own_node_id(c.network);
  if (auto err = own ? resolve_own_type(net_.own_dictionary(c.network), cmd.index, cmd.sub, cmd.type, type, &entry)
                     : resolve_type(net_.description(c.network, cmd.node), cmd.index, cmd.sub, cmd.type, type, &entry))
    return c.done(std::move(*err));
  // The value is checked against type and EDS limits before anything goes
  // on the bus; the errors name the object and the type.
  const std::string label = object_label(cmd.index, cmd.sub);
  auto value = canopen::value_from_json(type, cmd.value);
  if (!value) return c.done(problem(400, label + ": " + value.error().detail));
  if (entry != nullptr) {
    std::string detail;
    if (auto ec = canopen::check_limits(*value, entry->low, entry->high, &detail))
      return c.done(problem(400, label + ": " + detail));
  }
  ++counters_.sdo_requests;
  const canopen::Value written = *value;
  const std::string line = "SDO write by " + requester(c.caller.who) + ": net " + std::to_string(c.network) +
                           " node " + std::to_string(cmd.node) + " " + index_text(cmd.index) + " sub " +
                           std::to_string(cmd.sub) + " = " + canopen::format_value(written);
  if (own) {
    // As an SDO download would: access, length and limit checks, hooks and
    // observers (a write to 1016h reconfigures the heartbeat consumers).
    if (auto ec = net_.write_own(c.network, cmd.index, cmd.sub, canopen::encode(written))) {
      audit_(line + ": " + ec.message());
      return c.done(sdo_problem(ec, true));
    }
    audit_(line + ": ok");
    return c.done(SdoValue{written});
  }
  if (auto full = take_sdo_place(c, cmd.node)) {
    audit_(line + ": " + std::to_string(full->status) + " (" + c.caller.key +
           " has its share of the node's SDO queue)");
    return c.done(std::move(*full));
  }
  canopen::sdo::Request r;
  r.node = cmd.node;
  r.index = cmd.index;
  r.sub = cmd.sub;
  r.timeout = cmd.timeout;
  const auto size = canopen::encode(written).size();
  if (cmd.block)
    r.mode = *cmd.block ? canopen::sdo::Mode::Block
                        : (size >= 1 && size <= 4 ? canopen::sdo::Mode::Expedited : canopen::sdo::Mode::Segmented);
  r.on_done = [this, done = c.done, written, line, net = c.network, node = cmd.node, key = c.caller.key,
               t0 = net_.now()](canopen::sdo::TransferResult&& res) {
    place_freed(net, node, key);
    sdo_finished(t0);
    if (!res.ok()) {
      audit_(line + ": " + res.error.message());
      return done(transfer_failed(res));
    }
    audit_(line + ": ok");
    done(SdoValue{written});
  };
  if (auto full = submitted(c, net_.sdo_download(c.network, std::move(r), canopen::encode(written)), cmd.node))
    c.done(std::move(*full));
}

std::optional<Problem> RequestCore::take_sdo_place(const Context& c, std::uint8_t node) {
  if (shares_.take(sdo_queue_key(c.network, node), c.caller.key)) return std::nullopt;
  ++counters_.sdo_share_refused;
  const std::string who = c.caller.key.empty() ? std::string("this caller") : c.caller.key;
  auto p = problem(429, who + " has " + std::to_string(shares_.share()) + " SDO requests waiting for node " +
                            std::to_string(node) + " already, its share of the node's queue of " +
                            std::to_string(settings_.sdo_queue_limit) +
                            "; send more once one is answered (other callers still get in)");
  p.retry_after = 1;
  return p;
}

void RequestCore::place_freed(std::uint32_t net, std::uint8_t node, const std::string& key) {
  shares_.give_back(sdo_queue_key(net, node), key);
}

std::optional<Problem> RequestCore::submitted(const Context& c, const canopen::Result<canopen::sdo::RequestId>& id,
                                              std::uint8_t node) {
  if (id) return std::nullopt;
  // Queue full for the node (060A0023h): the client should come back later.
  place_freed(c.network, node, c.caller.key);  // the handler that would give it back never runs
  auto p = problem(429, "too many SDO requests queued for node " + std::to_string(node));
  p.retry_after = 1;
  return p;
}

void RequestCore::sdo_finished(std::chrono::steady_clock::time_point submitted_at) {
  const double s = std::chrono::duration<double>(net_.now() - submitted_at).count();
  const auto& bounds = Counters::kSdoLatencyBounds;
  const auto slot = static_cast<std::size_t>(std::lower_bound(bounds.begin(), bounds.end(), s) - bounds.begin());
  ++counters_.sdo_latency_counts[slot];
  counters_.sdo_latency_sum += s;
  ++counters_.sdo_latency_count;
}

Problem RequestCore::transfer_failed(const canopen::sdo::TransferResult& res) {
  const bool remote = res.origin == canopen::sdo::Origin::Remote;
  if (remote) ++counters_.sdo_aborts;
  if (res.error == make_error_code(canopen::SdoAbort::Timeout)) ++counters_.sdo_timeouts;
  return sdo_problem(res.error, remote, res.detail);
}

// ---- NMT, RPDO, SYNC, PDO configuration --------------------------------------

void RequestCore::nmt(Context& c, const Nmt& cmd) {
  const std::string name(nmt_command_name(cmd.command));
  if (auto p = refused(c, required_role(Operation::nmt, cmd.command), "NMT " + name, cmd.node, true))
    return c.done(std::move(*p));
  ++counters_.nmt_commands;
  net_.send_nmt(c.network, cmd.command, cmd.node);
  audit_("NMT " + name + " by " + requester(c.caller.who) + ": net " + std::to_string(c.network) + " node " +
         std::to_string(cmd.node) + ": sent");
  c.done(NmtSent{c.network, cmd.node, cmd.command});
}

void RequestCore::rpdo_write(Context& c, const RpdoWrite& cmd) {
  const auto* desc = net_.description(c.network, cmd.node);
  const std::string what = "node " + std::to_string(cmd.node) + " RPDO" + std::to_string(cmd.number);
  if (desc == nullptr)
    return c.done(problem(404, "node " + std::to_string(cmd.node) + " has no EDS/DCF, so its RPDOs are unknown"));
  // The configuration in effect: the EDS/DCF's unless SDO writes or a read
  // from the device changed it (GET .../pdo shows it).
  const auto* in_effect = net_.rpdo_config(c.network, cmd.node, cmd.number);
  if (in_effect == nullptr)
    return c.done(problem(404, what + " is not in use (not in its EDS/DCF, disabled by COB-ID bit 31, or "
                                      "its mapping does not resolve; see GET .../pdo)"));
  const canopen::pdo::PdoConfig cfg = *in_effect;  // a copy: the pointer lives only until the next change
  std::string error;
  auto body = rest::parse_rpdo_body(cmd.body, cfg, desc->od, what, error);
  if (!body) return c.done(problem(400, error));
  if (auto p = bus_refused(c)) return c.done(std::move(*p));
  const std::string line = "RPDO write by " + requester(c.caller.who) + ": net " + std::to_string(c.network) +
                           " node " + std::to_string(cmd.node) + " RPDO" + std::to_string(cmd.number);
  RpdoSent sent{c.network, cmd.node, cmd.number, cfg.comm.cob_id.can_id(), cfg.comm.transmission_type, {}};
  if (auto ec = net_.write_rpdo(c.network, cmd.node, cmd.number, body->values, body->raw ? &*body->raw : nullptr,
                                sent.raw)) {
    audit_(line + ": " + ec.message());
    const int status = ec == make_error_code(canopen::SdoAbort::NoSuchObject) ? 404 : 400;
    return c.done(problem(status, what + ": " + ec.message()));
  }
  audit_(line + " = " + hex_bytes(sent.raw) + ": sent");
  c.done(std::move(sent));
}

void RequestCore::sync(Context& c, const Sync& cmd) {
  if (auto p = bus_refused(c)) return c.done(std::move(*p));
  net_.send_sync(c.network, cmd.counter);
  audit_("SYNC by " + requester(c.caller.who) + ": net " + std::to_string(c.network) +
         (cmd.counter ? " counter " + std::to_string(*cmd.counter) : std::string()) + ": sent");
  c.done(SyncSent{c.network, cmd.counter});
}

void RequestCore::pdo_config_read(Context& c, const PdoConfigRead& cmd) {
  if (!net_.has_pdo_table(c.network, cmd.node))
    return c.done(problem(404, "node " + std::to_string(cmd.node) + " on network " + std::to_string(c.network) +
                                   " has no EDS/DCF, so its PDOs are not decoded"));
  if (auto p = bus_refused(c)) return c.done(std::move(*p));
  const std::string line = "PDO configuration read by " + requester(c.caller.who) + ": net " +
                           std::to_string(c.network) + " node " + std::to_string(cmd.node);
  auto ec = net_.read_pdo_config(
      c.network, cmd.node,
      [this, line, done = c.done, net = c.network, node = cmd.node](const canopen::pdo::PdoReadReport& r) {
        audit_(line + ": " + r.summary());
        if (r.cancelled)
          return done(problem(503, "node " + std::to_string(node) + " booted during the read; " + r.summary()));
        if (r.stopped) return done(problem(r.stopped == make_error_code(canopen::SdoAbort::Timeout) ? 504 : 502,
                                           r.summary()));
        done(PdoConfigReport{net, node, r});
      });
  if (!ec) return;
  audit_(line + ": " + ec.message());
  if (ec == make_error_code(canopen::SdoAbort::NoSdoConnection))
    return c.done(problem(429, "too many SDO requests queued for node " + std::to_string(cmd.node)));
  c.done(problem(404, "node " + std::to_string(cmd.node) + ": " + ec.message()));
}

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
  if (const auto* f = std::get_if<LssFastscan>(&cmd)) {
    run->line = "LSS fastscan by " + who + ": " + net;
    steps = {waiting, *f};
  } else if (const auto* k = std::get_if<LssConfigure>(&cmd)) {
    run->line = "LSS configure by " + who + ": " + net + " " + canopen::lss::to_string(k->address) + " -> node-ID " +
                std::to_string(k->node_id) + (k->bitrate ? ", " + std::to_string(*k->bitrate) + " bit/s" : "") +
                (k->store ? ", store" : "");
    run->pending = LssAssignment{k->address, k->node_id, k->bitrate, false};
    steps = {waiting, LssSwitchSelective{k->address}, LssSetNodeId{k->node_id}};
    if (k->bitrate) steps.push_back(LssSetBitTiming{0, *canopen::lss::bit_timing_index(*k->bitrate)});
    if (k->store) steps.push_back(LssStore{});
    steps.push_back(waiting);
  } else if (const auto* a = std::get_if<LssAssignAll>(&cmd)) {
    run->line = "LSS assign-all by " + who + ": " + net + " from node-ID " + std::to_string(a->first_node_id) +
                (a->store ? ", store" : "");
    run->next_id = a->first_node_id;
    steps = {waiting, LssFastscan{a->timeout}};
  } else if (const auto* g = std::get_if<LssSwitchGlobal>(&cmd)) {
    run->line = "LSS switch state global " + std::string(g->configuration ? "configuration" : "waiting") + " by " +
                who + ": " + net;
    steps = {*g};
  } else if (const auto* sel = std::get_if<LssSwitchSelective>(&cmd)) {
    run->line = "LSS switch state selective by " + who + ": " + net + " " + canopen::lss::to_string(sel->address);
    steps = {*sel};
  } else if (const auto* n = std::get_if<LssSetNodeId>(&cmd)) {
    run->line = "LSS configure node-ID " + std::to_string(n->node_id) + " by " + who + ": " + net;
    steps = {*n};
  } else if (const auto* b = std::get_if<LssSetBitTiming>(&cmd)) {
    run->line = "LSS configure bit timing " + std::to_string(b->table) + "/" + std::to_string(b->index) + " by " +
                who + ": " + net;
    steps = {*b};
  } else if (const auto* act = std::get_if<LssActivateBitTiming>(&cmd)) {
    run->line = "LSS activate bit timing (delay " + std::to_string(act->delay_ms) + " ms) by " + who + ": " + net;
    steps = {*act};
  } else if (std::holds_alternative<LssStore>(cmd)) {
    run->line = "LSS store configuration by " + who + ": " + net;
    steps = {LssStore{}};
  } else if (const auto* q = std::get_if<LssInquire>(&cmd)) {
    run->line = "LSS inquire by " + who + ": " + net;
    run->inquired.what = q->what;
    if (q->what) {
      steps = {*q->what};
    } else {
      steps = {LssInquiry::vendor_id, LssInquiry::product_code, LssInquiry::revision, LssInquiry::serial};
    }
  } else {
    return c.done(problem(500, "not an LSS command"));
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

// ---- shared checks -----------------------------------------------------------

std::optional<Problem> RequestCore::refused(const Context& c, Role need, std::string_view what, std::uint8_t node,
                                            bool command_read) {
  auto d = auth::check_role(c.caller, need);
  if (!d) return std::nullopt;
  ++counters_.auth_failures;
  audit_("auth failure: " + requester(c.caller.who) + ": " + std::string(what) + " net " + std::to_string(c.network) +
         " node " + std::to_string(node) + ": " + std::to_string(d->status) + " " + d->detail);
  return problem(d->status, d->detail, command_read);
}

std::optional<Problem> RequestCore::bus_refused(const Context& c) const {
  if (!c.check_bus) return std::nullopt;
  const auto state = net_.bus_state(c.network);
  if (state && (*state == canopen::can::BusState::BusOff || *state == canopen::can::BusState::Down))
    return problem(503, "network " + std::to_string(c.network) + " is " + std::string(canopen::can::to_string(*state)),
                   false);
  return std::nullopt;
}

}  // namespace gateway::core
