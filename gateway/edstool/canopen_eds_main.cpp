// canopen-eds: the check users run on vendor EDS/DCF files before they
// deploy, with exactly the gateway's acceptance rules (eds_report.hpp).
//
//   canopen-eds check [--node-id N] FILE...   exit 0 all accepted, 1 any rejected
//   canopen-eds show FILE [--node-id N]       the dictionary as JSON on stdout
//
// Usage errors exit 2 with one line on stderr.
#include <boost/json/serialize.hpp>
#include <charconv>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "edstool/eds_report.hpp"

namespace {

constexpr int kRejected = 1;
constexpr int kUsage = 2;

constexpr std::string_view kUsageText =
    "usage: canopen-eds check [--node-id N] FILE...\n"
    "       canopen-eds show FILE [--node-id N]\n"
    "\n"
    "check  validates EDS/DCF files (CiA 306) with the gateway's rules: one line per file,\n"
    "       'FILE: ok', 'FILE: ok, N warnings' followed by 'FILE:LINE: warning: reason',\n"
    "       or 'FILE:LINE: error: reason'. Exit 0 when every file is accepted, 1 otherwise.\n"
    "show   prints the object dictionary as JSON (the shape of GET .../nodes/{node}/od);\n"
    "       warnings go to stderr.\n"
    "--node-id N  the node-ID the device has on the bus (1..127), used for $NODEID; default:\n"
    "       a DCF's [DeviceComissioning] NodeID, else 1.\n";

struct UsageError {
  std::string text;
};

std::uint8_t parse_node_id(std::string_view s) {
  unsigned v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc{} || end != s.data() + s.size() || v < 1 || v > 127) {
    throw UsageError{"--node-id: '" + std::string(s) + "' is not a node-ID 1..127"};
  }
  return static_cast<std::uint8_t>(v);
}

struct Args {
  std::string command;
  std::optional<std::uint8_t> node_id;
  std::vector<std::string> files;
};

Args parse_args(int argc, char** argv) {
  Args a;
  bool options_done = false;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (!options_done && arg == "--") {
      options_done = true;
    } else if (!options_done && arg == "--node-id") {
      if (i + 1 >= argc) throw UsageError{"--node-id needs a value"};
      a.node_id = parse_node_id(argv[++i]);
    } else if (!options_done && arg.starts_with("--node-id=")) {
      a.node_id = parse_node_id(arg.substr(10));
    } else if (!options_done && arg.size() > 1 && arg.front() == '-') {
      throw UsageError{"unknown option '" + std::string(arg) + "'"};
    } else if (a.command.empty()) {
      a.command = arg;
    } else {
      a.files.emplace_back(arg);
    }
  }
  if (a.command.empty()) throw UsageError{"no command (check or show)"};
  if (a.command != "check" && a.command != "show") throw UsageError{"unknown command '" + a.command + "'"};
  if (a.files.empty()) throw UsageError{a.command + ": no FILE given"};
  if (a.command == "show" && a.files.size() != 1) throw UsageError{"show takes one FILE"};
  return a;
}

int check(const Args& a) {
  int status = 0;
  for (const auto& f : a.files) {
    const auto r = gateway::edstool::check_file(f, a.node_id);
    for (const auto& line : r.lines) std::cout << line << '\n';
    if (!r.accepted) status = kRejected;
  }
  return status;
}

int show(const Args& a) {
  const auto& file = a.files.front();
  try {
    const auto d = canopen::eds::load_device_description(file, a.node_id, gateway::edstool::kFallbackNodeId);
    for (const auto& w : d.warnings) std::cerr << gateway::edstool::warning_line(file, w) << '\n';
    std::cout << boost::json::serialize(gateway::edstool::dictionary_json(d)) << '\n';
    return 0;
  } catch (const canopen::eds::EdsError& e) {
    std::cerr << gateway::edstool::error_line(e) << '\n';
    return kRejected;
  }
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--") break;
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsageText;
      return 0;
    }
  }
  try {
    const Args a = parse_args(argc, argv);
    return a.command == "check" ? check(a) : show(a);
  } catch (const UsageError& e) {
    std::cerr << "canopen-eds: " << e.text << "\n" << kUsageText.substr(0, kUsageText.find("\n\n") + 1);
    return kUsage;
  }
}
