// Internal to canopen_master: pieces the per-node SDO sequences (boot-up
// configuration, DCF read-back and apply, program download) share.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/sdo/client.hpp"

namespace canopen::master::detail {

// "0002A3F1h": 32-bit values in event and failure details.
inline std::string hex32h(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%08Xh", v);
  return buf;
}

// A service's destructor: forgets every run first, so the handlers of the
// requests it cancels find none, then cancels the SDO requests still running.
// `runs` maps node -> a run with `std::optional<sdo::RequestId> request`.
template <typename Runs>
void drop_runs(sdo::SdoClient& client, Runs& runs, TimePoint now) {
  std::vector<sdo::RequestId> pending;
  for (auto& [node, run] : runs)
    if (run.request) pending.push_back(*run.request);
  runs.clear();
  for (const auto id : pending) client.cancel(id, now);
}

}  // namespace canopen::master::detail
