// Command line of canopen-gateway (../shared/api-contract.md, "Command line").
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "log.hpp"

namespace gateway {

// One --eds NODE=FILE: the EDS/DCF describing remote node NODE (on every network).
struct EdsOption {
  int node = 0;
  std::string file;
  friend bool operator==(const EdsOption&, const EdsOption&) = default;
};

struct CliOptions {
  std::vector<std::string> can_interfaces;  // one network each, numbered from 1
  int node_id = 127;                        // the gateway's own CANopen node-ID
  std::vector<EdsOption> eds;               // in command-line order, one per node
  LogLevel log_level = LogLevel::Info;
  bool help = false;
  bool version = false;
};

// Bad command line: what() is one line naming the flag and the reason.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses argv (without argv[0]). Throws UsageError.
CliOptions parse_cli(const std::vector<std::string>& args);

std::string usage_text();

}  // namespace gateway
