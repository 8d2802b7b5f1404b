// Run-time node configuration in the request core (contract "Remote
// configuration and maintenance"): GET/PUT/DELETE .../config and PUT
// .../eds. The role, network and node-ID are checked by execute(); here the
// gateway's own node is refused, settings the front end could not decode
// and settings for another node are refused, an EDS/DCF is read exactly as
// `canopen-eds check` reads it, and every change gets an audit line.
#include <string>

#include "canopen/eds/eds.hpp"
#include "core/core_helpers.hpp"
#include "core/node_settings.hpp"
#include "core/request_core.hpp"

namespace gateway::core {

void RequestCore::node_config(const Caller& caller, std::uint32_t net, const Command& command, const Done& done) {
  const std::uint8_t node = std::visit(
      [](const auto& c) -> std::uint8_t {
        if constexpr (requires { c.node; }) return c.node;
        else return 0;
      },
      command);
  if (node_settings_ == nullptr) {
    Problem p;
    p.status = 500;
    p.detail = "run-time node configuration is not available in this process";
    return done(std::move(p));
  }
  if (node == net_.own_node_id(net)) {
    return done(detail::problem(400, "node " + std::to_string(node) + " is the gateway's own node-ID on network " +
                            std::to_string(net) + "; its settings are the network's (heartbeat-ms, sync, time)"));
  }
  if (std::holds_alternative<NodeConfigRead>(command)) return done(node_settings_->node_config(net, node));

  const std::string where = "net " + std::to_string(net) + " node " + std::to_string(node);
  Result result;
  std::string what;
  if (const auto* w = std::get_if<NodeConfigWrite>(&command)) {
    if (w->revert) {
      what = "configuration reverted to the configuration file";
      result = node_settings_->revert_node_config(net, node);
    } else {
      what = "configuration changed";
      if (!w->invalid.empty()) {
        result = detail::problem(400, w->invalid);
      } else if (w->settings.id != node) {
        result = detail::problem(400, "request body: id: " + std::to_string(w->settings.id) +
                                          " is not the node of the path (" + std::to_string(node) + ")");
      } else {
        result = node_settings_->write_node_config(net, node, w->settings);
      }
    }
  } else {
    const auto& e = std::get<NodeEdsWrite>(command);
    const std::string name = e.file_name.empty() ? "node" + std::to_string(node) + ".eds" : e.file_name;
    what = "EDS/DCF " + name + " uploaded";
    if (e.text.empty()) {
      result = detail::problem(400, name + ": empty: the body is the EDS or DCF file");
    } else {
      // As `canopen-eds check --node-id N` and the start-up read it: the
      // node's ID resolves $NODEID and wins over a DCF's NodeID.
      try {
        auto desc = canopen::eds::parse_device_description(e.text, name, node);
        auto warnings = desc.warnings;
        result = node_settings_->write_node_eds(net, node, std::move(desc), e.text);
        if (auto* view = std::get_if<NodeConfigView>(&result)) {
          view->warnings = std::move(warnings);
          view->eds_name = name;
        }
      } catch (const canopen::eds::EdsError& err) {
        result = detail::problem(400, err.what());
      }
    }
  }
  if (const auto* p = std::get_if<Problem>(&result)) {
    audit_("node configuration refused: " + detail::requester(caller.who) + ": " + where + ": " + what + ": " +
           std::to_string(p->status) + " " + p->detail);
  } else {
    const auto& v = std::get<NodeConfigView>(result);
    audit_("node configuration: " + detail::requester(caller.who) + ": " + where + ": " + what + " (settings from " + v.source +
           (v.file.empty() ? std::string() : " " + v.file) + ")");
  }
  done(std::move(result));
}

}  // namespace gateway::core
