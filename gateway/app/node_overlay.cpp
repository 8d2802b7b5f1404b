#include "app/node_overlay.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include <boost/json/parse.hpp>

namespace gateway {

namespace fs = std::filesystem;

namespace {

// An overlay file is one node's settings: anything larger is not ours.
constexpr std::uintmax_t kMaxSettingsFile = 64 * 1024;

std::string stem(std::uint32_t net, std::uint8_t node) {
  return "net" + std::to_string(net) + "-node" + std::to_string(node);
}

}  // namespace

fs::path node_settings_file(const std::string& state_dir, std::uint32_t net, std::uint8_t node) {
  return fs::path(state_dir) / "nodes" / (stem(net, node) + ".yaml");
}

fs::path node_eds_file(const std::string& state_dir, std::uint32_t net, std::uint8_t node, bool dcf) {
  return fs::path(state_dir) / "nodes" / (stem(net, node) + (dcf ? ".dcf" : ".eds"));
}

std::map<std::uint8_t, std::string> apply_node_overlay(const std::string& state_dir, std::uint32_t net,
                                                       NetworkConfig& cfg, const std::string& label, Logger& log) {
  std::map<std::uint8_t, std::string> from;
  if (state_dir.empty()) return from;
  std::error_code ec;
  const fs::path dir = fs::path(state_dir) / "nodes";
  if (!fs::is_directory(dir, ec)) return from;
  const std::string prefix = "net" + std::to_string(net) + "-node";
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const auto name = entry.path().filename().string();
    if (!name.starts_with(prefix) || entry.path().extension() != ".yaml") continue;
    const auto number = name.substr(prefix.size(), name.size() - prefix.size() - 5);
    const bool digits =
        !number.empty() && number.size() <= 3 && std::all_of(number.begin(), number.end(), [](char c) {
          return c >= '0' && c <= '9';
        });
    if (!digits) continue;
    const int id = std::stoi(number);
    const std::string file = entry.path().string();
    auto refuse = [&](const std::string& why) {
      log.error(label + ": " + why + ": node " + number + " keeps the configuration file's settings");
    };
    if (id < 1 || id > 127) continue;
    if (entry.file_size(ec) > kMaxSettingsFile) {
      refuse(file + ": larger than " + std::to_string(kMaxSettingsFile) + " bytes, not a node's settings");
      continue;
    }
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) {
      refuse(file + ": cannot be read");
      continue;
    }
    NodeConfig node;
    try {
      boost::system::error_code jec;
      auto json = boost::json::parse(text.str(), jec);
      // Written as JSON; a hand-edited YAML one is read as YAML, with lines.
      node = jec ? parse_node_config(text.str(), file, "", true) : node_config_from_json(json, cfg, file, "", false);
    } catch (const ConfigError& e) {
      refuse(e.what());
      continue;
    }
    if (node.id != id) {
      refuse(file + ": id " + std::to_string(node.id) + " is not the node its name says");
      continue;
    }
    if (node.id == cfg.node_id) {
      refuse(file + ": node " + number + " is the gateway's own node-ID");
      continue;
    }
    auto it = std::find_if(cfg.nodes.begin(), cfg.nodes.end(), [&](const NodeConfig& n) { return n.id == node.id; });
    if (it != cfg.nodes.end()) *it = node;
    else cfg.nodes.push_back(node);
    from[node.id] = file;
    log.info(label + " node " + number + ": settings from " + file + " (changed at run time; they win over the "
             "configuration file for this node)");
  }
  return from;
}

}  // namespace gateway
