// The gateway's run-time node configuration as the request core needs it
// (contract "Remote configuration and maintenance": GET/PUT/DELETE
// .../nodes/{node}/config, PUT .../nodes/{node}/eds). The process (App)
// implements it over its networks and state-dir; the core's tests fake it.
// The core has checked the caller's role, the network and the node-ID
// (1..127, not the gateway's own) before any call.
//
// Thread safety: the io thread only, as RequestCore.
#pragma once

#include <cstdint>
#include <string_view>

#include "canopen/eds/eds.hpp"
#include "core/request.hpp"

namespace gateway::core {

class NodeSettings {
 public:
  virtual ~NodeSettings() = default;
  // The node's settings (its `nodes:` entry) and where they come from.
  virtual NodeConfigView node_config(std::uint32_t net, std::uint8_t node) const = 0;
  // Applies `settings` (decoded by the configuration file's rules, for this
  // node) at once and keeps them in state-dir (409 when there is none; 400
  // when its EDS/DCF cannot be read). Answers NodeConfigView or Problem; a
  // Problem changes nothing.
  virtual Result write_node_config(std::uint32_t net, std::uint8_t node, const NodeConfig& settings) = 0;
  // Uses `description` (already accepted by the EDS reader) for the node at
  // once, keeps `text` in state-dir and makes it the node's eds. As above.
  virtual Result write_node_eds(std::uint32_t net, std::uint8_t node, canopen::eds::DeviceDescription description,
                                std::string_view text) = 0;
  // Drops what state-dir holds for the node: the configuration file's
  // settings (or none) apply again, at once. As above.
  virtual Result revert_node_config(std::uint32_t net, std::uint8_t node) = 0;
};

}  // namespace gateway::core
