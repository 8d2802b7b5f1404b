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

namespace gateway::rest {

// Decimal path number ("1", "127"): at most 9 digits, nothing else.
using core::parse_decimal;

// Hex bytes ("0f00", "0F 00"); spaces are ignored, an odd digit count is
// malformed.
std::optional<canopen::Bytes> parse_hex(std::string_view s);

// The body of PUT .../rpdo/{n}: either values by object, or the raw data.
struct RpdoBody {
  std::vector<canopen::MappedValue> values;  // empty when `raw` is set
  std::optional<canopen::Bytes> raw;
};

// Decodes {"values": [{"index", "subIndex", "value"}...]} or {"raw": "hex"}
// against `pdo` (the node's RPDO from its EDS/DCF): every value must be
// mapped by it, fit its type and the limits `od` gives; raw must have the
// RPDO's length. `what` names the RPDO in errors ("node 5 RPDO1"). On
// failure returns nullopt and sets `error` (the detail of a 400).
std::optional<RpdoBody> parse_rpdo_body(std::string_view body, const canopen::pdo::PdoConfig& pdo,
                                        const canopen::od::ObjectDictionary& od, std::string_view what,
                                        std::string& error);

}  // namespace gateway::rest
