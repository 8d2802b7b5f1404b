#include "ascii/ascii_lss.hpp"

#include <string>
#include <type_traits>
#include <variant>

#include "core/request_core.hpp"

namespace gateway::ascii {

namespace {

// A refusal or failure of the core as CANopenNode's gateway answers an LSS
// command (its error codes, facts B.1).
std::string problem_text(std::uint32_t seq, const core::Problem& p) {
  if (p.lss_error) {
    switch (*p.lss_error) {
      case core::LssError::node_id_not_supported: return error_response(seq, Error::LssNodeIdNotSupported);
      case core::LssError::bitrate_not_supported: return error_response(seq, Error::LssBitrateNotSupported);
      case core::LssError::store_not_supported: return error_response(seq, Error::LssStoreFailed);
      case core::LssError::store_media_error: return error_response(seq, Error::LssMedia);
      case core::LssError::manufacturer:
      case core::LssError::other: return error_response(seq, Error::LssManufacturer);
    }
  }
  if (auto refused = role_refusal(seq, p.status, p.detail)) return *refused;  // not for this client's role
  switch (p.status) {
    case 400: return error_response(seq, Error::Syntax);
    // An unknown network is refused before the command is read; a fastscan
    // that nobody answered is a 404 too: for CiA 309-3 a time-out.
    case 404: return error_response(seq, p.command_read ? Error::Timeout : Error::UnsupportedNet);
    case 504: return error_response(seq, Error::Timeout);
    default: return error_response(seq, Error::InternalState);  // 409 another LSS operation, 503 bus down
  }
}

std::optional<core::LssInquiry> inquiry_of(std::uint8_t lss_sub) {
  switch (lss_sub) {
    case 0: return core::LssInquiry::vendor_id;
    case 1: return core::LssInquiry::product_code;
    case 2: return core::LssInquiry::revision;
    case 3: return core::LssInquiry::serial;
    default: return std::nullopt;
  }
}

// The core command of an ASCII LSS command; nullopt: not supported.
std::optional<core::Command> command_of(const LssCommand& cmd) {
  return std::visit(
      [](const auto& c) -> std::optional<core::Command> {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, LssSwitchGlobal>) {
          return core::LssSwitchGlobal{c.configuration};
        } else if constexpr (std::is_same_v<T, LssSwitchSelective>) {
          return core::LssSwitchSelective{c.identity};
        } else if constexpr (std::is_same_v<T, LssSetNode>) {
          return core::LssSetNodeId{c.node};
        } else if constexpr (std::is_same_v<T, LssConfigureBitrate>) {
          return core::LssSetBitTiming{c.table_selector, c.table_index};
        } else if constexpr (std::is_same_v<T, LssActivateBitrate>) {
          return core::LssActivateBitTiming{c.switch_delay_ms};
        } else if constexpr (std::is_same_v<T, LssStore>) {
          return core::LssStore{};
        } else if constexpr (std::is_same_v<T, LssInquireAddress>) {
          if (!c.lss_sub) return core::LssInquire{};
          auto what = inquiry_of(*c.lss_sub);
          if (!what) return std::nullopt;
          return core::LssInquire{what};
        } else if constexpr (std::is_same_v<T, LssGetNode>) {
          return core::LssInquire{core::LssInquiry::node_id};
        } else if constexpr (std::is_same_v<T, LssFastscan>) {
          return core::LssFastscan{std::chrono::milliseconds(c.timeout_ms == 0 ? 100 : c.timeout_ms)};
        } else {
          static_assert(std::is_same_v<T, LssAllNodes>);
          // Only a fastscan of all four words: ignore/match scan types are not done.
          for (auto s : c.scan)
            if (s != LssScan::scan) return std::nullopt;
          return core::LssAssignAll{c.first_node, c.store,
                                    std::chrono::milliseconds(c.timeout_ms == 0 ? 100 : c.timeout_ms)};
        }
      },
      cmd);
}

std::string answer(std::uint32_t seq, const LssCommand& cmd, const core::Result& result) {
  if (const auto* p = std::get_if<core::Problem>(&result)) return problem_text(seq, *p);
  if (const auto* f = std::get_if<core::LssFound>(&result)) return lss_identity_response(seq, f->address);
  if (const auto* q = std::get_if<core::LssInquired>(&result)) {
    if (std::holds_alternative<LssGetNode>(cmd)) return lss_node_response(seq, static_cast<std::uint8_t>(q->value));
    if (!q->what) return lss_identity_response(seq, q->address);
    return lss_word_response(seq, q->value);
  }
  if (const auto* a = std::get_if<core::LssAssigned>(&result)) {
    std::string text;
    for (const auto& as : a->assignments) text += lss_assigned_line(as.node_id, as.address);
    return text + lss_allnodes_finished(seq, static_cast<unsigned>(a->assignments.size()));
  }
  return ok_response(seq);
}

}  // namespace

LssHandler make_lss_handler(core::RequestCore& core) {
  return [&core](const LssRequest& req, LssReply reply) {
    auto command = command_of(req.command);
    if (!command) return reply(error_response(req.seq, Error::RequestNotSupported));
    core::Request r;
    r.caller = req.caller;
    r.network = req.network;
    r.command = std::move(*command);
    r.check_bus = true;  // answered 102 while the bus is off or down rather than waiting
    core.execute(std::move(r), [reply, seq = req.seq, cmd = req.command](core::Result result) {
      reply(answer(seq, cmd, result));
    });
  };
}

}  // namespace gateway::ascii
