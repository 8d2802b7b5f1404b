// Fuzzes the EDS/DCF reader: any text either parses or raises EdsError with
// a "file:line: reason" message; nothing else may escape, crash or leak.
// fuzz-libs: canopen_eds
// fuzz-seeds: deploy/eds tests/support/eds
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "canopen/eds/eds.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (const char* name : {"fuzz.eds", "fuzz.dcf"}) {
    try {
      auto d = canopen::eds::parse_device_description(text, name, std::uint8_t{5});
      // Whatever was accepted must be readable back through the dictionary.
      for (const auto& [index, obj] : d.od.objects()) {
        for (const auto& [sub, entry] : obj.subs) (void)d.od.get(index, sub);
      }
    } catch (const canopen::eds::EdsError& e) {
      if (std::string_view(e.what()).find(':') == std::string_view::npos) __builtin_trap();
    }
  }
  return 0;
}
