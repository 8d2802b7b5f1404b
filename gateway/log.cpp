#include "log.hpp"

#include <chrono>
#include <ctime>

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

void Logger::log(LogLevel l, std::string_view msg) {
  if (!enabled(l)) return;
  append_utc_now(buffer_);
  buffer_.push_back(' ');
  buffer_.append(kNames[static_cast<int>(l)]);
  buffer_.push_back(' ');
  for (char c : msg) {
    if (c == '\n') buffer_.append("\\n");
    else buffer_.push_back(c);
  }
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
