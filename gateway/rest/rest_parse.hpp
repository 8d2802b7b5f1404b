// The parts of REST request decoding that need no App, server or bus: path
// numbers, hex text and the RPDO write body checked against the RPDO's
// mapping. Split out of rest_api.cpp so the fuzz target
// (tests/fuzz/fuzz_rest_request.cpp) reaches them without a running gateway.
//
// Never throws or crashes on any input. Thread safety: pure functions.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/types.hpp"
#include "core/format.hpp"
#include "core/request.hpp"
#include "core/rpdo_values.hpp"

namespace gateway::rest {

// Decimal path number ("1", "127"): at most 9 digits, nothing else.
using core::parse_decimal;

// Hex bytes ("0f00", "0F 00"); spaces are ignored, an odd digit count is
// malformed.
std::optional<canopen::Bytes> parse_hex(std::string_view s);

// The body of PUT .../rpdo/{n}: either values by object, or the raw data.
using core::RpdoBody;

// The core's command for the body {"values": [{"index", "subIndex",
// "value"}...]} or {"raw": "hex"} of PUT .../rpdo/{n}: what is wrong with
// its form is carried in `invalid` (the body's or one item's), for the core
// to answer in its order (core/rpdo_values.hpp).
core::RpdoWrite decode_rpdo_body(std::uint8_t node, std::uint16_t number, std::string_view body);

// decode_rpdo_body() and the core's typing against `pdo` (the node's RPDO
// from its EDS/DCF) in one: every value must be mapped by it, fit its type
// and the limits `od` gives; raw must have the RPDO's length. `what` names
// the RPDO in errors ("node 5 RPDO1"). On failure returns nullopt and sets
// `error` (the detail of a 400).
std::optional<RpdoBody> parse_rpdo_body(std::string_view body, const canopen::pdo::PdoConfig& pdo,
                                        const canopen::od::ObjectDictionary& od, std::string_view what,
                                        std::string& error);

// The LSS bodies (contract "LSS master"), as the core's commands. Keys are
// the contract's and nothing else; identity words and node-IDs are JSON
// numbers (identity words also "0x..." strings). On failure nullopt and
// `error` (the detail of a 400).
//   fastscan:   empty, or {"timeoutMs": 1..10000} (per fastscan step)
//   configure:  {"identity": {"vendorId", "productCode", "revisionNumber",
//                "serialNumber"}, "nodeId": 1..127, "bitrate": bit/s
//                (optional), "store": bool (default true)}
//   assign-all: {"firstNodeId": 1..127, "store": bool (default true),
//                "timeoutMs": (optional)}
std::optional<core::LssFastscan> parse_lss_fastscan(std::string_view body, std::string& error);
std::optional<core::LssConfigure> parse_lss_configure(std::string_view body, std::string& error);
std::optional<core::LssAssignAll> parse_lss_assign_all(std::string_view body, std::string& error);

}  // namespace gateway::rest
