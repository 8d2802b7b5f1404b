// An RPDO write's values typed against the RPDO's mapping in effect: the
// core's half of PUT .../rpdo/{n} and of Sparkplug writes to RPDO-mapped
// objects (front ends decode their wire form into a core::RpdoWrite).
//
// Pure function; thread-safe.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/types.hpp"
#include "core/request.hpp"

namespace gateway::core {

// What goes into the RPDO: values by object, or the raw data.
struct RpdoBody {
  std::vector<canopen::MappedValue> values;  // empty when `raw` is set
  std::optional<canopen::Bytes> raw;
};

// Every value must be mapped by `pdo` (the node's RPDO in effect), fit its
// type and the limits `od` gives; raw must have the RPDO's length. Checked
// in the order given, the write's own `invalid` first. `what` names the
// RPDO in errors ("node 5 RPDO1"). On failure nullopt and `error` (the
// detail of a 400).
std::optional<RpdoBody> typed_rpdo_values(const RpdoWrite& write, const canopen::pdo::PdoConfig& pdo,
                                          const canopen::od::ObjectDictionary& od, std::string_view what,
                                          std::string& error);

}  // namespace gateway::core
