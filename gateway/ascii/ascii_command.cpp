#include "ascii/ascii_command.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "canopen/sdo/abort.hpp"

namespace gateway::ascii {

namespace {

// CANopenNode's tokens are runs of printable ASCII (isgraph in the C
// locale); everything else, CR and bytes above 7Eh included, separates them.
bool graph(char c) { return c > 0x20 && c < 0x7F; }

char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

std::string lowered(std::string_view s) {
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

std::optional<std::uint64_t> parse_u(std::string_view t, std::uint64_t lo, std::uint64_t hi) {
  auto v = parse_unsigned(t);
  if (!v || *v < lo || *v > hi) return std::nullopt;
  return v;
}

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

std::uint64_t get_le(std::span<const std::uint8_t> b) {
  std::uint64_t v = 0;
  for (std::size_t i = b.size(); i-- > 0;) v = (v << 8) | b[i];
  return v;
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

std::string_view error_text(Error e) {
  switch (e) {
    case Error::RequestNotSupported: return "Request not supported.";
    case Error::Syntax: return "Syntax error.";
    case Error::InternalState: return "Request not processed due to internal state.";
    case Error::Timeout: return "Time-out.";
    case Error::NoDefaultNet: return "No default net set.";
    case Error::NoDefaultNode: return "No default node set.";
    case Error::UnsupportedNet: return "Unsupported net.";
    case Error::UnsupportedNode: return "Unsupported node.";
    case Error::LostGuarding: return "Lost guarding message.";
    case Error::LostConnection: return "Lost connection.";
    case Error::HeartbeatStarted: return "Heartbeat started.";
    case Error::HeartbeatLost: return "Heartbeat lost.";
    case Error::WrongNmtState: return "Wrong NMT state.";
    case Error::BootUp: return "Boot-up.";
    case Error::ErrorPassive: return "Error passive.";
    case Error::BusOff: return "Bus off.";
    case Error::CanBufferOverflow: return "CAN buffer overflow.";
    case Error::CanInit: return "CAN init.";
    case Error::CanActive: return "CAN active.";
    case Error::PdoAlreadyUsed: return "PDO already used.";
    case Error::PdoLengthExceeded: return "PDO length exceeded.";
    case Error::LssManufacturer: return "LSS manufacturer error.";
    case Error::LssNodeIdNotSupported: return "LSS node-ID not supported.";
    case Error::LssBitrateNotSupported: return "LSS bit-rate not supported.";
    case Error::LssStoreFailed: return "LSS parameter storing failed.";
    case Error::LssMedia: return "LSS media error.";
    case Error::OutOfMemory: return "Running out of memory.";
  }
  return "-";
}

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

unsigned lss_bitrate_kbit(std::uint8_t table_index) {
  constexpr unsigned kTable[] = {1000, 800, 500, 250, 125, 0, 50, 20, 10, 0};
  return table_index < std::size(kTable) ? kTable[table_index] : 0;
}

// ---- parsing -----------------------------------------------------------------

namespace {

struct Fail {
  Error error;
};

// The value token that must be the last one on the line.
template <typename T>
std::optional<T> last_u(Cursor& c, std::uint64_t lo, std::uint64_t hi) {
  const auto tok = c.token();
  if (tok.empty() || !c.at_end()) return std::nullopt;
  auto v = parse_u(tok, lo, hi);
  if (!v) return std::nullopt;
  return static_cast<T>(*v);
}

// A value token that must not be the last one.
template <typename T>
std::optional<T> inner_u(Cursor& c, std::uint64_t lo, std::uint64_t hi) {
  const auto tok = c.token();
  if (tok.empty() || c.at_end()) return std::nullopt;
  auto v = parse_u(tok, lo, hi);
  if (!v) return std::nullopt;
  return static_cast<T>(*v);
}

std::variant<Command, Fail> parse_lss(const std::string& cmd, Cursor& c) {
  const Fail syntax{Error::Syntax};
  if (cmd == "lss_switch_glob") {
    if (c.at_end()) return syntax;
    auto v = last_u<std::uint8_t>(c, 0, 1);
    if (!v) return syntax;
    return Command{LssCommand{LssSwitchGlobal{*v == 1}}};
  }
  if (cmd == "lss_switch_sel") {
    if (c.at_end()) return syntax;
    auto v = inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF);
    auto p = v ? inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : std::nullopt;
    auto r = p ? inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : std::nullopt;
    auto s = r ? last_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : std::nullopt;
    if (!s) return syntax;
    return Command{LssCommand{LssSwitchSelective{{*v, *p, *r, *s}}}};
  }
  if (cmd == "lss_set_node") {
    if (c.at_end()) return syntax;
    auto v = last_u<std::uint8_t>(c, 0, 0xFF);
    if (!v || (*v > 0x7F && *v < 0xFF)) return syntax;
    return Command{LssCommand{LssSetNode{*v}}};
  }
  if (cmd == "lss_conf_bitrate") {
    if (c.at_end()) return syntax;
    auto sel = inner_u<std::uint8_t>(c, 0, 0);  // only the CiA 301 table
    auto idx = sel ? last_u<std::uint8_t>(c, 0, 9) : std::nullopt;
    if (!idx || *idx == 5) return syntax;
    return Command{LssCommand{LssConfigureBitrate{*sel, *idx}}};
  }
  if (cmd == "lss_activate_bitrate") {
    if (c.at_end()) return syntax;
    auto v = last_u<std::uint16_t>(c, 0, 0xFFFF);
    if (!v) return syntax;
    return Command{LssCommand{LssActivateBitrate{*v}}};
  }
  if (cmd == "lss_store") {
    if (!c.at_end()) return syntax;
    return Command{LssCommand{LssStore{}}};
  }
  if (cmd == "lss_inquire_addr") {
    if (c.at_end()) return Command{LssCommand{LssInquireAddress{}}};
    auto v = last_u<std::uint8_t>(c, 0, 3);
    if (!v) return syntax;
    return Command{LssCommand{LssInquireAddress{*v}}};
  }
  if (cmd == "lss_get_node") {
    if (!c.at_end()) return syntax;
    return Command{LssCommand{LssGetNode{}}};
  }
  if (cmd == "_lss_fastscan") {
    LssFastscan f;
    if (!c.at_end()) {
      auto v = last_u<std::uint16_t>(c, 0, 0xFFFF);
      if (!v) return syntax;
      if (*v != 0) f.timeout_ms = *v;
    }
    return Command{LssCommand{f}};
  }
  if (cmd == "lss_allnodes") {
    LssAllNodes a;
    if (c.at_end()) return Command{LssCommand{a}};
    auto t = parse_u(c.token(), 0, 0xFFFF);
    if (!t) return syntax;
    if (*t != 0) a.timeout_ms = static_cast<std::uint16_t>(*t);
    if (c.at_end()) return Command{LssCommand{a}};
    auto first = inner_u<std::uint8_t>(c, 1, 127);
    if (!first) return syntax;
    a.first_node = *first;
    auto store = parse_u(c.token(), 0, 1);
    if (!store) return syntax;
    a.store = *store == 1;
    if (c.at_end()) return Command{LssCommand{a}};
    std::uint32_t* words[] = {&a.match.vendor_id, &a.match.product_code, &a.match.revision, &a.match.serial};
    for (int i = 0; i < 4; ++i) {
      auto s = inner_u<std::uint8_t>(c, 0, 2);
      auto w = s ? (i < 3 ? inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : last_u<std::uint32_t>(c, 0, 0xFFFFFFFF))
                 : std::nullopt;
      if (!w) return syntax;
      a.scan[static_cast<std::size_t>(i)] = static_cast<LssScan>(*s);
      *words[i] = *w;
    }
    return Command{LssCommand{a}};
  }
  return Fail{Error::RequestNotSupported};
}

}  // namespace

Parsed parse_line(std::string_view line, const Defaults& defaults) {
  Parsed out;
  Cursor c(line);
  if (c.at_end()) return out;  // blank or comment only
  out.kind = Parsed::Kind::error;
  auto fail = [&](Error e) {
    out.kind = Parsed::Kind::error;
    out.error = e;
    return out;
  };
  // The mandatory "[<sequence>]".
  const std::string_view seq_tok = c.token();
  if (c.at_end() || seq_tok.size() < 3 || seq_tok.front() != '[' || seq_tok.back() != ']') return fail(Error::Syntax);
  auto seq = parse_u(seq_tok.substr(1, seq_tok.size() - 2), 0, 0xFFFFFFFF);
  if (!seq) return fail(Error::Syntax);
  out.seq = static_cast<std::uint32_t>(*seq);
  out.line.seq = *out.seq;

  // Up to two numbers (node, or net and node), then the command.
  std::uint64_t nums[2] = {};
  int count = 0;
  std::string_view tok;
  for (;;) {
    tok = c.token();
    if (tok.empty()) return fail(Error::Syntax);
    if (tok[0] < '0' || tok[0] > '9') break;
    if (count == 2 || c.at_end()) return fail(Error::Syntax);
    auto v = parse_u(tok, 0, 0xFFFFFFFF);
    if (!v) return fail(Error::Syntax);
    nums[count++] = *v;
  }
  std::uint16_t net = defaults.net;
  std::optional<std::uint8_t> node = defaults.node;
  if (count == 1) {
    if (nums[0] > 127) return fail(Error::UnsupportedNode);
    node = static_cast<std::uint8_t>(nums[0]);
  } else if (count == 2) {
    if (nums[0] > 0xFFFF) return fail(Error::UnsupportedNet);
    if (nums[1] > 127) return fail(Error::UnsupportedNode);
    net = static_cast<std::uint16_t>(nums[0]);
    node = static_cast<std::uint8_t>(nums[1]);
  }
  out.line.net = net;
  const std::string cmd = lowered(tok);
  auto done = [&](Command command, std::uint8_t n = 0) {
    out.kind = Parsed::Kind::command;
    out.line.node = n;
    out.line.command = std::move(command);
    return out;
  };
  // The node a command addresses: 105 without one, 107 below `min`.
  auto need_node = [&](std::uint8_t min) -> std::optional<Error> {
    if (!node) return Error::NoDefaultNode;
    if (*node < min) return Error::UnsupportedNode;
    return std::nullopt;
  };

  if (cmd == "set") {
    if (c.at_end()) return fail(Error::Syntax);
    const std::string what = lowered(c.token());
    if (what == "network") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint16_t>(c, 0, 0xFFFF);
      if (!v) return fail(Error::Syntax);
      return done(SetNetwork{*v});
    }
    if (what == "node") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint8_t>(c, 1, 127);
      if (!v) return fail(Error::Syntax);
      return done(SetNode{*v});
    }
    if (what == "sdo_timeout") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint16_t>(c, 1, 0xFFFF);
      if (!v) return fail(Error::Syntax);
      return done(SetSdoTimeout{*v});
    }
    if (what == "sdo_block") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint8_t>(c, 0, 1);
      if (!v) return fail(Error::Syntax);
      return done(SetSdoBlock{*v == 1});
    }
    return fail(Error::RequestNotSupported);
  }
  if (cmd == "r" || cmd == "read") {
    if (auto e = need_node(1)) return fail(*e);
    if (c.at_end()) return fail(Error::Syntax);
    auto index = inner_u<std::uint16_t>(c, 0, 0xFFFF);
    if (!index) return fail(Error::Syntax);
    auto sub = parse_u(c.token(), 0, 0xFF);
    if (!sub) return fail(Error::Syntax);
    SdoReadCmd r{*index, static_cast<std::uint8_t>(*sub), Datatype::hex};
    if (!c.at_end()) {
      const auto t = c.token();
      if (!c.at_end()) return fail(Error::Syntax);
      auto dt = datatype_from_name(t);
      if (!dt) return fail(Error::Syntax);
      r.type = *dt;
    }
    return done(r, *node);
  }
  if (cmd == "w" || cmd == "write") {
    if (auto e = need_node(1)) return fail(*e);
    if (c.at_end()) return fail(Error::Syntax);
    auto index = inner_u<std::uint16_t>(c, 0, 0xFFFF);
    auto sub = index ? inner_u<std::uint8_t>(c, 0, 0xFF) : std::nullopt;
    if (!sub) return fail(Error::Syntax);
    const auto t = c.token();
    if (t.empty() || c.at_end()) return fail(Error::Syntax);
    auto dt = datatype_from_name(t);
    if (!dt) return fail(Error::Syntax);
    auto data = parse_value(*dt, c.rest());
    if (!data) return fail(Error::Syntax);
    return done(SdoWriteCmd{*index, *sub, *dt, std::move(*data)}, *node);
  }
  auto nmt = [&](canopen::NmtCommand command) {
    if (auto e = need_node(0)) return fail(*e);
    if (!c.at_end()) return fail(Error::Syntax);
    return done(NmtCmd{command}, *node);
  };
  if (cmd == "start") return nmt(canopen::NmtCommand::Start);
  if (cmd == "stop") return nmt(canopen::NmtCommand::Stop);
  if (cmd == "preop" || cmd == "preoperational") return nmt(canopen::NmtCommand::EnterPreOperational);
  if (cmd == "reset") {
    if (auto e = need_node(0)) return fail(*e);
    if (c.at_end()) return fail(Error::Syntax);
    const std::string what = lowered(c.token());
    if (!c.at_end()) return fail(Error::Syntax);
    if (what == "node") return done(NmtCmd{canopen::NmtCommand::ResetNode}, *node);
    if (what == "comm" || what == "communication") return done(NmtCmd{canopen::NmtCommand::ResetCommunication}, *node);
    return fail(Error::Syntax);
  }
  if (cmd == "help") {
    if (c.at_end()) return done(Help{HelpTopic::general});
    const std::string what = lowered(c.token());
    if (!c.at_end()) return fail(Error::Syntax);
    if (what == "datatype") return done(Help{HelpTopic::datatype});
    if (what == "lss") return done(Help{HelpTopic::lss});
    return fail(Error::Syntax);
  }
  if (cmd.starts_with("lss_") || cmd == "_lss_fastscan") {
    auto r = parse_lss(cmd, c);
    if (auto* f = std::get_if<Fail>(&r)) return fail(f->error);
    return done(std::get<Command>(std::move(r)));
  }
  return fail(Error::RequestNotSupported);
}

// ---- canonical text ------------------------------------------------------------

namespace {

std::string value_text(const SdoWriteCmd& w) {
  const auto& d = w.data;
  switch (w.type) {
    case Datatype::hex: return print_value(Datatype::hex, d);
    case Datatype::vs: {
      std::string s = "\"";
      for (auto b : d) {
        s += static_cast<char>(b);
        if (b == '"') s += '"';
      }
      return s + "\"";
    }
    case Datatype::os:
    case Datatype::us:
    case Datatype::d: return print_value(w.type, d);
    case Datatype::r32: {
      float f = 0;
      const auto bits = static_cast<std::uint32_t>(get_le(d));
      std::memcpy(&f, &bits, 4);
      return printf_string("%a", static_cast<double>(f));
    }
    case Datatype::r64: {
      double f = 0;
      const auto bits = get_le(d);
      std::memcpy(&f, &bits, 8);
      return printf_string("%a", f);
    }
    default: break;
  }
  // Integers: hex for x, decimal otherwise (what parse_value reads back).
  const std::uint64_t v = get_le(d);
  switch (w.type) {
    case Datatype::i8: return std::to_string(static_cast<std::int8_t>(v));
    case Datatype::i16: return std::to_string(static_cast<std::int16_t>(v));
    case Datatype::i32: return std::to_string(static_cast<std::int32_t>(v));
    case Datatype::i64: return std::to_string(static_cast<std::int64_t>(v));
    case Datatype::x8:
    case Datatype::x16:
    case Datatype::x32:
    case Datatype::x64: return printf_string("0x%llX", static_cast<unsigned long long>(v));
    default: return std::to_string(v);
  }
}

std::string nmt_text(canopen::NmtCommand c) {
  switch (c) {
    case canopen::NmtCommand::Start: return "start";
    case canopen::NmtCommand::Stop: return "stop";
    case canopen::NmtCommand::EnterPreOperational: return "preop";
    case canopen::NmtCommand::ResetNode: return "reset node";
    case canopen::NmtCommand::ResetCommunication: return "reset comm";
  }
  return "start";
}

std::string lss_text(const LssCommand& l) {
  auto u = [](std::uint64_t v) { return std::to_string(v); };
  return std::visit(
      [&](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, LssSwitchGlobal>) return "lss_switch_glob " + u(x.configuration ? 1 : 0);
        if constexpr (std::is_same_v<T, LssSwitchSelective>)
          return "lss_switch_sel " + u(x.identity.vendor_id) + " " + u(x.identity.product_code) + " " +
                 u(x.identity.revision) + " " + u(x.identity.serial);
        if constexpr (std::is_same_v<T, LssSetNode>) return "lss_set_node " + u(x.node);
        if constexpr (std::is_same_v<T, LssConfigureBitrate>)
          return "lss_conf_bitrate " + u(x.table_selector) + " " + u(x.table_index);
        if constexpr (std::is_same_v<T, LssActivateBitrate>) return "lss_activate_bitrate " + u(x.switch_delay_ms);
        if constexpr (std::is_same_v<T, LssStore>) return "lss_store";
        if constexpr (std::is_same_v<T, LssInquireAddress>)
          return x.lss_sub ? "lss_inquire_addr " + u(*x.lss_sub) : std::string("lss_inquire_addr");
        if constexpr (std::is_same_v<T, LssGetNode>) return "lss_get_node";
        if constexpr (std::is_same_v<T, LssFastscan>) return "_lss_fastscan " + u(x.timeout_ms);
        if constexpr (std::is_same_v<T, LssAllNodes>) {
          std::string s = "lss_allnodes " + u(x.timeout_ms) + " " + u(x.first_node) + " " + u(x.store ? 1 : 0);
          const std::uint32_t words[] = {x.match.vendor_id, x.match.product_code, x.match.revision, x.match.serial};
          for (std::size_t i = 0; i < 4; ++i) s += " " + u(static_cast<unsigned>(x.scan[i])) + " " + u(words[i]);
          return s;
        }
      },
      l);
}

}  // namespace

std::string format_line(const Line& line) {
  std::string s = "[" + std::to_string(line.seq) + "] " + std::to_string(line.net) + " " +
                  std::to_string(line.node) + " ";
  std::visit(
      [&](const auto& x) {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, SdoReadCmd>)
          s += "r " + printf_string("0x%04X", static_cast<unsigned>(x.index)) + " " + std::to_string(x.sub) + " " +
               std::string(datatype_name(x.type));
        if constexpr (std::is_same_v<T, SdoWriteCmd>)
          s += "w " + printf_string("0x%04X", static_cast<unsigned>(x.index)) + " " + std::to_string(x.sub) + " " +
               std::string(datatype_name(x.type)) + " " + value_text(x);
        if constexpr (std::is_same_v<T, NmtCmd>) s += nmt_text(x.command);
        if constexpr (std::is_same_v<T, SetNetwork>) s += "set network " + std::to_string(x.net);
        if constexpr (std::is_same_v<T, SetNode>) s += "set node " + std::to_string(x.node);
        if constexpr (std::is_same_v<T, SetSdoTimeout>) s += "set sdo_timeout " + std::to_string(x.ms);
        if constexpr (std::is_same_v<T, SetSdoBlock>) s += std::string("set sdo_block ") + (x.on ? "1" : "0");
        if constexpr (std::is_same_v<T, Help>)
          s += x.topic == HelpTopic::general ? "help" : x.topic == HelpTopic::datatype ? "help datatype" : "help lss";
        if constexpr (std::is_same_v<T, LssCommand>) s += lss_text(x);
      },
      line.command);
  return s;
}

// ---- framing -------------------------------------------------------------------

void LineFramer::feed(std::string_view data, std::vector<Item>& out) {
  while (!data.empty()) {
    const auto nl = data.find('\n');
    const std::string_view piece = data.substr(0, nl);
    if (discarding_) {
      // The rest of an over-long line, up to its end.
    } else if (buf_.size() + piece.size() > max_) {
      buf_.append(piece.substr(0, max_ - buf_.size()));
      out.push_back({std::move(buf_), true});
      buf_.clear();
      discarding_ = true;
    } else {
      buf_.append(piece);
    }
    if (nl == std::string_view::npos) return;
    if (!discarding_) {
      out.push_back({std::move(buf_), false});
      buf_.clear();
    }
    discarding_ = false;
    data.remove_prefix(nl + 1);
  }
}

// ---- responses -----------------------------------------------------------------

std::string ok_response(std::uint32_t seq) { return "[" + std::to_string(seq) + "] OK\r\n"; }

std::string error_response(std::uint32_t seq, Error e) {
  return "[" + std::to_string(seq) + "] ERROR:" + std::to_string(static_cast<unsigned>(e)) + " #" +
         std::string(error_text(e)) + "\r\n";
}

std::string abort_response(std::uint32_t seq, std::uint32_t abort_code) {
  return "[" + std::to_string(seq) + "] ERROR:" + printf_string("0x%08lX", static_cast<unsigned long>(abort_code)) +
         " #" + std::string(canopen::sdo_abort_text(abort_code)) + "\r\n";
}

std::string empty_response() { return "\r\n"; }

std::string_view help_text(HelpTopic topic) {
  // Written for this gateway; the layout (a leading "\n", lines ending in
  // "\n", the last one in "\r\n") is what CiA 309-3 clients expect.
  static constexpr std::string_view kGeneral =
      "\n"
      "Every command starts with \"[<sequence>]\" (a number echoed in the answer):\n"
      "[[<net>] <node>] r[ead] <index> <subindex> [<datatype>]   SDO upload (datatype default: hex)\n"
      "[[<net>] <node>] w[rite] <index> <subindex> <datatype> <value>   SDO download\n"
      "[[<net>] <node>] start | stop | preop[erational]   NMT command (node 0: all nodes)\n"
      "[[<net>] <node>] reset node | reset comm[unication]   NMT reset\n"
      "set network <net> | set node <node>   this connection's defaults\n"
      "set sdo_timeout <ms> | set sdo_block <0|1>   SDO options (defaults 500 ms, no block)\n"
      "help [datatype|lss]   this text, the datatypes or the LSS commands\n"
      "\n"
      "Answers: \"[<sequence>] OK\", \"[<sequence>] <value>\", \"[<sequence>] ERROR:<code>\"\n"
      "(100 not supported, 101 syntax, 102 internal state, 103 time-out, 104/105 no\n"
      "default net/node, 106/107 unsupported net/node, 600 line too long) or\n"
      "\"[<sequence>] ERROR:0x<SDO abort code>\". Networks are the gateway's, from 1.\n"
      "Lines end with LF or CR LF; '#' starts a comment; commands are case-insensitive.\r\n";
  static constexpr std::string_view kDatatype =
      "\n"
      "Datatypes:\n"
      "b                   boolean (0 or 1)\n"
      "i8 i16 i32 i64      signed integers\n"
      "u8 u16 u32 u64      unsigned integers\n"
      "x8 x16 x32 x64      unsigned integers shown in hex\n"
      "r32 r64             floating point\n"
      "vs                  visible string (in double quotes when it has spaces, \"\" for \")\n"
      "os us d             octet string, unicode string, domain: base64 on one line\n"
      "hex                 bytes in hex, optionally separated by spaces\r\n";
  static constexpr std::string_view kLss =
      "\n"
      "LSS commands (CiA 305), \"[<sequence>] [<net>]\" first:\n"
      "lss_switch_glob <0|1>                      all slaves waiting (0) or configuration (1)\n"
      "lss_switch_sel <vendor> <product> <revision> <serial>   select one slave\n"
      "lss_set_node <node>                        node-ID of the selected slave\n"
      "lss_conf_bitrate 0 <index>                 bit timing: 0=1000 1=800 2=500 3=250\n"
      "                                           4=125 6=50 7=20 8=10 kbit/s, 9=auto\n"
      "lss_activate_bitrate <delay ms>            switch every slave to the new bit rate\n"
      "lss_store                                  selected slave stores its configuration\n"
      "lss_inquire_addr [<0..3>]                  identity word(s) of the selected slave\n"
      "lss_get_node                               node-ID of the selected slave\n"
      "_lss_fastscan [<timeout ms>]               find one unconfigured slave (default 100 ms)\n"
      "lss_allnodes [<timeout ms> [<first node> <store 0|1>\n"
      "             [<scan> <vendor> <scan> <product> <scan> <revision> <scan> <serial>]]]\n"
      "                                           give every unconfigured slave a node-ID\n"
      "                                           (scan: 0 fastscan, 1 ignore, 2 match)\r\n";
  switch (topic) {
    case HelpTopic::datatype: return kDatatype;
    case HelpTopic::lss: return kLss;
    case HelpTopic::general: break;
  }
  return kGeneral;
}

std::string lss_node_response(std::uint32_t seq, std::uint8_t node) {
  return "[" + std::to_string(seq) + "] " + printf_string("0x%02X", static_cast<unsigned>(node)) + "\r\n";
}

std::string lss_word_response(std::uint32_t seq, std::uint32_t value) {
  return "[" + std::to_string(seq) + "] " + printf_string("0x%08lX", static_cast<unsigned long>(value)) + "\r\n";
}

namespace {
std::string identity_words(const LssIdentity& id) {
  return printf_string("0x%08lX 0x%08lX 0x%08lX 0x%08lX", static_cast<unsigned long>(id.vendor_id),
                       static_cast<unsigned long>(id.product_code), static_cast<unsigned long>(id.revision),
                       static_cast<unsigned long>(id.serial));
}
}  // namespace

std::string lss_identity_response(std::uint32_t seq, const LssIdentity& id) {
  return "[" + std::to_string(seq) + "] " + identity_words(id) + "\r\n";
}

std::string lss_assigned_line(std::uint8_t node, const LssIdentity& id) {
  return "# Node-ID " + std::to_string(node) + " assigned to: " + identity_words(id) + "\n";
}

std::string lss_allnodes_finished(std::uint32_t seq, unsigned found) {
  return "# Found " + std::to_string(found) + " nodes, search finished.\n" + ok_response(seq);
}

}  // namespace gateway::ascii
