#include "cli.hpp"

#include <charconv>
#include <set>

namespace gateway {

namespace {

// Flags of the contract that later parts of the gateway implement. Until
// they do, they are refused rather than silently ignored.
const std::set<std::string> kNotYetSupported = {"--config", "--mqtt", "--mqtt-format",
                                                "--http", "--gateway-id", "--demo"};

int parse_int(const std::string& flag, const std::string& v) {
  int out = 0;
  auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), out);
  if (ec != std::errc() || p != v.data() + v.size()) throw UsageError(flag + ": '" + v + "' is not a number");
  return out;
}

}  // namespace

std::string usage_text() {
  return "usage: canopen-gateway [--config FILE] [--can IFACE]... [--node-id N] [--eds NODE=FILE]...\n"
         "                       [--mqtt URI] [--mqtt-format json|protobuf] [--http ADDR:PORT]\n"
         "                       [--gateway-id ID] [--demo] [--log-level trace|debug|info|warn|error]\n";
}

CliOptions parse_cli(const std::vector<std::string>& args) {
  CliOptions o;
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string flag = args[i];
    std::string value;
    bool has_inline_value = false;
    if (auto eq = flag.find('='); flag.rfind("--", 0) == 0 && eq != std::string::npos) {
      value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
      has_inline_value = true;
    }
    auto take_value = [&]() -> std::string {
      if (has_inline_value) return value;
      if (i + 1 >= args.size() || args[i + 1].rfind("--", 0) == 0) throw UsageError(flag + ": missing value");
      return args[++i];
    };
    auto no_value = [&] {
      if (has_inline_value) throw UsageError(flag + " takes no value");
    };
    if (flag == "-h" || flag == "--help") {
      no_value();
      o.help = true;
    } else if (flag == "--version") {
      no_value();
      o.version = true;
    } else if (flag == "--can") {
      std::string iface = take_value();
      // Linux interface names: 1..15 bytes, no '/', ':' or white space, not "." or "..".
      const bool bad = iface.empty() || iface.size() > 15 || iface == "." || iface == ".." ||
                       iface.find_first_of("/: \t\n") != std::string::npos;
      if (bad) throw UsageError("--can: '" + iface + "' is not an interface name");
      o.can_interfaces.push_back(iface);
    } else if (flag == "--node-id") {
      const std::string v = take_value();
      const int n = parse_int(flag, v);
      if (n < 1 || n > 127) throw UsageError("--node-id: " + v + " is out of range 1..127");
      o.node_id = n;
    } else if (flag == "--eds") {
      const std::string v = take_value();
      const auto eq = v.find('=');
      if (eq == std::string::npos) throw UsageError("--eds: '" + v + "' is not NODE=FILE");
      const std::string node_text = v.substr(0, eq);
      int n = 0;
      auto [p, ec] = std::from_chars(node_text.data(), node_text.data() + node_text.size(), n);
      if (ec != std::errc() || p != node_text.data() + node_text.size())
        throw UsageError("--eds: node '" + node_text + "' is not a number");
      if (n < 1 || n > 127) throw UsageError("--eds: node " + node_text + " is out of range 1..127");
      if (eq + 1 == v.size()) throw UsageError("--eds: no file given for node " + node_text);
      for (const auto& e : o.eds) {
        if (e.node == n) throw UsageError("--eds: node " + node_text + " given twice");
      }
      o.eds.push_back({n, v.substr(eq + 1)});
    } else if (flag == "--log-level") {
      const std::string v = take_value();
      auto l = parse_log_level(v);
      if (!l) throw UsageError("--log-level: '" + v + "' is not one of trace, debug, info, warn, error");
      o.log_level = *l;
    } else if (kNotYetSupported.count(flag) != 0) {
      throw UsageError(flag + ": not supported by this version of canopen-gateway yet");
    } else {
      throw UsageError("unknown option '" + args[i] + "'");
    }
  }
  if (!o.help && !o.version && o.can_interfaces.empty()) throw UsageError("no CAN interface given (use --can IFACE)");
  return o;
}

}  // namespace gateway
