// The state-dir overlay of run-time node configuration (issue 17, contract
// "Remote configuration and maintenance"): a node whose settings were
// changed over REST has them in <state-dir>/nodes/net<N>-node<M>.yaml (its
// `nodes:` entry, written as JSON, which is YAML) and an uploaded EDS/DCF
// beside it (net<N>-node<M>.eds or .dcf). At start-up they win over the
// configuration file for that node as a whole; other nodes keep the file's
// settings.
//
// Thread safety: free functions; blocking file I/O of small files (start-up,
// and the App's bounded writes of one node's settings).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "config/config.hpp"
#include "log.hpp"

namespace gateway {

std::filesystem::path node_settings_file(const std::string& state_dir, std::uint32_t net, std::uint8_t node);
// The kept EDS/DCF of a node (the ending says which, as for any EDS file).
std::filesystem::path node_eds_file(const std::string& state_dir, std::uint32_t net, std::uint8_t node, bool dcf);

// Start-up: the overlay files of network `net` over cfg.nodes (a node in
// the overlay takes its settings as a whole; one only there is added).
// A file that cannot be read or is not a valid entry for that node is
// logged as an error naming the file, and the node keeps the configuration
// file's settings. Returns node -> the file its settings now come from.
std::map<std::uint8_t, std::string> apply_node_overlay(const std::string& state_dir, std::uint32_t net,
                                                       NetworkConfig& cfg, const std::string& label, Logger& log);

}  // namespace gateway
