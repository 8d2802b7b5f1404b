// One descriptor per operation, and which operation each Command alternative
// is. The core decides everything about a request from these (role, node
// rule, when the bus is checked, the audit text), so there is no catch-all
// anywhere: a Command alternative without its own operation_of() overload
// does not compile (the static_assert below says which header to change),
// and a new Operation without a describe() case is a -Wswitch error.
//
// Adding an operation: its Operation, Command and Result in request.hpp; here
// one operation_of() overload (or is_lss_command for an LSS service) and its
// describe() case; its handler in RequestCore::execute's dispatcher, which
// does not compile without one.
//
// Pure constexpr functions; thread-safe.
#pragma once

#include <concepts>
#include <string_view>
#include <type_traits>
#include <variant>

#include "core/request.hpp"

namespace gateway::core {

// Which node-IDs an operation takes.
enum class NodeRule : std::uint8_t {
  network,      // none: the whole network (SYNC, LSS)
  node,         // 1..127
  node_or_all,  // 0..127, 0 = every node (NMT)
};

struct OperationInfo {
  // What an audit line and a role refusal call it ("SDO write", "LSS").
  std::string_view text;
  // The role it needs (contract "Roles"). NMT: the role of start, stop and
  // pre-operational; its resets need admin (required_role(Command)).
  Role role = Role::Admin;
  NodeRule node = NodeRule::node;
  // Refused while the bus is down before the node-ID and role are looked
  // at (SDO and NMT: what is asked cannot happen anyway). The others check
  // the bus once their own checks passed, or not at all.
  bool bus_first = false;
};

// Roles: reads viewer, writes and process data operator, what changes a
// device's identity or configuration admin (contract "Roles", "LSS master
// (CiA 305), REST (role admin)", "Remote configuration and maintenance
// (role admin unless noted)").
constexpr OperationInfo describe(Operation op) {
  using enum Role;
  switch (op) {
    case Operation::sdo_read: return {"SDO read", Viewer, NodeRule::node, true};
    case Operation::sdo_write: return {"SDO write", Operator, NodeRule::node, true};
    case Operation::nmt: return {"NMT", Operator, NodeRule::node_or_all, true};
    case Operation::rpdo_write: return {"RPDO write", Operator, NodeRule::node, false};
    case Operation::sync: return {"SYNC", Operator, NodeRule::network, false};
    case Operation::pdo_config_read: return {"PDO configuration read", Operator, NodeRule::node, false};
    case Operation::lss: return {"LSS", Admin, NodeRule::network, false};
    case Operation::config_read: return {"configuration read", Viewer, NodeRule::node, false};
    case Operation::config_write: return {"configuration change", Admin, NodeRule::node, false};
    case Operation::dcf_read: return {"DCF read", Viewer, NodeRule::node, false};
    case Operation::dcf_write: return {"DCF apply", Admin, NodeRule::node, false};
    case Operation::store: return {"store/restore", Operator, NodeRule::node, false};
    case Operation::program: return {"program download", Admin, NodeRule::node, false};
  }
  return {"request", Admin, NodeRule::node, false};  // not reached: the switch covers every Operation
}

// The LSS services (CiA 305): one operation, role admin, network-wide, one
// at a time per network (RequestCore::lss). Listed one by one, so a new
// command is never LSS by accident.
template <typename T>
inline constexpr bool is_lss_command = false;
template <> inline constexpr bool is_lss_command<LssFastscan> = true;
template <> inline constexpr bool is_lss_command<LssConfigure> = true;
template <> inline constexpr bool is_lss_command<LssAssignAll> = true;
template <> inline constexpr bool is_lss_command<LssDevices> = true;
template <> inline constexpr bool is_lss_command<LssSwitchGlobal> = true;
template <> inline constexpr bool is_lss_command<LssSwitchSelective> = true;
template <> inline constexpr bool is_lss_command<LssSetNodeId> = true;
template <> inline constexpr bool is_lss_command<LssSetBitTiming> = true;
template <> inline constexpr bool is_lss_command<LssActivateBitTiming> = true;
template <> inline constexpr bool is_lss_command<LssStore> = true;
template <> inline constexpr bool is_lss_command<LssInquire> = true;

constexpr Operation operation_of(const SdoRead&) { return Operation::sdo_read; }
constexpr Operation operation_of(const SdoWrite&) { return Operation::sdo_write; }
constexpr Operation operation_of(const Nmt&) { return Operation::nmt; }
constexpr Operation operation_of(const RpdoWrite&) { return Operation::rpdo_write; }
constexpr Operation operation_of(const Sync&) { return Operation::sync; }
constexpr Operation operation_of(const PdoConfigRead&) { return Operation::pdo_config_read; }
constexpr Operation operation_of(const Undecodable& u) { return u.operation; }
constexpr Operation operation_of(const NodeConfigRead&) { return Operation::config_read; }
constexpr Operation operation_of(const NodeConfigWrite&) { return Operation::config_write; }
constexpr Operation operation_of(const NodeEdsWrite&) { return Operation::config_write; }
constexpr Operation operation_of(const DcfRead&) { return Operation::dcf_read; }
constexpr Operation operation_of(const DcfApply&) { return Operation::dcf_write; }
constexpr Operation operation_of(const NodeStore&) { return Operation::store; }
constexpr Operation operation_of(const ProgramDownload&) { return Operation::program; }
template <typename T>
  requires is_lss_command<T>
constexpr Operation operation_of(const T&) {
  return Operation::lss;
}

// Every alternative of Command has its operation_of(): checked here, so the
// error names this header rather than a std::visit deep in the core.
template <typename T>
concept Described = requires(const T& t) {
  { operation_of(t) } -> std::same_as<Operation>;
};
template <typename V>
struct EveryCommandDescribed;
template <typename... T>
struct EveryCommandDescribed<std::variant<T...>> : std::bool_constant<(Described<T> && ...)> {};
static_assert(EveryCommandDescribed<Command>::value,
              "a Command alternative has no operation_of() overload: add it in core/operation.hpp");

inline Operation operation_of(const Command& command) {
  return std::visit([](const auto& c) { return operation_of(c); }, command);
}

// std::visit with one lambda per alternative (no default: a missing one is
// a compile error).
template <typename... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <typename... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace gateway::core
