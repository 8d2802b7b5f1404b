#include "log.hpp"

#include <chrono>
#include <ctime>

#include "canopen/types.hpp"

namespace gateway {

std::optional<LogLevel> parse_log_level(std::string_view s) {
  if (s == "trace") return LogLevel::Trace;
  if (s == "debug") return LogLevel::Debug;
  if (s == "info") return LogLevel::Info;
  if (s == "warn" || s == "warning") return LogLevel::Warn;
  if (s == "error") return LogLevel::Error;
  return std::nullopt;
}

namespace {

// Length of the UTF-8 sequence at s[i] that printable() keeps, 0 when the
// byte must be escaped (malformed, overlong or surrogate UTF-8, or a C0/C1
// control or DEL).
std::size_t kept_length(std::string_view s, std::size_t i) {
  char32_t cp = 0;
  const std::size_t n = canopen::utf8_sequence(s, i, &cp);
  if (n == 0 || cp < 0x20 || (cp >= 0x7F && cp <= 0x9F)) return 0;
  return n;
}

void append_printable(std::string& out, std::string_view s, bool newline_as_backslash_n) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  for (std::size_t i = 0; i < s.size();) {
    if (const auto n = kept_length(s, i)) {
      out.append(s.data() + i, n);
      i += n;
    } else if (s[i] == '\n' && newline_as_backslash_n) {
      out.append("\\n");
      ++i;
    } else {
      const auto c = static_cast<unsigned char>(s[i++]);
      out.append({'\\', 'x', kHex[c >> 4], kHex[c & 0xF]});
    }
  }
}

constexpr std::string_view kNames[] = {"TRACE", "DEBUG", "INFO ", "WARN ", "ERROR"};

void append_utc_now(std::string& out) {
  const auto now = std::chrono::system_clock::now();
  const auto secs = std::chrono::time_point_cast<std::chrono::seconds>(now);
  const auto micros = std::chrono::duration_cast<std::chrono::microseconds>(now - secs).count();
  const std::time_t t = std::chrono::system_clock::to_time_t(secs);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[40];
  const int n = std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%06ldZ", tm.tm_year + 1900,
                              tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                              static_cast<long>(micros));
  out.append(buf, static_cast<std::size_t>(n));
}

}  // namespace

std::string printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  append_printable(out, text, false);
  return out;
}

void Logger::log(LogLevel l, std::string_view msg) {
  if (!enabled(l)) return;
  append_utc_now(buffer_);
  buffer_.push_back(' ');
  buffer_.append(kNames[static_cast<int>(l)]);
  buffer_.push_back(' ');
  append_printable(buffer_, msg, true);
  buffer_.push_back('\n');
  if (l >= LogLevel::Warn || buffer_.size() > 64 * 1024) flush();
}

void Logger::flush() {
  if (buffer_.empty()) return;
  std::fwrite(buffer_.data(), 1, buffer_.size(), out_);
  std::fflush(out_);
  buffer_.clear();
}

}  // namespace gateway
