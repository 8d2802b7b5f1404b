// Roles of API callers (REST, WebSocket, MQTT requests), ordered: each role
// may do everything the ones below it may.
//   viewer:   reads (nodes, OD, SDO upload, EMCY, metrics) and the event stream
//   operator: SDO download, RPDO write, SYNC, NMT start/stop/pre-operational
//   admin:    NMT reset node / reset communication, configuration
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace gateway {

enum class Role : std::uint8_t { None = 0, Viewer = 1, Operator = 2, Admin = 3 };

constexpr std::string_view to_string(Role r) {
  switch (r) {
    case Role::Viewer:
      return "viewer";
    case Role::Operator:
      return "operator";
    case Role::Admin:
      return "admin";
    case Role::None:
      break;
  }
  return "none";
}

constexpr std::optional<Role> role_from_string(std::string_view s) {
  if (s == "viewer") return Role::Viewer;
  if (s == "operator") return Role::Operator;
  if (s == "admin") return Role::Admin;
  if (s == "none") return Role::None;
  return std::nullopt;
}

constexpr bool allows(Role have, Role need) { return static_cast<int>(have) >= static_cast<int>(need); }

}  // namespace gateway
