// App's run-time node configuration (core::NodeSettings, node_config.cpp):
// a node's new settings or EDS/DCF are checked, kept durably in state-dir
// (node_overlay.hpp) and then applied to its NetworkUnit (decoding,
// watching, 1016h, boot-up configuration, OD and SDO typing), the state
// cache (name) and, when enabled, Sparkplug (a new DBIRTH). Nothing changes
// when a check or the write to state-dir fails. Without a state-dir
// (a Config built by hand) changes are refused with 409: a change that
// would be gone after a restart is not what a user of the API expects.
//
// Thread safety: io thread only (App's).
#pragma once

#include "app/app.hpp"
#include "core/node_settings.hpp"

namespace gateway {

struct App::NodeConfigs final : core::NodeSettings {
  explicit NodeConfigs(App& a) : app(a) {}
  core::NodeConfigView node_config(std::uint32_t net, std::uint8_t node) const override;
  core::Result write_node_config(std::uint32_t net, std::uint8_t node, const NodeConfig& settings) override;
  core::Result write_node_eds(std::uint32_t net, std::uint8_t node, canopen::eds::DeviceDescription description,
                              std::string_view text) override;
  core::Result revert_node_config(std::uint32_t net, std::uint8_t node) override;

 private:
  // Checks, keeps (settings file; `eds_text` to `eds_file` first when
  // given) and applies `node`; the problem otherwise, nothing changed.
  core::Result change(std::uint32_t net, NodeConfig node, std::optional<canopen::eds::DeviceDescription> description,
                      std::string_view eds_text = {}, const std::string& eds_file = {});
  // Applies to the unit and everything that shows the node.
  void apply(std::uint32_t net, const NodeConfig& node, std::optional<canopen::eds::DeviceDescription> description);

  App& app;
};

}  // namespace gateway
