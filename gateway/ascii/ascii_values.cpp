// Values: the datatype table, value text parsed into the bytes on the bus
// (parse_value) and bytes printed as CANopenNode prints them (ValuePrinter).
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "ascii/ascii_command.hpp"
#include "ascii/ascii_text.hpp"

namespace gateway::ascii {

namespace detail {

namespace {

int digit_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  const char l = lower(c);
  if (l >= 'a' && l <= 'f') return l - 'a' + 10;
  return 99;
}

// strtoul/strtoull with base 0 (0x hex, leading 0 octal, else decimal),
// without sign; nullopt when not all of `t` is the number or it overflows.
std::optional<std::uint64_t> parse_unsigned(std::string_view t) {
  int base = 10;
  if (t.size() > 2 && t[0] == '0' && (t[1] == 'x' || t[1] == 'X')) {
    base = 16;
    t.remove_prefix(2);
  } else if (t.size() > 1 && t[0] == '0') {
    base = 8;
    t.remove_prefix(1);
  }
  if (t.empty()) return std::nullopt;
  std::uint64_t v = 0;
  for (char c : t) {
    const int d = digit_value(c);
    if (d >= base) return std::nullopt;
    if (v > (std::numeric_limits<std::uint64_t>::max() - static_cast<unsigned>(d)) / static_cast<unsigned>(base))
      return std::nullopt;
    v = v * static_cast<unsigned>(base) + static_cast<unsigned>(d);
  }
  return v;
}

}  // namespace

std::optional<std::uint64_t> parse_u(std::string_view t, std::uint64_t lo, std::uint64_t hi) {
  auto v = parse_unsigned(t);
  if (!v || *v < lo || *v > hi) return std::nullopt;
  return v;
}

}  // namespace detail

using namespace detail;

namespace {

// strtol/strtoll with base 0: an optional sign, then as parse_unsigned.
std::optional<std::int64_t> parse_signed(std::string_view t, std::int64_t lo, std::int64_t hi) {
  bool neg = false;
  if (!t.empty() && (t[0] == '-' || t[0] == '+')) {
    neg = t[0] == '-';
    t.remove_prefix(1);
  }
  auto m = parse_unsigned(t);
  if (!m) return std::nullopt;
  constexpr auto kMaxNeg = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()) + 1;
  if (*m > (neg ? kMaxNeg : kMaxNeg - 1)) return std::nullopt;
  const std::int64_t v = neg ? static_cast<std::int64_t>(0 - *m) : static_cast<std::int64_t>(*m);
  if (v < lo || v > hi) return std::nullopt;
  return v;
}

void put_le(canopen::Bytes& out, std::uint64_t v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

// What follows a value: white space, then the end or a '#' comment.
bool only_comment_left(std::string_view s) {
  Cursor c(s);
  return c.at_end();
}

std::optional<canopen::Bytes> parse_number(Datatype t, std::string_view text) {
  Cursor c(text);
  const std::string_view tok = c.token();
  if (tok.empty() || !c.at_end()) return std::nullopt;
  canopen::Bytes out;
  auto unsigned_of = [&](std::size_t n, std::uint64_t max) -> bool {
    auto v = parse_u(tok, 0, max);
    if (!v) return false;
    put_le(out, *v, n);
    return true;
  };
  auto signed_of = [&](std::size_t n, std::int64_t lo, std::int64_t hi) -> bool {
    auto v = parse_signed(tok, lo, hi);
    if (!v) return false;
    put_le(out, static_cast<std::uint64_t>(*v), n);
    return true;
  };
  bool ok = false;
  switch (t) {
    case Datatype::b:
    case Datatype::u8:
    case Datatype::x8: ok = unsigned_of(1, 0xFF); break;
    case Datatype::u16:
    case Datatype::x16: ok = unsigned_of(2, 0xFFFF); break;
    case Datatype::u32:
    case Datatype::x32: ok = unsigned_of(4, 0xFFFFFFFF); break;
    case Datatype::u64:
    case Datatype::x64: ok = unsigned_of(8, std::numeric_limits<std::uint64_t>::max()); break;
    case Datatype::i8: ok = signed_of(1, -128, 127); break;
    case Datatype::i16: ok = signed_of(2, -32768, 32767); break;
    case Datatype::i32: ok = signed_of(4, std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max()); break;
    case Datatype::i64: ok = signed_of(8, std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max()); break;
    case Datatype::r32: {
      const std::string z(tok);
      char* end = nullptr;
      const float f = std::strtof(z.c_str(), &end);
      if (end != z.c_str() + z.size()) return std::nullopt;
      std::uint32_t bits = 0;
      std::memcpy(&bits, &f, 4);
      put_le(out, bits, 4);
      ok = true;
      break;
    }
    case Datatype::r64: {
      // CANopenNode reads r64 with strtof (float precision); strtod keeps the value.
      const std::string z(tok);
      char* end = nullptr;
      const double f = std::strtod(z.c_str(), &end);
      if (end != z.c_str() + z.size()) return std::nullopt;
      std::uint64_t bits = 0;
      std::memcpy(&bits, &f, 8);
      put_le(out, bits, 8);
      ok = true;
      break;
    }
    default: break;
  }
  if (!ok) return std::nullopt;
  return out;
}

// Two-digit hex groups, optionally separated by white space; a single
// digit before white space or the end is one byte.
std::optional<canopen::Bytes> parse_hex(std::string_view text) {
  canopen::Bytes out;
  int pending = -1;
  std::size_t i = 0;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    const int d = digit_value(c);
    if (d < 16) {
      if (pending < 0) {
        pending = d;
      } else {
        out.push_back(static_cast<std::uint8_t>(pending * 16 + d));
        pending = -1;
      }
    } else if (graph(c)) {
      if (c != '#') return std::nullopt;
      break;  // a comment: the rest of the line
    } else if (pending >= 0) {
      out.push_back(static_cast<std::uint8_t>(pending));
      pending = -1;
    }
  }
  if (pending >= 0) out.push_back(static_cast<std::uint8_t>(pending));
  if (out.empty()) return std::nullopt;
  return out;
}

// One word, or a double-quoted string with "" for a quote.
std::optional<canopen::Bytes> parse_vs(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size() && !graph(text[i])) ++i;
  if (i >= text.size() || text[i] == '#') return std::nullopt;
  canopen::Bytes out;
  if (text[i] == '"') {
    ++i;
    for (;;) {
      if (i >= text.size()) return std::nullopt;  // no closing quote
      if (text[i] == '"') {
        if (i + 1 < text.size() && text[i + 1] == '"') {
          out.push_back('"');
          i += 2;
          continue;
        }
        ++i;
        break;
      }
      out.push_back(static_cast<std::uint8_t>(text[i++]));
    }
    if (i < text.size() && graph(text[i])) return std::nullopt;  // white space must follow the quote
  } else {
    while (i < text.size() && graph(text[i])) {
      if (text[i] == '"') {
        if (i + 1 < text.size() && text[i + 1] == '"') {
          out.push_back('"');
          i += 2;
          continue;
        }
        return std::nullopt;  // a quote inside a word that did not start with one
      }
      out.push_back(static_cast<std::uint8_t>(text[i++]));
    }
  }
  if (!only_comment_left(text.substr(i))) return std::nullopt;
  if (out.empty()) return std::nullopt;
  return out;
}

constexpr char kBase64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

// RFC 2045 base64 on one line; it ends at '=', white space or the end.
std::optional<canopen::Bytes> parse_base64(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size() && !graph(text[i])) ++i;
  if (i >= text.size() || text[i] == '#') return std::nullopt;
  canopen::Bytes out;
  std::uint32_t bits = 0;
  int n = 0;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    const int v = base64_value(c);
    if (v >= 0) {
      bits = (bits << 6) | static_cast<std::uint32_t>(v);
      if (++n == 4) {
        out.push_back(static_cast<std::uint8_t>(bits >> 16));
        out.push_back(static_cast<std::uint8_t>(bits >> 8));
        out.push_back(static_cast<std::uint8_t>(bits));
        bits = 0;
        n = 0;
      }
      continue;
    }
    if (c != '=' && c != ' ' && c != '\t' && c != '\r') return std::nullopt;
    break;
  }
  if (n == 2) out.push_back(static_cast<std::uint8_t>(bits >> 4));
  if (n == 3) {
    out.push_back(static_cast<std::uint8_t>(bits >> 10));
    out.push_back(static_cast<std::uint8_t>(bits >> 2));
  }
  // After the data: padding, white space, then the end or a comment.
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '#') break;
    if (graph(c) && c != '=') return std::nullopt;
  }
  if (out.empty()) return std::nullopt;
  return out;
}

struct DatatypeInfo {
  const char* name;
  std::size_t size;  // 0: variable
};
constexpr std::array<DatatypeInfo, kDatatypeCount> kDatatypes = {{{"hex", 0}, {"b", 1},   {"i8", 1},  {"i16", 2},
                                                                   {"i32", 4}, {"i64", 8}, {"u8", 1},  {"u16", 2},
                                                                   {"u32", 4}, {"u64", 8}, {"x8", 1},  {"x16", 2},
                                                                   {"x32", 4}, {"x64", 8}, {"r32", 4}, {"r64", 8},
                                                                   {"vs", 0},  {"os", 0},  {"us", 0},  {"d", 0}}};

}  // namespace

std::string_view datatype_name(Datatype t) { return kDatatypes[static_cast<std::size_t>(t)].name; }

std::optional<Datatype> datatype_from_name(std::string_view name) {
  const std::string l = lowered(name);
  for (std::size_t i = 0; i < kDatatypes.size(); ++i)
    if (l == kDatatypes[i].name) return static_cast<Datatype>(i);
  return std::nullopt;
}

std::optional<std::size_t> datatype_size(Datatype t) {
  const auto s = kDatatypes[static_cast<std::size_t>(t)].size;
  if (s == 0) return std::nullopt;
  return s;
}

std::optional<canopen::Bytes> parse_value(Datatype t, std::string_view text) {
  switch (t) {
    case Datatype::hex: return parse_hex(text);
    case Datatype::vs: return parse_vs(text);
    case Datatype::os:
    case Datatype::us:
    case Datatype::d: return parse_base64(text);
    default: return parse_number(t, text);
  }
}

// ---- printing ----------------------------------------------------------------

ValuePrinter::ValuePrinter(Datatype t, std::size_t total) : type_(t), total_(total) {
  // A fixed-size type whose size the data does not have is printed as hex.
  if (auto s = datatype_size(t); s && *s != total) type_ = Datatype::hex;
}

void ValuePrinter::print(std::span<const std::uint8_t> chunk, bool last, std::string& out) {
  switch (type_) {
    case Datatype::hex:
      for (auto b : chunk) {
        out += printf_string(started_ ? " %02X" : "%02X", static_cast<unsigned>(b));
        started_ = true;
      }
      return;
    case Datatype::vs:
      if (!started_) out += '"';
      started_ = true;
      for (auto b : chunk) {
        if (b == 0 || b == '\r') continue;
        out += static_cast<char>(b);
        if (b == '"') out += '"';
      }
      if (last) out += '"';
      return;
    case Datatype::os:
    case Datatype::us:
    case Datatype::d:
      for (auto b : chunk) {
        b64_bits_ = (b64_bits_ << 8) | b;
        if (++b64_count_ == 3) {
          out += kBase64[(b64_bits_ >> 18) & 0x3F];
          out += kBase64[(b64_bits_ >> 12) & 0x3F];
          out += kBase64[(b64_bits_ >> 6) & 0x3F];
          out += kBase64[b64_bits_ & 0x3F];
          b64_bits_ = 0;
          b64_count_ = 0;
        }
      }
      if (last && b64_count_ == 1) {
        out += kBase64[(b64_bits_ >> 2) & 0x3F];
        out += kBase64[(b64_bits_ << 4) & 0x3F];
        out += "==";
        b64_count_ = 0;
      } else if (last && b64_count_ == 2) {
        out += kBase64[(b64_bits_ >> 10) & 0x3F];
        out += kBase64[(b64_bits_ >> 4) & 0x3F];
        out += kBase64[(b64_bits_ << 2) & 0x3F];
        out += '=';
        b64_count_ = 0;
      }
      return;
    default: break;
  }
  // A number: the whole value (at most 8 bytes) comes in one chunk.
  if (chunk.size() != total_) {
    ValuePrinter hex(Datatype::hex, chunk.size());
    hex.print(chunk, last, out);
    return;
  }
  const std::uint64_t v = get_le(chunk);
  switch (type_) {
    case Datatype::b:
    case Datatype::u8:
    case Datatype::u16:
    case Datatype::u32: out += printf_string("%lu", static_cast<unsigned long>(v)); break;
    case Datatype::u64: out += printf_string("%llu", static_cast<unsigned long long>(v)); break;
    case Datatype::i8: out += printf_string("%d", static_cast<int>(static_cast<std::int8_t>(v))); break;
    case Datatype::i16: out += printf_string("%d", static_cast<int>(static_cast<std::int16_t>(v))); break;
    case Datatype::i32: out += printf_string("%ld", static_cast<long>(static_cast<std::int32_t>(v))); break;
    case Datatype::i64: out += printf_string("%lld", static_cast<long long>(static_cast<std::int64_t>(v))); break;
    case Datatype::x8: out += printf_string("0x%02X", static_cast<unsigned>(v)); break;
    case Datatype::x16: out += printf_string("0x%04X", static_cast<unsigned>(v)); break;
    case Datatype::x32: out += printf_string("0x%08lX", static_cast<unsigned long>(v)); break;
    case Datatype::x64: out += printf_string("0x%016llX", static_cast<unsigned long long>(v)); break;
    case Datatype::r32: {
      float f = 0;
      const auto bits = static_cast<std::uint32_t>(v);
      std::memcpy(&f, &bits, 4);
      out += printf_string("%g", static_cast<double>(f));
      break;
    }
    case Datatype::r64: {
      double f = 0;
      std::memcpy(&f, &v, 8);
      out += printf_string("%g", f);
      break;
    }
    default: break;
  }
}

std::string print_value(Datatype t, std::span<const std::uint8_t> data) {
  std::string out;
  ValuePrinter p(t, data.size());
  p.print(data, true, out);
  return out;
}

}  // namespace gateway::ascii
