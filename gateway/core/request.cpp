#include "core/request.hpp"

#include "canopen/sdo/abort.hpp"
#include "core/operation.hpp"

namespace gateway::core {

namespace {

std::string abort_detail(std::uint32_t code, std::string_view context) {
  std::string d(canopen::sdo_abort_text(code));
  if (!context.empty()) {
    d += ": ";
    d += context;
  }
  return d;
}

}  // namespace

Problem sdo_problem(std::error_code ec, bool remote, std::string_view context) {
  const std::uint32_t code = canopen::to_abort_code(ec);
  Problem p;
  p.status = 422;
  p.detail = abort_detail(code, context);
  p.abort_code = code;
  if (remote) {
    p.title = "SDO abort";
  } else if (code == static_cast<std::uint32_t>(canopen::SdoAbort::Timeout)) {
    p.status = 504;
    p.title = "SDO timeout";
  } else {
    p.status = 502;
    p.title = "SDO transfer failed";
  }
  return p;
}


Role required_role(Operation op, std::optional<canopen::NmtCommand> nmt) {
  // Reset node / reset communication (CiA 301 7.2.8.3.1) need admin; a
  // command not known yet is treated as the most privileged.
  if (op == Operation::nmt && (!nmt || *nmt == canopen::NmtCommand::ResetNode ||
                               *nmt == canopen::NmtCommand::ResetCommunication))
    return Role::Admin;
  return describe(op).role;
}

Role required_role(const Command& command) {
  // NMT's role depends on its command; every other one on its operation alone.
  if (const auto* n = std::get_if<Nmt>(&command)) return required_role(Operation::nmt, n->command);
  return required_role(operation_of(command));
}

std::string_view to_string(Transport t) {
  switch (t) {
    case Transport::rest: return "REST";
    case Transport::mqtt: return "MQTT";
    case Transport::websocket: return "WebSocket";
    case Transport::ascii: return "ASCII";
    case Transport::sparkplug: return "Sparkplug";
  }
  return "unknown";
}

std::string_view nmt_command_name(canopen::NmtCommand c) {
  using C = canopen::NmtCommand;
  switch (c) {
    case C::Start: return "start";
    case C::Stop: return "stop";
    case C::EnterPreOperational: return "preop";
    case C::ResetNode: return "reset-node";
    case C::ResetCommunication: return "reset-comm";
  }
  return "unknown";
}

std::optional<canopen::NmtCommand> nmt_command_from_name(std::string_view s) {
  using C = canopen::NmtCommand;
  for (C c : {C::Start, C::Stop, C::EnterPreOperational, C::ResetNode, C::ResetCommunication}) {
    if (nmt_command_name(c) == s) return c;
  }
  return std::nullopt;
}

}  // namespace gateway::core
