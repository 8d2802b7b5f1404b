// Helpers shared by the command-line tools the system tests drive.
#pragma once

#include <charconv>
#include <stdexcept>
#include <string>
#include <string_view>

namespace canopen::tools {

// Decimal or 0x-prefixed hexadecimal; throws std::invalid_argument otherwise.
inline unsigned long parse_number(const std::string& s) {
  int base = 10;
  std::string_view v = s;
  if (v.starts_with("0x") || v.starts_with("0X")) {
    base = 16;
    v.remove_prefix(2);
  }
  unsigned long out = 0;
  auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), out, base);
  if (v.empty() || ec != std::errc() || p != v.data() + v.size()) throw std::invalid_argument("bad number '" + s + "'");
  return out;
}

}  // namespace canopen::tools
