// Small helpers the request core's files share (request_core.cpp,
// lss_requests.cpp, maintenance.cpp, node_config.cpp). Internal to core/.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "core/request.hpp"

namespace gateway::core::detail {

// Who asked, for the audit log.
inline std::string requester(std::string_view who) {
  return who.empty() ? std::string("anonymous") : std::string(who);
}

// The queue key of QueueShares (and of one maintenance run) for a node's SDO queue.
inline std::uint64_t sdo_queue_key(std::uint32_t network, std::uint8_t node) {
  return std::uint64_t{network} << 8 | node;
}

// `command_read`: see Problem::command_read.
inline Problem problem(int status, std::string detail, bool command_read = true) {
  Problem p;
  p.status = status;
  p.detail = std::move(detail);
  p.command_read = command_read;
  return p;
}

}  // namespace gateway::core::detail
