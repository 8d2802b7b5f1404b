#include "messages/json_text.hpp"

#include "core/format.hpp"

#include <algorithm>
#include <array>
#include <boost/json/serialize.hpp>
#include <charconv>
#include <cmath>
#include <variant>

#include "canopen/json_value.hpp"

namespace gateway::detail {

namespace {

constexpr char kHex[] = "0123456789abcdef";

template <typename T>
void append_chars(std::string& out, T v) {
  std::array<char, 32> buf{};
  const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  out.append(buf.data(), r.ptr);
}

// Integer types whose every value fits a JSON number exactly (<= 48 bits),
// the same split as value_to_json.
bool fits_json_number(canopen::DataType t) { return canopen::fixed_size(t).value_or(8) <= 6; }

}  // namespace

std::string to_utf8(std::string_view s) { return is_utf8(s) ? std::string(s) : canopen::latin1_to_utf8(s); }

void append_json_string(std::string& out, std::string_view s) {
  out += '"';
  // Runs of characters that need no escape are appended in one go.
  std::size_t run = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto b = static_cast<unsigned char>(s[i]);
    if (b >= 0x20 && b != '"' && b != '\\') continue;
    out.append(s.data() + run, i - run);
    run = i + 1;
    switch (b) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      default: {
        const char esc[] = {'\\', 'u', '0', '0', kHex[b >> 4], kHex[b & 0x0F]};
        out.append(esc, sizeof esc);
      }
    }
  }
  out.append(s.data() + run, s.size() - run);
  out += '"';
}

void append_uint(std::string& out, std::uint64_t v) { append_chars(out, v); }
void append_int(std::string& out, std::int64_t v) { append_chars(out, v); }

void append_hex(std::string& out, std::span<const std::uint8_t> bytes) { core::append_hex(out, bytes); }

std::string to_hex(std::span<const std::uint8_t> bytes) { return core::hex_bytes(bytes); }

std::string abort_code_text(std::uint32_t code) { return core::abort_code_text(code); }

UnixTime to_unix_time(std::chrono::system_clock::time_point tp) {
  using namespace std::chrono;
  const auto ns = duration_cast<nanoseconds>(tp.time_since_epoch());
  const auto s = floor<seconds>(ns);
  return {s.count(), static_cast<std::int32_t>((ns - s).count())};
}

void append_timestamp(std::string& out, UnixTime t) {
  using namespace std::chrono;
  const sys_seconds tp{seconds{t.seconds}};
  const auto day = floor<days>(tp);
  const year_month_day ymd{day};
  const hh_mm_ss hms{tp - day};
  // "YYYY-MM-DDTHH:MM:SS.nnnnnnnnnZ" built in place, then one append.
  std::array<char, 40> buf{};
  char* p = buf.data();
  const auto put2 = [&p](unsigned v) {
    *p++ = static_cast<char>('0' + v / 10 % 10);
    *p++ = static_cast<char>('0' + v % 10);
  };
  const auto y = static_cast<unsigned>(std::clamp(static_cast<int>(ymd.year()), 0, 9999));
  *p++ = '"';
  put2(y / 100);
  put2(y % 100);
  *p++ = '-';
  put2(static_cast<unsigned>(ymd.month()));
  *p++ = '-';
  put2(static_cast<unsigned>(ymd.day()));
  *p++ = 'T';
  put2(static_cast<unsigned>(hms.hours().count()));
  *p++ = ':';
  put2(static_cast<unsigned>(hms.minutes().count()));
  *p++ = ':';
  put2(static_cast<unsigned>(hms.seconds().count()));
  if (t.nanos > 0) {
    auto n = static_cast<std::uint32_t>(t.nanos);
    int digits = 9;
    if (n % 1'000'000 == 0) {
      n /= 1'000'000;
      digits = 3;
    } else if (n % 1'000 == 0) {
      n /= 1'000;
      digits = 6;
    }
    *p++ = '.';
    for (int i = digits - 1; i >= 0; --i) {
      p[i] = static_cast<char>('0' + n % 10);
      n /= 10;
    }
    p += digits;
  }
  *p++ = 'Z';
  *p++ = '"';
  out.append(buf.data(), static_cast<std::size_t>(p - buf.data()));
}

void append_value_json(std::string& out, const canopen::Value& v) {
  using canopen::DataType;
  const DataType t = v.type;
  if (t == DataType::Boolean) {
    out += std::get<bool>(v.data) ? "true" : "false";
    return;
  }
  if (canopen::is_signed_integer(t)) {
    const auto i = std::get<std::int64_t>(v.data);
    if (fits_json_number(t)) {
      append_int(out, i);
    } else {
      out += '"';
      append_int(out, i);
      out += '"';
    }
    return;
  }
  if (canopen::is_unsigned_integer(t)) {
    const auto u = std::get<std::uint64_t>(v.data);
    if (fits_json_number(t)) {
      append_uint(out, u);
    } else {
      out += '"';
      append_uint(out, u);
      out += '"';
    }
    return;
  }
  switch (t) {
    case DataType::Real32: {
      const float f = std::get<float>(v.data);
      // Shortest float text: 0.1f is 0.1, as in value_to_json.
      if (std::isfinite(f)) return append_chars(out, f);
      break;
    }
    case DataType::Real64: {
      const double d = std::get<double>(v.data);
      if (std::isfinite(d)) return append_chars(out, d);
      break;
    }
    case DataType::OctetString:
    case DataType::Domain: {
      const auto& b = std::get<canopen::Bytes>(v.data);
      out += '"';
      append_hex(out, b);
      out += '"';
      return;
    }
    case DataType::VisibleString: {
      const auto& s = std::get<std::string>(v.data);
      if (is_utf8(s)) return append_json_string(out, s);
      return append_json_string(out, to_utf8(s));
    }
    default: break;
  }
  // Rare shapes (non-finite reals, us, t, td): the reference conversion.
  out += boost::json::serialize(canopen::value_to_json(v));
}

}  // namespace gateway::detail
