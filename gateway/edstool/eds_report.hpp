// What `canopen-eds` and the gateway say about a device description file,
// in one place so they cannot drift apart:
//  - check_file(): the gateway's acceptance rules (load_device_description)
//    and its warnings, as the lines `canopen-eds check` prints
//    (../shared/api-contract.md: "FILE: ok", "FILE: ok, N warnings" then
//    "FILE:LINE: warning: reason", or "FILE:LINE: error: reason");
//  - dictionary_json(): the object dictionary in the shape of
//    GET /api/v1/networks/{net}/nodes/{node}/od (without network and node);
//    objects_json() its "objects" part for any dictionary (the gateway's
//    own node has no file).
//
// Pure functions, thread-safe.
#pragma once

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "canopen/eds/eds.hpp"

namespace gateway::edstool {

// $NODEID in a file looked at with no node in mind (no --node-id, no DCF
// NodeID): any valid node-ID shows whether the expressions are well formed.
constexpr std::uint8_t kFallbackNodeId = 1;

struct CheckResult {
  bool accepted = false;
  std::vector<std::string> lines;  // what `canopen-eds check` prints for the file, in order
};

// node_id as the gateway would pass it (the node's configured ID); without
// one, a DCF's NodeID is used, else 1, so $NODEID expressions can be checked.
CheckResult check_file(const std::filesystem::path& file, std::optional<std::uint8_t> node_id = {});

// A warning of DeviceDescription::warnings ("file:line: text") of the
// file named `file` as "file:line: warning: text".
std::string warning_line(const std::string& file, const std::string& warning);
// An EdsError as "file:line: error: reason" ("file: error: reason" for line 0).
std::string error_line(const canopen::eds::EdsError& e);

// {"vendorName", "productName", "dcf", "objects": [{"index", "indexHex",
// "name", "objectCode", "subs": [{"subIndex", "name", "type", "access",
// "pdoMappable", "default", "low", "high", "unit", "factor"}]}]}; unit and
// factor are null where the file gives none (value in unit = raw x factor).
boost::json::object dictionary_json(const canopen::eds::DeviceDescription& d);
// The "objects" array of dictionary_json() for `od`, in index order; units
// and factors from `facts` (the file `od` was read from), null without one.
boost::json::array objects_json(const canopen::od::ObjectDictionary& od,
                                const canopen::eds::DeviceDescription* facts = nullptr);

}  // namespace gateway::edstool
