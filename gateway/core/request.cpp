#include "core/request.hpp"

#include <boost/json/object.hpp>
#include <boost/json/serialize.hpp>

#include "canopen/sdo/abort.hpp"
#include "core/format.hpp"
#include "http_status.hpp"

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

std::string utf8(std::string_view s) { return canopen::is_utf8(s) ? std::string(s) : canopen::latin1_to_utf8(s); }

}  // namespace

std::string problem_json(const Problem& p, std::string_view correlation_id) {
  boost::json::object o;
  o["type"] = p.type.empty() ? std::string("about:blank") : utf8(p.type);
  o["title"] = p.title.empty() ? std::string(reason_phrase(p.status)) : utf8(p.title);
  o["status"] = p.status;
  o["detail"] = utf8(p.detail);
  if (p.abort_code) o["abortCode"] = abort_code_text(*p.abort_code);
  if (!correlation_id.empty()) o["correlationId"] = utf8(correlation_id);
  return boost::json::serialize(o);
}

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
  switch (op) {
    case Operation::sdo_read:
      return Role::Viewer;
    case Operation::nmt:
      // Reset node / reset communication (CiA 301 7.2.8.3.1) need admin; a
      // command not known yet is treated as the most privileged.
      return !nmt || *nmt == canopen::NmtCommand::ResetNode || *nmt == canopen::NmtCommand::ResetCommunication
                 ? Role::Admin
                 : Role::Operator;
    case Operation::lss:
      return Role::Admin;  // contract "LSS master (CiA 305), REST (role admin)"
    // contract "Remote configuration and maintenance (role admin unless noted)"
    case Operation::config_read:
    case Operation::dcf_read:
      return Role::Viewer;
    case Operation::store:
      return Role::Operator;
    case Operation::config_write:
    case Operation::dcf_write:
    case Operation::program:
      return Role::Admin;
    case Operation::sdo_write:
    case Operation::rpdo_write:
    case Operation::sync:
    case Operation::pdo_config_read:
      return Role::Operator;
  }
  return Role::Admin;
}

namespace {
struct RoleOf {
  Role operator()(const SdoRead&) const { return required_role(Operation::sdo_read); }
  Role operator()(const SdoWrite&) const { return required_role(Operation::sdo_write); }
  Role operator()(const Nmt& n) const { return required_role(Operation::nmt, n.command); }
  Role operator()(const RpdoWrite&) const { return required_role(Operation::rpdo_write); }
  Role operator()(const Sync&) const { return required_role(Operation::sync); }
  Role operator()(const PdoConfigRead&) const { return required_role(Operation::pdo_config_read); }
  Role operator()(const Undecodable& u) const { return required_role(u.operation); }
  Role operator()(const NodeConfigRead&) const { return required_role(Operation::config_read); }
  Role operator()(const NodeConfigWrite&) const { return required_role(Operation::config_write); }
  Role operator()(const NodeEdsWrite&) const { return required_role(Operation::config_write); }
  Role operator()(const DcfRead&) const { return required_role(Operation::dcf_read); }
  Role operator()(const DcfApply&) const { return required_role(Operation::dcf_write); }
  Role operator()(const NodeStore&) const { return required_role(Operation::store); }
  Role operator()(const ProgramDownload&) const { return required_role(Operation::program); }
  Role operator()(const auto&) const { return required_role(Operation::lss); }  // the LSS commands
};
}  // namespace

Role required_role(const Command& command) { return std::visit(RoleOf{}, command); }

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
