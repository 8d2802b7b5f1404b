#include "core/format.hpp"

#include <charconv>

namespace gateway::core {

namespace {
constexpr char kLower[] = "0123456789abcdef";
constexpr char kUpper[] = "0123456789ABCDEF";
}  // namespace

std::string hex_number(std::uint32_t v, int digits) {
  int n = 1;
  while (n < 8 && (v >> (4 * n)) != 0) ++n;
  if (n < digits) n = digits;
  std::string s(static_cast<std::size_t>(n), '0');
  for (int i = n - 1; i >= 0; --i, v >>= 4) s[static_cast<std::size_t>(i)] = kUpper[v & 0x0F];
  return s;
}

std::string index_text(std::uint16_t index) { return hex_number(index, 4) + 'h'; }

std::string abort_code_text(std::uint32_t code) { return "0x" + hex_number(code, 8); }

void append_hex(std::string& out, std::span<const std::uint8_t> bytes, HexCase c) {
  const char* digits = c == HexCase::upper ? kUpper : kLower;
  const std::size_t at = out.size();
  out.resize(at + bytes.size() * 2);
  char* p = out.data() + at;
  for (std::uint8_t b : bytes) {
    *p++ = digits[b >> 4];
    *p++ = digits[b & 0x0F];
  }
}

std::string hex_bytes(std::span<const std::uint8_t> bytes, HexCase c) {
  std::string s;
  s.reserve(bytes.size() * 2);
  append_hex(s, bytes, c);
  return s;
}

std::optional<std::uint32_t> parse_decimal(std::string_view s) {
  std::uint32_t v = 0;
  if (s.empty() || s.size() > 9) return std::nullopt;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc{} || p != s.data() + s.size()) return std::nullopt;
  return v;
}

}  // namespace gateway::core
