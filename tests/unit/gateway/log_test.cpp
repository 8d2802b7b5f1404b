// Tests for gateway/log.cpp: the leveled logger's line format, filtering and
// buffering (records below warn wait for flush(), warn/error go out at once).
#include "log.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <regex>
#include <string>
#include <vector>

namespace gateway {
namespace {

// Captures what the logger writes, through a real FILE*.
class Capture {
 public:
  Capture() : file_(std::tmpfile()) {}
  ~Capture() {
    if (file_) std::fclose(file_);
  }
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;

  std::FILE* file() const { return file_; }

  std::string text() const {
    std::fflush(file_);
    const long end = std::ftell(file_);
    std::string s(static_cast<std::size_t>(end), '\0');
    std::rewind(file_);
    const std::size_t n = std::fread(s.data(), 1, s.size(), file_);
    s.resize(n);
    std::fseek(file_, 0, SEEK_END);
    return s;
  }

  std::vector<std::string> lines() const {
    std::vector<std::string> out;
    const std::string t = text();
    std::size_t start = 0;
    while (start < t.size()) {
      const auto nl = t.find('\n', start);
      if (nl == std::string::npos) {
        out.push_back(t.substr(start));
        break;
      }
      out.push_back(t.substr(start, nl - start));
      start = nl + 1;
    }
    return out;
  }

 private:
  std::FILE* file_;
};

// "<time> <LEVEL> <message>" with the level padded to five characters.
std::string message_of(const std::string& line) {
  return line.size() > 34 ? line.substr(34) : std::string();
}
std::string level_of(const std::string& line) { return line.size() >= 33 ? line.substr(28, 5) : std::string(); }

TEST(LogLevelParse, AcceptsContractNames) {
  EXPECT_EQ(parse_log_level("trace"), LogLevel::Trace);
  EXPECT_EQ(parse_log_level("debug"), LogLevel::Debug);
  EXPECT_EQ(parse_log_level("info"), LogLevel::Info);
  EXPECT_EQ(parse_log_level("warn"), LogLevel::Warn);
  EXPECT_EQ(parse_log_level("warning"), LogLevel::Warn);
  EXPECT_EQ(parse_log_level("error"), LogLevel::Error);
}

TEST(LogLevelParse, RejectsOtherNames) {
  for (const char* s : {"", "verbose", "fatal", "inf", "info ", " info", "err"}) {
    EXPECT_FALSE(parse_log_level(s)) << '"' << s << '"';
  }
}

TEST(Logger, LineFormatIsUtcRfc3339LevelMessage) {
  Capture cap;
  Logger log(LogLevel::Trace, cap.file());
  log.error("bus-off on can0");
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  const std::regex re(R"(^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{6}Z ERROR bus-off on can0$)");
  EXPECT_TRUE(std::regex_match(lines[0], re)) << lines[0];
  EXPECT_EQ(cap.text().back(), '\n');
}

TEST(Logger, TimestampIsCurrentUtcTime) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  const auto before = std::chrono::system_clock::now();
  log.warn("x");
  const auto after = std::chrono::system_clock::now();
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  std::tm tm{};
  ASSERT_TRUE(strptime(lines[0].c_str(), "%Y-%m-%dT%H:%M:%S", &tm));
  const auto logged = std::chrono::system_clock::from_time_t(timegm(&tm));
  EXPECT_GE(logged, std::chrono::floor<std::chrono::seconds>(before));
  EXPECT_LE(logged, after);
}

TEST(Logger, LevelNamesArePaddedToFiveCharacters) {
  Capture cap;
  Logger log(LogLevel::Trace, cap.file());
  log.trace("t");
  log.debug("d");
  log.info("i");
  log.warn("w");
  log.error("e");
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 5U);
  EXPECT_EQ(level_of(lines[0]), "TRACE");
  EXPECT_EQ(level_of(lines[1]), "DEBUG");
  EXPECT_EQ(level_of(lines[2]), "INFO ");
  EXPECT_EQ(level_of(lines[3]), "WARN ");
  EXPECT_EQ(level_of(lines[4]), "ERROR");
  EXPECT_EQ(message_of(lines[0]), "t");
  EXPECT_EQ(message_of(lines[2]), "i");
  EXPECT_EQ(message_of(lines[4]), "e");
}

TEST(Logger, RecordsBelowLevelAreDropped) {
  Capture cap;
  Logger log(LogLevel::Warn, cap.file());
  EXPECT_FALSE(log.enabled(LogLevel::Info));
  EXPECT_TRUE(log.enabled(LogLevel::Warn));
  EXPECT_TRUE(log.enabled(LogLevel::Error));
  log.trace("t");
  log.debug("d");
  log.info("i");
  log.flush();
  EXPECT_EQ(cap.text(), "");
  log.warn("w");
  ASSERT_EQ(cap.lines().size(), 1U);
  EXPECT_EQ(message_of(cap.lines()[0]), "w");
}

TEST(Logger, DefaultLevelIsInfo) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  EXPECT_FALSE(log.enabled(LogLevel::Debug));
  EXPECT_TRUE(log.enabled(LogLevel::Info));
  Logger default_log;
  EXPECT_FALSE(default_log.enabled(LogLevel::Debug));
  EXPECT_TRUE(default_log.enabled(LogLevel::Info));
}

TEST(Logger, SetLevelChangesFilter) {
  Capture cap;
  Logger log(LogLevel::Error, cap.file());
  log.warn("hidden");
  log.set_level(LogLevel::Debug);
  log.debug("shown");
  log.flush();
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(message_of(lines[0]), "shown");
}

TEST(Logger, InfoAndBelowAreBufferedUntilFlush) {
  Capture cap;
  Logger log(LogLevel::Trace, cap.file());
  log.trace("a");
  log.debug("b");
  log.info("c");
  EXPECT_EQ(cap.text(), "") << "records below warn wait for flush()";
  log.flush();
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 3U);
  EXPECT_EQ(message_of(lines[0]), "a");
  EXPECT_EQ(message_of(lines[1]), "b");
  EXPECT_EQ(message_of(lines[2]), "c");
}

TEST(Logger, WarnAndErrorAreWrittenAtOnce) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  log.warn("w");
  EXPECT_EQ(cap.lines().size(), 1U);
  log.error("e");
  EXPECT_EQ(cap.lines().size(), 2U);
}

TEST(Logger, WarnAlsoWritesEarlierBufferedRecordsInOrder) {
  Capture cap;
  Logger log(LogLevel::Debug, cap.file());
  log.info("first");
  log.debug("second");
  log.warn("third");
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 3U);
  EXPECT_EQ(message_of(lines[0]), "first");
  EXPECT_EQ(message_of(lines[1]), "second");
  EXPECT_EQ(message_of(lines[2]), "third");
  EXPECT_EQ(level_of(lines[2]), "WARN ");
}

TEST(Logger, FlushWithNothingBufferedWritesNothing) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  log.flush();
  log.flush();
  EXPECT_EQ(cap.text(), "");
}

TEST(Logger, FlushTwiceDoesNotDuplicate) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  log.info("once");
  log.flush();
  log.flush();
  EXPECT_EQ(cap.lines().size(), 1U);
}

TEST(Logger, LargeBufferIsWrittenWithoutExplicitFlush) {
  // A saturated bus logged at debug must not grow the buffer without bound.
  Capture cap;
  Logger log(LogLevel::Debug, cap.file());
  const std::string msg(100, 'x');
  int logged = 0;
  while (cap.text().empty()) {
    log.debug(msg);
    ASSERT_LT(++logged, 10'000) << "buffer never written";
  }
  const auto lines = cap.lines();
  EXPECT_EQ(static_cast<int>(lines.size()), logged) << "the write contains every record so far";
  // Whole lines only.
  EXPECT_EQ(cap.text().back(), '\n');
  for (const auto& l : lines) EXPECT_EQ(message_of(l), msg);
  // Roughly 64 KiB of buffered text, not one write per record.
  EXPECT_GT(cap.text().size(), 60U * 1024U);
}

TEST(Logger, EmptyMessageStillMakesALine) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  log.error("");
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(level_of(lines[0]), "ERROR");
}

TEST(Logger, LogWithExplicitLevel) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  log.log(LogLevel::Warn, "via log()");
  log.log(LogLevel::Debug, "filtered");
  log.flush();
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(message_of(lines[0]), "via log()");
}

TEST(Logger, NewlinesInAMessageStayOnOneLine) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  log.warn("first\nsecond");
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(message_of(lines[0]), "first\\nsecond");
}

// Issue 13: input quoted in a message (a YAML value, a flag, a device's
// string) cannot end the line or drive the terminal.
TEST(Printable, ControlCharactersBecomeHexEscapes) {
  EXPECT_EQ(printable("plain text: 'can0' 1017h"), "plain text: 'can0' 1017h");
  EXPECT_EQ(printable(std::string("a\x01" "b\tc\rd\ne\x7f" "f", 11)), "a\\x01b\\x09c\\x0Dd\\x0Ae\\x7Ff");
  EXPECT_EQ(printable("\x1b[2J"), "\\x1B[2J");
  EXPECT_EQ(printable(std::string("nul\0here", 8)), "nul\\x00here");
}

TEST(Printable, Utf8StaysButC1ControlsAndMalformedBytesAreEscaped) {
  EXPECT_EQ(printable("Drehzahl \xC3\xBC \xE2\x82\xAC \xF0\x9F\x98\x80"), "Drehzahl \xC3\xBC \xE2\x82\xAC \xF0\x9F\x98\x80");
  EXPECT_EQ(printable("\xC2\x9B" "31m"), "\\xC2\\x9B31m") << "U+009B (CSI) is a control character";
  EXPECT_EQ(printable("latin-1 \xFC"), "latin-1 \\xFC");
  EXPECT_EQ(printable("cut \xE2\x82"), "cut \\xE2\\x82");
  EXPECT_EQ(printable("overlong \xC0\xAF"), "overlong \\xC0\\xAF");
  EXPECT_EQ(printable("surrogate \xED\xA0\x80"), "surrogate \\xED\\xA0\\x80");
}

TEST(Printable, IsIdempotent) {
  const std::string once = printable(std::string("a\x01\xFF\x1b\\x41", 8));
  EXPECT_EQ(printable(once), once);
}

TEST(Logger, ControlCharactersInAMessageAreEscaped) {
  Capture cap;
  Logger log(LogLevel::Info, cap.file());
  log.warn("node name \x1b[31mred\x07");
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(message_of(lines[0]), "node name \\x1B[31mred\\x07");
}

TEST(Logger, BufferedRecordsAreWrittenWhenTheLoggerIsDestroyed) {
  Capture cap;
  {
    Logger log(LogLevel::Debug, cap.file());
    log.debug("last words");
  }
  const auto lines = cap.lines();
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(message_of(lines[0]), "last words");
}

}  // namespace
}  // namespace gateway
