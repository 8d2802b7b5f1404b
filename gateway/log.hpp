// Minimal leveled logger for the gateway process: one line per record,
// "<UTC RFC 3339 time> <LEVEL> <message>", written to stderr. Newlines in a
// message are written as "\n" and other control characters as printable()
// does, so a record is always one line and cannot drive the terminal.
//
// Records below warn are buffered and written by flush() (the event loop
// flushes after each batch of work), so a saturated bus logged at debug does
// not cost one write() per frame. warn and error are written at once.
//
// Thread safety: use from the io_context's thread only.
#pragma once

#include <cstdio>
#include <optional>
#include <string>
#include <string_view>

namespace gateway {

enum class LogLevel { Trace, Debug, Info, Warn, Error };

std::optional<LogLevel> parse_log_level(std::string_view s);

// `text` made safe to quote in a one-line message (errors, the log):
// control characters (C0, DEL, C1) and bytes that are not UTF-8 become
// "\xNN" (one per byte); everything else, UTF-8 included, stays.
// Idempotent: its output comes back unchanged. Thread-safe.
std::string printable(std::string_view text);

class Logger {
 public:
  explicit Logger(LogLevel level = LogLevel::Info, std::FILE* out = stderr) : level_(level), out_(out) {}
  ~Logger() { flush(); }
  Logger(const Logger&) = delete;
  Logger& operator=(const Logger&) = delete;

  bool enabled(LogLevel l) const { return l >= level_; }
  void set_level(LogLevel l) { level_ = l; }
  void log(LogLevel l, std::string_view msg);
  void flush();

  void trace(std::string_view m) { log(LogLevel::Trace, m); }
  void debug(std::string_view m) { log(LogLevel::Debug, m); }
  void info(std::string_view m) { log(LogLevel::Info, m); }
  void warn(std::string_view m) { log(LogLevel::Warn, m); }
  void error(std::string_view m) { log(LogLevel::Error, m); }

 private:
  LogLevel level_;
  std::FILE* out_;
  std::string buffer_;
};

}  // namespace gateway
