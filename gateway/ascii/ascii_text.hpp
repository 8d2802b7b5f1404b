// Internal to the ASCII language (ascii_command.cpp, ascii_values.cpp,
// ascii_parse.cpp, ascii_answer.cpp): the tokens, numbers and printf
// formats its parts share, as CANopenNode reads and writes them. Not for
// use outside gateway/ascii/. Pure functions and a plain cursor.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace gateway::ascii::detail {

// CANopenNode's tokens are runs of printable ASCII (isgraph in the C
// locale); everything else, CR and bytes above 7Eh included, separates them.
inline bool graph(char c) { return c > 0x20 && c < 0x7F; }

inline char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

inline std::string lowered(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = lower(c);
  return out;
}

// A cursor over one line: tokens, '#' comments, "is anything left".
class Cursor {
 public:
  explicit Cursor(std::string_view s) : s_(s) {}
  // Nothing but white space and a comment left.
  bool at_end() {
    skip();
    return pos_ >= s_.size();
  }
  std::string_view token() {
    skip();
    const std::size_t b = pos_;
    while (pos_ < s_.size() && graph(s_[pos_]) && s_[pos_] != '#') ++pos_;
    return s_.substr(b, pos_ - b);
  }
  std::string_view rest() const { return s_.substr(pos_); }

 private:
  void skip() {
    while (pos_ < s_.size() && !graph(s_[pos_])) ++pos_;
    if (pos_ < s_.size() && s_[pos_] == '#') pos_ = s_.size();
  }
  std::string_view s_;
  std::size_t pos_ = 0;
};

// strtoul/strtoull with base 0 (0x hex, leading 0 octal, else decimal),
// without sign, within [lo, hi]; nullopt when not all of `t` is the number
// (ascii_values.cpp).
std::optional<std::uint64_t> parse_u(std::string_view t, std::uint64_t lo, std::uint64_t hi);

// Little-endian, as the values are on the bus.
inline std::uint64_t get_le(std::span<const std::uint8_t> b) {
  std::uint64_t v = 0;
  for (std::size_t i = b.size(); i-- > 0;) v = (v << 8) | b[i];
  return v;
}

// Every caller passes a literal format (CANopenNode's printf formats).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
template <typename... Args>
std::string printf_string(const char* fmt, Args... args) {
  char buf[64];
  const int n = std::snprintf(buf, sizeof buf, fmt, args...);
  return std::string(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
}
#pragma GCC diagnostic pop

}  // namespace gateway::ascii::detail
