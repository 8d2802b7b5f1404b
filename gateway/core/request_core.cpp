#include "core/request_core.hpp"

#include <algorithm>
#include <deque>

#include "canopen/eds/eds.hpp"
#include "canopen/literal.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "core/core_helpers.hpp"
#include "core/format.hpp"
#include "core/operation.hpp"
#include "core/rpdo_values.hpp"

namespace gateway::core {

namespace {

using detail::problem;
using detail::requester;
using detail::sdo_queue_key;

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
  const OperationInfo info = describe(op);
  if (info.bus_first) {
    if (auto p = bus_refused(c)) return c.done(std::move(*p));
  }
  if (info.node != NodeRule::network && (node > 127 || (node == 0 && info.node != NodeRule::node_or_all)))
    return c.done(problem(400, "node-ID " + std::to_string(node) + " is out of range 1..127", false));
  // NMT: once its command is known.
  if (op != Operation::nmt) {
    if (auto p = refused(c, required_role(op), info.text, node, false)) return c.done(std::move(*p));
  }
  if (bad != nullptr) return c.done(problem(400, bad->detail, false));

  std::visit(Overloaded{
                 [&](const SdoRead& cmd) { sdo_read(c, cmd); },
                 [&](const SdoWrite& cmd) { sdo_write(c, cmd); },
                 [&](const Nmt& cmd) { nmt(c, cmd); },
                 [&](const RpdoWrite& cmd) { rpdo_write(c, cmd); },
                 [&](const Sync& cmd) { sync(c, cmd); },
                 [&](const PdoConfigRead& cmd) { pdo_config_read(c, cmd); },
                 [&](const Undecodable&) {},  // answered above
                 // Run-time node configuration (node_config.cpp).
                 [&](const NodeConfigRead&) { node_config(c.caller, c.network, command, c.done); },
                 [&](const NodeConfigWrite&) { node_config(c.caller, c.network, command, c.done); },
                 [&](const NodeEdsWrite&) { node_config(c.caller, c.network, command, c.done); },
                 // Remote maintenance (maintenance.cpp).
                 [&](const DcfRead& cmd) { dcf_read(c, cmd); },
                 [&](const DcfApply& cmd) { dcf_apply(c, cmd); },
                 [&](const NodeStore& cmd) { node_store(c, cmd); },
                 [&](const ProgramDownload&) {  // the image moves on, not copied
                   program_download(c, std::move(std::get<ProgramDownload>(request.command)));
                 },
                 [&]<typename T>(const T&)
                   requires is_lss_command<T>
                 { lss(c, command); },
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
  const auto* typed = std::get_if<canopen::Value>(&cmd.value);
  const auto requested = typed != nullptr ? std::optional<canopen::DataType>(typed->type) : cmd.type;
  if (auto err = own ? resolve_own_type(net_.own_dictionary(c.network), cmd.index, cmd.sub, requested, type, &entry)
                     : resolve_type(net_.description(c.network, cmd.node), cmd.index, cmd.sub, requested, type, &entry))
    return c.done(std::move(*err));
  // The value is checked against type and EDS limits before anything goes
  // on the bus; the errors name the object and the type.
  const std::string label = object_label(cmd.index, cmd.sub);
  auto value = typed != nullptr ? canopen::Result<canopen::Value>(*typed)
                                : canopen::value_from_literal(type, std::get<canopen::Literal>(cmd.value));
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
  auto body = typed_rpdo_values(cmd, cfg, desc->od, what, error);
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
