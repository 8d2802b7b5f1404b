#include "event_message.hpp"

#include <array>

namespace gateway {

namespace {
constexpr std::array<std::string_view, 11> kNames = {"status", "bus",  "state", "heartbeat", "emcy",    "tpdo",
                                                     "pdo",    "sync", "time",  "boot",      "transfer"};
static_assert(kNames.size() == static_cast<std::size_t>(kLastEventKind) + 1);
}

std::string_view to_string(EventKind k) { return kNames[static_cast<std::size_t>(k)]; }

bool event_kind_from_string(std::string_view s, EventKind& out) {
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    if (kNames[i] == s) {
      out = static_cast<EventKind>(i);
      return true;
    }
  }
  return false;
}

}  // namespace gateway
