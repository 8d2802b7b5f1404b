// CANopen data types (CiA 301 7.1): names, sizes, little-endian codecs,
// text conversion and range checks.
#include "canopen/types.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <system_error>

#include "canopen/sdo/abort.hpp"

namespace canopen {

namespace {

struct TypeInfo {
  DataType type;
  std::string_view cia309;
  std::string_view standard;
  std::size_t size;  // bytes; 0 = variable length
};

// CiA 301 table 44 (data type indexes) and CiA 309-3 names.
constexpr std::array<TypeInfo, 25> kTypes{{
    {DataType::Boolean, "b", "BOOLEAN", 1},
    {DataType::Integer8, "i8", "INTEGER8", 1},
    {DataType::Integer16, "i16", "INTEGER16", 2},
    {DataType::Integer32, "i32", "INTEGER32", 4},
    {DataType::Unsigned8, "u8", "UNSIGNED8", 1},
    {DataType::Unsigned16, "u16", "UNSIGNED16", 2},
    {DataType::Unsigned32, "u32", "UNSIGNED32", 4},
    {DataType::Real32, "r32", "REAL32", 4},
    {DataType::VisibleString, "vs", "VISIBLE_STRING", 0},
    {DataType::OctetString, "os", "OCTET_STRING", 0},
    {DataType::UnicodeString, "us", "UNICODE_STRING", 0},
    {DataType::TimeOfDay, "t", "TIME_OF_DAY", 6},
    {DataType::TimeDifference, "td", "TIME_DIFFERENCE", 6},
    {DataType::Domain, "d", "DOMAIN", 0},
    {DataType::Integer24, "i24", "INTEGER24", 3},
    {DataType::Real64, "r64", "REAL64", 8},
    {DataType::Integer40, "i40", "INTEGER40", 5},
    {DataType::Integer48, "i48", "INTEGER48", 6},
    {DataType::Integer56, "i56", "INTEGER56", 7},
    {DataType::Integer64, "i64", "INTEGER64", 8},
    {DataType::Unsigned24, "u24", "UNSIGNED24", 3},
    {DataType::Unsigned40, "u40", "UNSIGNED40", 5},
    {DataType::Unsigned48, "u48", "UNSIGNED48", 6},
    {DataType::Unsigned56, "u56", "UNSIGNED56", 7},
    {DataType::Unsigned64, "u64", "UNSIGNED64", 8},
}};

// Index of each type's entry in kTypes by its 16-bit code (all codes are < 0x1C);
// decode() runs per PDO value, so no linear search there.
constexpr auto kByCode = [] {
  std::array<std::int8_t, 0x1C> by_code{};
  by_code.fill(-1);
  for (std::size_t i = 0; i < kTypes.size(); ++i)
    by_code[static_cast<std::size_t>(kTypes[i].type)] = static_cast<std::int8_t>(i);
  return by_code;
}();

const TypeInfo* find_info(DataType t) {
  const auto code = static_cast<std::size_t>(t);
  if (code >= kByCode.size() || kByCode[code] < 0) return nullptr;
  return &kTypes[static_cast<std::size_t>(kByCode[code])];
}

constexpr std::int64_t kMsPerDay = 86'400'000;
// 1984-01-01 is day 5113 of the Unix epoch.
constexpr std::int64_t kEpoch1984Days = 5113;

[[noreturn]] void type_mismatch(const Value& v) {
  std::fprintf(stderr, "canopen: value data does not match its type %04x\n", static_cast<unsigned>(v.type));
  std::abort();
}

template <typename T>
const T& data_as(const Value& v) {
  const T* p = std::get_if<T>(&v.data);
  assert(p && "value data does not match its type");
  if (p == nullptr) type_mismatch(v);
  return *p;
}

std::string type_label(DataType t) {
  auto n = cia309_name(t);
  if (n.empty()) return "type " + std::to_string(static_cast<unsigned>(t));
  return std::string(n);
}

Error error(SdoAbort code, std::string detail) { return Error{make_error_code(code), std::move(detail)}; }

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (lower(a[i]) != lower(b[i])) return false;
  }
  return true;
}

std::string quote(std::string_view s) {
  std::string out = "\"";
  out.append(s);
  out += '"';
  return out;
}

// ---- little-endian helpers ----

void put_le(Bytes& out, std::uint64_t v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::uint64_t get_le(std::span<const std::uint8_t> b) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < b.size() && i < 8; ++i) v |= std::uint64_t{b[i]} << (8 * i);
  return v;
}

// ---- UTF-8 / UTF-16 ----

void append_utf8(std::string& out, char32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

// Unpaired surrogates become U+FFFD so the result is always valid UTF-8.
std::string utf16_to_utf8(const std::u16string& s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    char32_t c = s[i];
    if (c >= 0xD800 && c <= 0xDBFF && i + 1 < s.size() && s[i + 1] >= 0xDC00 && s[i + 1] <= 0xDFFF) {
      c = 0x10000 + ((c - 0xD800) << 10) + (char32_t{s[i + 1]} - 0xDC00);
      ++i;
    } else if (c >= 0xD800 && c <= 0xDFFF) {
      c = 0xFFFD;
    }
    append_utf8(out, c);
  }
  return out;
}


// Strict UTF-8 decoding (no overlongs, no surrogates); nullopt if invalid.
std::optional<std::u16string> utf8_to_utf16(std::string_view s) {
  std::u16string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    char32_t cp = 0;
    const std::size_t n = utf8_sequence(s, i, &cp);
    if (n == 0) return std::nullopt;
    i += n;
    if (cp >= 0x10000) {
      cp -= 0x10000;
      out += static_cast<char16_t>(0xD800 + (cp >> 10));
      out += static_cast<char16_t>(0xDC00 + (cp & 0x3FF));
    } else {
      out += static_cast<char16_t>(cp);
    }
  }
  return out;
}

// ---- hex ----

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string to_hex(const Bytes& b) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(b.size() * 2);
  for (auto x : b) {
    out += kDigits[x >> 4];
    out += kDigits[x & 0xF];
  }
  return out;
}

// ---- integers ----

struct ParsedInt {
  bool negative = false;
  std::uint64_t magnitude = 0;
  bool overflow = false;  // magnitude does not fit 64 bits
};

// Decimal, 0x hex or leading-0 octal with an optional sign; nullopt on
// anything else (empty, trailing garbage, fractions, exponents).
std::optional<ParsedInt> parse_int_text(std::string_view s) {
  ParsedInt r;
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) {
    r.negative = s.front() == '-';
    s.remove_prefix(1);
  }
  unsigned base = 10;
  if (s.size() >= 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    base = 16;
    s.remove_prefix(2);
  } else if (s.size() >= 2 && s[0] == '0') {
    base = 8;
    s.remove_prefix(1);
  }
  if (s.empty()) return std::nullopt;
  for (char c : s) {
    const int d = hex_digit(c);
    if (d < 0 || static_cast<unsigned>(d) >= base) return std::nullopt;
    const auto ud = static_cast<std::uint64_t>(d);
    if (r.magnitude > (std::numeric_limits<std::uint64_t>::max() - ud) / base) {
      r.overflow = true;
    } else {
      r.magnitude = r.magnitude * base + ud;
    }
  }
  return r;
}

std::string above(std::string_view text, std::string_view limit, DataType t) {
  return std::string(text) + " is above " + std::string(limit) + " (" + type_label(t) + ")";
}
std::string below(std::string_view text, std::string_view limit, DataType t) {
  return std::string(text) + " is below " + std::string(limit) + " (" + type_label(t) + ")";
}

Result<Value> int_from_parsed(DataType type, const ParsedInt& p, std::string_view text) {
  if (is_unsigned_integer(type)) {
    const auto max = unsigned_max(type);
    if (p.negative && (p.magnitude != 0 || p.overflow)) return error(SdoAbort::ValueTooLow, below(text, "0", type));
    if (p.overflow || p.magnitude > max) return error(SdoAbort::ValueTooHigh, above(text, std::to_string(max), type));
    return Value::of_unsigned(type, p.magnitude);
  }
  const auto min = signed_min(type);
  const auto max = signed_max(type);
  if (p.negative) {
    const auto min_mag = std::uint64_t{0} - static_cast<std::uint64_t>(min);  // |min|
    if (p.overflow || p.magnitude > min_mag)
      return error(SdoAbort::ValueTooLow, below(text, std::to_string(min), type));
    return Value::of_signed(type, static_cast<std::int64_t>(std::uint64_t{0} - p.magnitude));
  }
  if (p.overflow || p.magnitude > static_cast<std::uint64_t>(max)) {
    return error(SdoAbort::ValueTooHigh, above(text, std::to_string(max), type));
  }
  return Value::of_signed(type, static_cast<std::int64_t>(p.magnitude));
}

Result<Value> parse_integer(DataType type, std::string_view text) {
  auto p = parse_int_text(text);
  if (!p) return error(SdoAbort::InvalidValue, quote(text) + " is not an integer (" + type_label(type) + ")");
  return int_from_parsed(type, *p, text);
}

// ---- reals ----

std::string format_double(double d) {
  if (std::isnan(d)) return "nan";
  if (std::isinf(d)) return d < 0 ? "-inf" : "inf";
  std::array<char, 32> buf{};
  auto r = std::to_chars(buf.data(), buf.data() + buf.size(), d);
  return std::string(buf.data(), r.ptr);
}

std::string format_float(float f) {
  if (std::isnan(f)) return "nan";
  if (std::isinf(f)) return f < 0 ? "-inf" : "inf";
  std::array<char, 32> buf{};
  auto r = std::to_chars(buf.data(), buf.data() + buf.size(), f);
  return std::string(buf.data(), r.ptr);
}

std::optional<double> parse_double_text(std::string_view s) {
  bool negative = false;
  std::string_view body = s;
  if (!body.empty() && (body.front() == '+' || body.front() == '-')) {
    negative = body.front() == '-';
    body.remove_prefix(1);
  }
  // from_chars takes no '+' and would accept a second '-'.
  if (body.empty() || body.front() == '+' || body.front() == '-') return std::nullopt;
  double d = 0;
  auto r = std::from_chars(body.data(), body.data() + body.size(), d, std::chars_format::general);
  if (r.ptr != body.data() + body.size()) return std::nullopt;
  if (r.ec == std::errc::result_out_of_range) {
    // Over- or underflow: tell them apart by the exponent's sign.
    const auto e = body.find_first_of("eE");
    // Without an exponent only a zero integer part can underflow ("0.000...1").
    const bool tiny = e != std::string_view::npos
                          ? e + 1 < body.size() && body[e + 1] == '-'
                          : body.substr(0, body.find('.')).find_first_not_of('0') == std::string_view::npos;
    d = tiny ? 0.0 : std::numeric_limits<double>::infinity();
  } else if (r.ec != std::errc{}) {
    return std::nullopt;
  }
  return negative ? -d : d;
}

bool is_inf_text(std::string_view s) {
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) s.remove_prefix(1);
  return iequals(s, "inf") || iequals(s, "infinity");
}

Result<Value> parse_real(DataType type, std::string_view text) {
  auto d = parse_double_text(text);
  if (!d) return error(SdoAbort::InvalidValue, quote(text) + " is not a number (" + type_label(type) + ")");
  const bool explicit_inf = is_inf_text(text);
  if (type == DataType::Real64) {
    if (std::isinf(*d) && !explicit_inf) {
      return *d > 0 ? Result<Value>(error(SdoAbort::ValueTooHigh,
                                          above(text, format_double(std::numeric_limits<double>::max()), type)))
                    : Result<Value>(error(SdoAbort::ValueTooLow,
                                          below(text, format_double(-std::numeric_limits<double>::max()), type)));
    }
    return Value::of_real64(*d);
  }
  // Doubles from here up round to infinity as floats (FLT_MAX + half an ulp);
  // anything below rounds to at most FLT_MAX.
  constexpr double overflow = 0x1.ffffffp127;
  if (!explicit_inf && !std::isnan(*d) && *d >= overflow) {
    return error(SdoAbort::ValueTooHigh, above(text, format_float(std::numeric_limits<float>::max()), type));
  }
  if (!explicit_inf && !std::isnan(*d) && *d <= -overflow) {
    return error(SdoAbort::ValueTooLow, below(text, format_float(-std::numeric_limits<float>::max()), type));
  }
  return Value::of_real32(static_cast<float>(*d));
}

// ---- time ----

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  std::int64_t q = a / b;
  if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
  return q;
}

std::string format_rfc3339(std::int64_t unix_ms) {
  using namespace std::chrono;
  const std::int64_t days = floor_div(unix_ms, kMsPerDay);
  const std::int64_t ms_of_day = unix_ms - days * kMsPerDay;
  const year_month_day ymd{sys_days{std::chrono::days{days}}};
  const auto h = ms_of_day / 3'600'000;
  const auto mi = (ms_of_day / 60'000) % 60;
  const auto s = (ms_of_day / 1000) % 60;
  const auto ms = ms_of_day % 1000;
  std::array<char, 48> buf{};
  const int n =
      std::snprintf(buf.data(), buf.size(), "%04d-%02u-%02uT%02lld:%02lld:%02lld.%03lldZ", static_cast<int>(ymd.year()),
                    static_cast<unsigned>(ymd.month()), static_cast<unsigned>(ymd.day()), static_cast<long long>(h),
                    static_cast<long long>(mi), static_cast<long long>(s), static_cast<long long>(ms));
  return std::string(buf.data(), static_cast<std::size_t>(std::max(n, 0)));
}

// Reads exactly n decimal digits.
bool read_digits(std::string_view& s, std::size_t n, int& out) {
  if (s.size() < n) return false;
  int v = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
    v = v * 10 + (s[i] - '0');
  }
  out = v;
  s.remove_prefix(n);
  return true;
}

bool expect(std::string_view& s, char c) {
  if (s.empty() || lower(s.front()) != lower(c)) return false;
  s.remove_prefix(1);
  return true;
}

// RFC 3339 date-time ("2026-11-22T10:15:30.123Z", offsets allowed) -> Unix ms.
std::optional<std::int64_t> parse_rfc3339(std::string_view s) {
  using namespace std::chrono;
  int y = 0, mo = 0, d = 0, h = 0, mi = 0, sec = 0;
  if (!read_digits(s, 4, y) || !expect(s, '-') || !read_digits(s, 2, mo) || !expect(s, '-') || !read_digits(s, 2, d)) {
    return std::nullopt;
  }
  if (s.empty() || (lower(s.front()) != 't' && s.front() != ' ')) return std::nullopt;
  s.remove_prefix(1);
  if (!read_digits(s, 2, h) || !expect(s, ':') || !read_digits(s, 2, mi) || !expect(s, ':') ||
      !read_digits(s, 2, sec)) {
    return std::nullopt;
  }
  if (h > 23 || mi > 59 || sec > 59) return std::nullopt;
  std::int64_t frac_ms = 0;
  if (!s.empty() && s.front() == '.') {
    s.remove_prefix(1);
    std::size_t digits = 0;
    while (!s.empty() && s.front() >= '0' && s.front() <= '9') {
      if (digits < 3) frac_ms = frac_ms * 10 + (s.front() - '0');
      ++digits;
      s.remove_prefix(1);
    }
    if (digits == 0) return std::nullopt;
    for (std::size_t k = digits; k < 3; ++k) frac_ms *= 10;  // sub-millisecond digits are truncated
  }
  std::int64_t offset_min = 0;
  if (expect(s, 'z')) {
  } else if (!s.empty() && (s.front() == '+' || s.front() == '-')) {
    const bool neg = s.front() == '-';
    s.remove_prefix(1);
    int oh = 0, om = 0;
    if (!read_digits(s, 2, oh) || !expect(s, ':') || !read_digits(s, 2, om) || oh > 23 || om > 59) return std::nullopt;
    offset_min = (neg ? -1 : 1) * (oh * 60 + om);
  } else {
    return std::nullopt;
  }
  if (!s.empty()) return std::nullopt;
  const year_month_day ymd{year{y}, month{static_cast<unsigned>(mo)}, day{static_cast<unsigned>(d)}};
  if (!ymd.ok()) return std::nullopt;
  const std::int64_t days = sys_days{ymd}.time_since_epoch().count();
  return days * kMsPerDay + ((h * 60 + mi) * 60 + sec) * std::int64_t{1000} + frac_ms - offset_min * 60'000;
}

Result<Value> parse_time(DataType type, std::string_view text) {
  const auto invalid = [&] {
    return Result<Value>(error(SdoAbort::InvalidValue,
                               quote(text) + " is not a valid " + type_label(type) +
                                   (type == DataType::TimeOfDay ? " (\"days ms\" or RFC 3339)" : " (\"days ms\")")));
  };
  // "days ms" (a date has its '-' at [4] and may use a space before the time)
  const bool looks_like_date = text.size() > 4 && text[4] == '-';
  const auto sp = text.find_first_of(" \t");
  if (sp != std::string_view::npos && !looks_like_date) {
    const auto days_text = text.substr(0, sp);
    const auto ms_text = trim(text.substr(sp));
    auto days = parse_int_text(days_text);
    auto ms = parse_int_text(ms_text);
    if (!days || !ms || ms_text.find_first_of(" \t") != std::string_view::npos) return invalid();
    if (days->negative && days->magnitude != 0) return error(SdoAbort::ValueTooLow, below(text, "0 days", type));
    if (ms->negative && ms->magnitude != 0) return error(SdoAbort::ValueTooLow, below(text, "0 ms", type));
    if (days->overflow || days->magnitude > 0xFFFF)
      return error(SdoAbort::ValueTooHigh, above(text, "65535 days", type));
    if (ms->overflow || ms->magnitude >= static_cast<std::uint64_t>(kMsPerDay)) {
      return error(SdoAbort::ValueTooHigh, above(text, "86399999 ms", type));
    }
    return Value{type,
                 TimeOfDay{static_cast<std::uint32_t>(ms->magnitude), static_cast<std::uint16_t>(days->magnitude)}};
  }
  if (type != DataType::TimeOfDay) return invalid();
  auto unix_ms = parse_rfc3339(text);
  if (!unix_ms) return invalid();
  const std::int64_t first = kEpoch1984Days * kMsPerDay;
  const std::int64_t last = (kEpoch1984Days + 0xFFFF + 1) * kMsPerDay - 1;
  if (*unix_ms < first) return error(SdoAbort::ValueTooLow, below(text, format_rfc3339(first), type));
  if (*unix_ms > last) return error(SdoAbort::ValueTooHigh, above(text, format_rfc3339(last), type));
  return Value{type, time_of_day_from_unix_ms(*unix_ms)};
}

// ---- numeric view for check_limits ----

struct Num {
  enum Kind { Signed, Unsigned, Real } kind = Signed;
  std::int64_t i = 0;
  std::uint64_t u = 0;
  double d = 0;
};

std::optional<Num> as_num(const Value& v) {
  if (const auto* b = std::get_if<bool>(&v.data)) return Num{Num::Signed, *b ? 1 : 0, 0, 0};
  if (const auto* i = std::get_if<std::int64_t>(&v.data)) return Num{Num::Signed, *i, 0, 0};
  if (const auto* u = std::get_if<std::uint64_t>(&v.data)) return Num{Num::Unsigned, 0, *u, 0};
  if (const auto* f = std::get_if<float>(&v.data)) return Num{Num::Real, 0, 0, static_cast<double>(*f)};
  if (const auto* d = std::get_if<double>(&v.data)) return Num{Num::Real, 0, 0, *d};
  return std::nullopt;
}

// Three-way comparison of an integer with a double without precision loss;
// nullopt when d is NaN.
template <typename I>
std::optional<int> cmp_int_real(I i, double d) {
  if (std::isnan(d)) return std::nullopt;
  constexpr double lo = static_cast<double>(std::numeric_limits<I>::min());  // 0 or -2^63, exact
  constexpr double hi = std::is_signed_v<I> ? 9223372036854775808.0 : 18446744073709551616.0;
  if (d >= hi) return -1;
  if (d < lo) return 1;
  const double t = std::trunc(d);
  const I ti = static_cast<I>(t);
  if (i < ti) return -1;
  if (i > ti) return 1;
  const double frac = d - t;
  return frac > 0 ? -1 : (frac < 0 ? 1 : 0);
}

// -1, 0, 1; nullopt when unordered (NaN).
std::optional<int> compare(const Num& a, const Num& b) {
  auto sgn = [](auto x, auto y) { return x < y ? -1 : (x > y ? 1 : 0); };
  using K = Num::Kind;
  if (a.kind == K::Signed && b.kind == K::Signed) return sgn(a.i, b.i);
  if (a.kind == K::Unsigned && b.kind == K::Unsigned) return sgn(a.u, b.u);
  if (a.kind == K::Signed && b.kind == K::Unsigned) return a.i < 0 ? -1 : sgn(static_cast<std::uint64_t>(a.i), b.u);
  if (a.kind == K::Unsigned && b.kind == K::Signed) return b.i < 0 ? 1 : sgn(a.u, static_cast<std::uint64_t>(b.i));
  if (a.kind == K::Real && b.kind == K::Real) {
    if (std::isnan(a.d) || std::isnan(b.d)) return std::nullopt;
    return sgn(a.d, b.d);
  }
  if (a.kind == K::Real) {
    auto r = b.kind == K::Signed ? cmp_int_real(b.i, a.d) : cmp_int_real(b.u, a.d);
    if (!r) return std::nullopt;
    return -*r;
  }
  return a.kind == K::Signed ? cmp_int_real(a.i, b.d) : cmp_int_real(a.u, b.d);
}

}  // namespace

// ---- names and sizes ----

std::optional<DataType> data_type_from_index(std::uint16_t index) {
  const auto* i = find_info(static_cast<DataType>(index));
  if (i == nullptr) return std::nullopt;
  return i->type;
}

std::string_view cia309_name(DataType t) {
  const auto* i = find_info(t);
  return i ? i->cia309 : std::string_view{};
}

std::string_view standard_name(DataType t) {
  const auto* i = find_info(t);
  return i ? i->standard : std::string_view{};
}

std::optional<DataType> parse_type_name(std::string_view name) {
  for (const auto& i : kTypes) {
    if (name == i.cia309) return i.type;
  }
  for (const auto& i : kTypes) {
    if (iequals(name, i.standard)) return i.type;
  }
  return std::nullopt;
}

std::optional<std::size_t> fixed_size(DataType t) {
  const auto* i = find_info(t);
  if (i == nullptr || i->size == 0) return std::nullopt;
  return i->size;
}

unsigned pdo_bit_size(DataType t) {
  if (t == DataType::Boolean) return 1;
  auto s = fixed_size(t);
  return s ? static_cast<unsigned>(*s * 8) : 0;
}

bool is_signed_integer(DataType t) {
  switch (t) {
    case DataType::Integer8:
    case DataType::Integer16:
    case DataType::Integer24:
    case DataType::Integer32:
    case DataType::Integer40:
    case DataType::Integer48:
    case DataType::Integer56:
    case DataType::Integer64: return true;
    default: return false;
  }
}

bool is_unsigned_integer(DataType t) {
  switch (t) {
    case DataType::Unsigned8:
    case DataType::Unsigned16:
    case DataType::Unsigned24:
    case DataType::Unsigned32:
    case DataType::Unsigned40:
    case DataType::Unsigned48:
    case DataType::Unsigned56:
    case DataType::Unsigned64: return true;
    default: return false;
  }
}

bool is_real(DataType t) { return t == DataType::Real32 || t == DataType::Real64; }

bool is_variable_length(DataType t) { return !fixed_size(t).has_value(); }

Value Value::zero(DataType t) {
  if (t == DataType::Boolean) return of_bool(false);
  if (is_signed_integer(t)) return of_signed(t, 0);
  if (is_unsigned_integer(t)) return of_unsigned(t, 0);
  switch (t) {
    case DataType::Real32: return of_real32(0.0f);
    case DataType::Real64: return of_real64(0.0);
    case DataType::VisibleString: return of_string({});
    case DataType::UnicodeString: return Value{t, std::u16string{}};
    case DataType::TimeOfDay:
    case DataType::TimeDifference: return Value{t, TimeOfDay{}};
    default: return of_bytes(t, {});
  }
}

std::int64_t signed_min(DataType t) {
  if (is_signed_integer(t)) {
    const auto bits = *fixed_size(t) * 8;
    return bits == 64 ? std::numeric_limits<std::int64_t>::min() : -(std::int64_t{1} << (bits - 1));
  }
  return 0;
}

std::int64_t signed_max(DataType t) {
  if (is_signed_integer(t)) {
    const auto bits = *fixed_size(t) * 8;
    return bits == 64 ? std::numeric_limits<std::int64_t>::max() : (std::int64_t{1} << (bits - 1)) - 1;
  }
  if (is_unsigned_integer(t)) {
    return static_cast<std::int64_t>(
        std::min<std::uint64_t>(unsigned_max(t), std::numeric_limits<std::int64_t>::max()));
  }
  if (t == DataType::Boolean) return 1;
  return 0;
}

std::uint64_t unsigned_max(DataType t) {
  if (is_unsigned_integer(t)) {
    const auto bits = *fixed_size(t) * 8;
    return bits == 64 ? std::numeric_limits<std::uint64_t>::max() : (std::uint64_t{1} << bits) - 1;
  }
  if (is_signed_integer(t)) return static_cast<std::uint64_t>(signed_max(t));
  if (t == DataType::Boolean) return 1;
  return 0;
}

// ---- codecs ----

void encode_into(const Value& v, Bytes& out) {
  const DataType t = v.type;
  if (t == DataType::Boolean) {
    out.push_back(data_as<bool>(v) ? 1 : 0);
    return;
  }
  if (is_signed_integer(t)) {
    put_le(out, static_cast<std::uint64_t>(data_as<std::int64_t>(v)), *fixed_size(t));
    return;
  }
  if (is_unsigned_integer(t)) {
    put_le(out, data_as<std::uint64_t>(v), *fixed_size(t));
    return;
  }
  switch (t) {
    case DataType::Real32: put_le(out, std::bit_cast<std::uint32_t>(data_as<float>(v)), 4); return;
    case DataType::Real64: put_le(out, std::bit_cast<std::uint64_t>(data_as<double>(v)), 8); return;
    case DataType::VisibleString: {
      const auto& s = data_as<std::string>(v);
      out.insert(out.end(), s.begin(), s.end());
      return;
    }
    case DataType::UnicodeString:
      for (char16_t c : data_as<std::u16string>(v)) put_le(out, c, 2);
      return;
    case DataType::TimeOfDay:
    case DataType::TimeDifference: {
      const auto& tod = data_as<TimeOfDay>(v);
      put_le(out, tod.ms & 0x0FFF'FFFFu, 4);  // upper 4 bits reserved (0)
      put_le(out, tod.days, 2);
      return;
    }
    default: {
      const auto& b = data_as<Bytes>(v);
      out.insert(out.end(), b.begin(), b.end());
      return;
    }
  }
}

bool holds_its_type(const Value& v) {
  const DataType t = v.type;
  if (t == DataType::Boolean) return std::holds_alternative<bool>(v.data);
  if (is_signed_integer(t)) return std::holds_alternative<std::int64_t>(v.data);
  if (is_unsigned_integer(t)) return std::holds_alternative<std::uint64_t>(v.data);
  switch (t) {
    case DataType::Real32: return std::holds_alternative<float>(v.data);
    case DataType::Real64: return std::holds_alternative<double>(v.data);
    case DataType::VisibleString: return std::holds_alternative<std::string>(v.data);
    case DataType::OctetString:
    case DataType::Domain: return std::holds_alternative<Bytes>(v.data);
    case DataType::UnicodeString: return std::holds_alternative<std::u16string>(v.data);
    case DataType::TimeOfDay:
    case DataType::TimeDifference: return std::holds_alternative<TimeOfDay>(v.data);
    default: return false;
  }
}

std::size_t encoded_size(const Value& v) {
  if (auto s = fixed_size(v.type)) return *s;
  if (const auto* str = std::get_if<std::string>(&v.data)) return str->size();
  if (const auto* bytes = std::get_if<Bytes>(&v.data)) return bytes->size();
  if (const auto* u16 = std::get_if<std::u16string>(&v.data)) return 2 * u16->size();
  return 0;
}

Bytes encode(const Value& v) {
  Bytes out;
  if (auto s = fixed_size(v.type)) out.reserve(*s);
  encode_into(v, out);
  return out;
}

Result<Value> decode(DataType type, std::span<const std::uint8_t> bytes) {
  if (find_info(type) == nullptr) {
    return error(SdoAbort::InvalidValue, "unknown data type " + std::to_string(static_cast<unsigned>(type)));
  }
  if (auto size = fixed_size(type)) {
    if (bytes.size() < *size) {
      return error(SdoAbort::LengthTooLow,
                   std::to_string(bytes.size()) + " bytes, " + type_label(type) + " needs " + std::to_string(*size));
    }
    if (bytes.size() > *size) {
      return error(SdoAbort::LengthTooHigh,
                   std::to_string(bytes.size()) + " bytes, " + type_label(type) + " needs " + std::to_string(*size));
    }
  }
  if (type == DataType::Boolean) return Value::of_bool(bytes[0] != 0);
  if (is_unsigned_integer(type)) return Value::of_unsigned(type, get_le(bytes));
  if (is_signed_integer(type)) {
    const auto bits = bytes.size() * 8;
    std::uint64_t u = get_le(bytes);
    if (bits < 64 && (u >> (bits - 1)) != 0) u |= ~std::uint64_t{0} << bits;  // sign-extend
    return Value::of_signed(type, static_cast<std::int64_t>(u));
  }
  switch (type) {
    case DataType::Real32: return Value::of_real32(std::bit_cast<float>(static_cast<std::uint32_t>(get_le(bytes))));
    case DataType::Real64: return Value::of_real64(std::bit_cast<double>(get_le(bytes)));
    case DataType::VisibleString: {
      const auto nul = std::find(bytes.begin(), bytes.end(), std::uint8_t{0});
      return Value::of_string(std::string(bytes.begin(), nul));
    }
    case DataType::UnicodeString: {
      if (bytes.size() % 2 != 0) {
        return error(SdoAbort::LengthMismatch,
                     std::to_string(bytes.size()) + " bytes, us needs an even number (UTF-16)");
      }
      std::u16string s;
      s.reserve(bytes.size() / 2);
      for (std::size_t i = 0; i + 1 < bytes.size(); i += 2) {
        const auto c = static_cast<char16_t>(bytes[i] | (bytes[i + 1] << 8));
        if (c == 0) break;  // like VISIBLE_STRING: a NUL ends the text
        s += c;
      }
      return Value{type, std::move(s)};
    }
    case DataType::TimeOfDay:
    case DataType::TimeDifference: {
      const auto word = static_cast<std::uint32_t>(get_le(bytes.first(4)));
      const auto days = static_cast<std::uint16_t>(get_le(bytes.subspan(4, 2)));
      return Value{type, TimeOfDay{word & 0x0FFF'FFFFu, days}};  // reserved bits ignored
    }
    default: return Value::of_bytes(type, Bytes(bytes.begin(), bytes.end()));
  }
}

// ---- text ----

Result<Value> parse_value(DataType type, std::string_view raw) {
  if (find_info(type) == nullptr) {
    return error(SdoAbort::InvalidValue, "unknown data type " + std::to_string(static_cast<unsigned>(type)));
  }
  // Strings keep their spaces; everything else ignores surrounding whitespace.
  if (type == DataType::VisibleString) return Value::of_string(std::string(raw));
  if (type == DataType::UnicodeString) {
    auto s = utf8_to_utf16(raw);
    if (!s) return error(SdoAbort::InvalidValue, "text is not valid UTF-8 (us)");
    return Value{type, std::move(*s)};
  }
  const std::string_view text = trim(raw);
  if (type == DataType::OctetString || type == DataType::Domain) {
    Bytes b;
    int hi = -1;
    for (char c : text) {
      if (is_space(c)) continue;
      const int d = hex_digit(c);
      if (d < 0) return error(SdoAbort::InvalidValue, quote(text) + " is not hex (" + type_label(type) + ")");
      if (hi < 0) {
        hi = d;
      } else {
        b.push_back(static_cast<std::uint8_t>((hi << 4) | d));
        hi = -1;
      }
    }
    if (hi >= 0)
      return error(SdoAbort::InvalidValue, quote(text) + " has an odd number of hex digits (" + type_label(type) + ")");
    return Value::of_bytes(type, std::move(b));
  }
  if (text.empty()) return error(SdoAbort::InvalidValue, "empty value (" + type_label(type) + ")");
  if (type == DataType::Boolean) {
    if (text == "1" || iequals(text, "true")) return Value::of_bool(true);
    if (text == "0" || iequals(text, "false")) return Value::of_bool(false);
    return error(SdoAbort::InvalidValue, quote(text) + " is not a boolean (b: 0, 1, true, false)");
  }
  if (is_signed_integer(type) || is_unsigned_integer(type)) return parse_integer(type, text);
  if (is_real(type)) return parse_real(type, text);
  return parse_time(type, text);
}

std::string format_value(const Value& v) {
  return std::visit(
      [&](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, bool>) {
          return x ? "1" : "0";  // as in EDS files
        } else if constexpr (std::is_same_v<T, std::int64_t> || std::is_same_v<T, std::uint64_t>) {
          return std::to_string(x);
        } else if constexpr (std::is_same_v<T, float>) {
          return format_float(x);
        } else if constexpr (std::is_same_v<T, double>) {
          return format_double(x);
        } else if constexpr (std::is_same_v<T, std::string>) {
          return x;
        } else if constexpr (std::is_same_v<T, Bytes>) {
          return to_hex(x);
        } else if constexpr (std::is_same_v<T, std::u16string>) {
          return utf16_to_utf8(x);
        } else {
          if (v.type == DataType::TimeOfDay) return format_rfc3339(unix_ms_from_time_of_day(x));
          return std::to_string(x.days) + " " + std::to_string(x.ms);
        }
      },
      v.data);
}

std::error_code check_limits(const Value& v, const std::optional<Value>& low, const std::optional<Value>& high,
                             std::string* detail) {
  const auto n = as_num(v);
  if (!n) return {};
  const auto fail = [&](SdoAbort code, std::string text) {
    if (detail) *detail = std::move(text);
    return make_error_code(code);
  };
  if (low) {
    if (auto l = as_num(*low)) {
      auto c = compare(*n, *l);
      if (!c)
        return fail(SdoAbort::InvalidValue,
                    format_value(v) + " cannot be compared with the low limit " + format_value(*low) +
                        " (" + type_label(v.type) + ")");
      if (*c < 0) {
        return fail(SdoAbort::ValueTooLow, format_value(v) + " is below the low limit " + format_value(*low) + " (" +
                                               type_label(v.type) + ")");
      }
    }
  }
  if (high) {
    if (auto h = as_num(*high)) {
      auto c = compare(*n, *h);
      if (!c)
        return fail(SdoAbort::InvalidValue,
                    format_value(v) + " cannot be compared with the high limit " + format_value(*high) +
                        " (" + type_label(v.type) + ")");
      if (*c > 0) {
        return fail(SdoAbort::ValueTooHigh, format_value(v) + " is above the high limit " + format_value(*high) + " (" +
                                                type_label(v.type) + ")");
      }
    }
  }
  return {};
}

// ---- TIME_OF_DAY <-> Unix time ----

TimeOfDay time_of_day_from_unix_ms(std::int64_t unix_ms) {
  // Clamped to what TIME_OF_DAY can hold: 1984-01-01 .. day 65535.
  const std::int64_t rel = unix_ms - kEpoch1984Days * kMsPerDay;
  if (rel < 0) return TimeOfDay{0, 0};
  const std::int64_t days = rel / kMsPerDay;
  if (days > 0xFFFF) return TimeOfDay{static_cast<std::uint32_t>(kMsPerDay - 1), 0xFFFF};
  return TimeOfDay{static_cast<std::uint32_t>(rel % kMsPerDay), static_cast<std::uint16_t>(days)};
}

std::int64_t unix_ms_from_time_of_day(const TimeOfDay& t) { return (kEpoch1984Days + t.days) * kMsPerDay + t.ms; }

// No overlongs, surrogates or code points above U+10FFFF.
std::size_t utf8_sequence(std::string_view s, std::size_t i, char32_t* cp_out) {
  const auto b0 = static_cast<unsigned char>(s[i]);
  if (b0 < 0x80) {
    *cp_out = b0;
    return 1;
  }
  std::size_t n = 0;
  char32_t cp = 0;
  if ((b0 & 0xE0) == 0xC0) {
    n = 2;
    cp = b0 & 0x1Fu;
  } else if ((b0 & 0xF0) == 0xE0) {
    n = 3;
    cp = b0 & 0x0Fu;
  } else if ((b0 & 0xF8) == 0xF0) {
    n = 4;
    cp = b0 & 0x07u;
  } else {
    return 0;
  }
  if (i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k) {
    const auto b = static_cast<unsigned char>(s[i + k]);
    if ((b & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b & 0x3Fu);
  }
  constexpr std::array<char32_t, 5> kMin = {0, 0, 0x80, 0x800, 0x10000};
  if (cp < kMin[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  *cp_out = cp;
  return n;
}

bool is_utf8(std::string_view s) {
  for (std::size_t i = 0; i < s.size();) {
    char32_t cp = 0;
    const std::size_t n = utf8_sequence(s, i, &cp);
    if (n == 0) return false;
    i += n;
  }
  return true;
}

std::string latin1_to_utf8(std::string_view s) {
  std::string out;
  out.reserve(s.size() * 2);
  for (char c : s) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x80) {
      out += c;
    } else {
      out += static_cast<char>(0xC0 | (b >> 6));
      out += static_cast<char>(0x80 | (b & 0x3F));
    }
  }
  return out;
}

}  // namespace canopen
