// Tests for gateway/cli.cpp: the canopen-gateway command line
// (api-contract.md, "Command line").
#include "cli.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace gateway {
namespace {

using ::testing::HasSubstr;

// Parses and returns the UsageError message; fails the test when no error.
std::string usage_error(const std::vector<std::string>& args) {
  try {
    parse_cli(args);
  } catch (const UsageError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a UsageError";
  return {};
}

TEST(Cli, SingleCanInterfaceWithDefaults) {
  const CliOptions o = parse_cli({"--can", "can0"});
  EXPECT_EQ(o.can_interfaces, (std::vector<std::string>{"can0"}));
  EXPECT_FALSE(o.node_id);  // not given: the config file's or the default (127)
  EXPECT_FALSE(o.log_level);
  EXPECT_FALSE(o.config_file);
  EXPECT_FALSE(o.mqtt_uri);
  EXPECT_FALSE(o.demo);
  EXPECT_FALSE(o.help);
  EXPECT_FALSE(o.version);
}

TEST(Cli, CanRepeatsAndKeepsNetworkOrder) {
  const CliOptions o = parse_cli({"--can", "vcan1", "--can", "can0", "--can=vcan7"});
  EXPECT_EQ(o.can_interfaces, (std::vector<std::string>{"vcan1", "can0", "vcan7"}));
}

TEST(Cli, NoInterfaceIsAnError) {
  EXPECT_THAT(usage_error({}), HasSubstr("--can"));
  EXPECT_THAT(usage_error({"--node-id", "5"}), HasSubstr("no CAN interface"));
}

TEST(Cli, HelpAndVersionNeedNoInterface) {
  EXPECT_TRUE(parse_cli({"--help"}).help);
  EXPECT_TRUE(parse_cli({"-h"}).help);
  EXPECT_TRUE(parse_cli({"--version"}).version);
}

TEST(Cli, NodeIdInRange) {
  EXPECT_EQ(parse_cli({"--can", "can0", "--node-id", "1"}).node_id, 1);
  EXPECT_EQ(parse_cli({"--can", "can0", "--node-id", "127"}).node_id, 127);
  EXPECT_EQ(parse_cli({"--can", "can0", "--node-id=42"}).node_id, 42);
}

TEST(Cli, NodeIdOutOfRangeIsRejected) {
  for (const char* v : {"0", "128", "-1", "255", "1000"}) {
    const std::string msg = usage_error({"--can", "can0", "--node-id", v});
    EXPECT_THAT(msg, HasSubstr("--node-id")) << v;
    EXPECT_THAT(msg, HasSubstr("1..127")) << v;
  }
}

TEST(Cli, NodeIdMustBeADecimalNumber) {
  for (const char* v : {"", "abc", "12abc", "0x10", " 5", "5 ", "+5", "99999999999999999999"}) {
    const std::string msg = usage_error({"--can", "can0", "--node-id", v});
    EXPECT_THAT(msg, HasSubstr("--node-id")) << '"' << v << '"';
  }
}

TEST(Cli, LogLevels) {
  const std::pair<const char*, LogLevel> cases[] = {
      {"trace", LogLevel::Trace}, {"debug", LogLevel::Debug}, {"info", LogLevel::Info},
      {"warn", LogLevel::Warn},   {"error", LogLevel::Error},
  };
  for (const auto& [text, level] : cases) {
    EXPECT_EQ(parse_cli({"--can", "can0", "--log-level", text}).log_level, level) << text;
    EXPECT_EQ(parse_cli({"--can", "can0", std::string("--log-level=") + text}).log_level, level) << text;
  }
}

TEST(Cli, UnknownLogLevelIsRejected) {
  const std::string msg = usage_error({"--can", "can0", "--log-level", "verbose"});
  EXPECT_THAT(msg, HasSubstr("--log-level"));
  EXPECT_THAT(msg, HasSubstr("verbose"));
}

TEST(Cli, MissingValueIsRejected) {
  EXPECT_THAT(usage_error({"--can"}), HasSubstr("--can: missing value"));
  EXPECT_THAT(usage_error({"--can", "can0", "--node-id"}), HasSubstr("--node-id: missing value"));
  EXPECT_THAT(usage_error({"--can", "can0", "--log-level"}), HasSubstr("--log-level: missing value"));
}

TEST(Cli, InterfaceNameLengthLimitIsFifteen) {
  const std::string max(15, 'c');
  EXPECT_EQ(parse_cli({"--can", max}).can_interfaces, (std::vector<std::string>{max}));
  EXPECT_THAT(usage_error({"--can", std::string(16, 'c')}), HasSubstr("--can"));
  EXPECT_THAT(usage_error({"--can", ""}), HasSubstr("--can"));
  EXPECT_THAT(usage_error({"--can="}), HasSubstr("--can"));
}

TEST(Cli, UnknownOptionIsRejectedAndNamed) {
  EXPECT_THAT(usage_error({"--can", "can0", "--bogus"}), HasSubstr("'--bogus'"));
  EXPECT_THAT(usage_error({"--can", "can0", "stray"}), HasSubstr("'stray'"));
  EXPECT_THAT(usage_error({"--can", "can0", "-x"}), HasSubstr("'-x'"));
}

TEST(Cli, ConfigOrDemoReplaceCan) {
  EXPECT_EQ(parse_cli({"--config", "gw.yaml"}).config_file, "gw.yaml");
  EXPECT_TRUE(parse_cli({"--demo"}).demo);
  EXPECT_THAT(usage_error({"--demo=yes"}), HasSubstr("--demo takes no value"));
  EXPECT_THAT(usage_error({"--config"}), HasSubstr("--config: missing value"));
}

TEST(Cli, MqttFlags) {
  const CliOptions o = parse_cli({"--demo", "--mqtt", "tcp://127.0.0.1:1883", "--mqtt-format=protobuf",
                                  "--gateway-id", "plant-7"});
  EXPECT_EQ(o.mqtt_uri, "tcp://127.0.0.1:1883");
  EXPECT_EQ(o.mqtt_format, "protobuf");
  EXPECT_EQ(o.gateway_id, "plant-7");
  EXPECT_THAT(usage_error({"--demo", "--mqtt", "localhost:1883"}), HasSubstr("not a broker URI"));
  // Schemes the publisher does not speak are refused here, not at start.
  EXPECT_THAT(usage_error({"--demo", "--mqtt", "ws://broker:8080"}), HasSubstr("not a broker URI"));
  EXPECT_EQ(parse_cli({"--demo", "--mqtt", "mqtts://broker"}).mqtt_uri, "mqtts://broker");
  EXPECT_THAT(usage_error({"--demo", "--mqtt-format", "xml"}), HasSubstr("not json or protobuf"));
  for (const char* bad : {"a/b", "a+", "#", "with space", ""}) {
    EXPECT_THAT(usage_error({"--demo", "--gateway-id", bad}), HasSubstr("--gateway-id")) << bad;
  }
}

// Contract "Sparkplug B": --sparkplug GROUP_ID; the group id is a topic
// level (facts A.2: no '+', '/', '#').
TEST(Cli, SparkplugFlagTakesTheGroupId) {
  EXPECT_EQ(parse_cli({"--demo", "--sparkplug", "plant1"}).sparkplug_group, "plant1");
  EXPECT_FALSE(parse_cli({"--demo"}).sparkplug_group) << "off unless given";
  for (const char* bad : {"a/b", "a+", "#", "with space", ""})
    EXPECT_THAT(usage_error({"--demo", "--sparkplug", bad}), HasSubstr("--sparkplug: '")) << bad;
}

TEST(Cli, HttpIsAddrPort) {
  EXPECT_EQ(parse_cli({"--demo", "--http", "0.0.0.0:8443"}).http, "0.0.0.0:8443");
  EXPECT_EQ(parse_cli({"--demo", "--http=[::1]:80"}).http, "[::1]:80");
  for (const char* bad : {"8080", "host:", ":80", "h:99999", "h:x", "::1:80"}) {
    EXPECT_THAT(usage_error({"--demo", "--http", bad}), HasSubstr("is not ADDR:PORT")) << bad;
  }
  std::string host;
  unsigned short port = 0;
  ASSERT_TRUE(split_host_port("[::1]:8080", host, port));
  EXPECT_EQ(host, "::1");
  EXPECT_EQ(port, 8080);
}

TEST(Cli, EdsRepeatsAsNodeEqualsFile) {
  const CliOptions o = parse_cli({"--can", "can0", "--eds", "5=drive.eds", "--eds=7=dir/io=x.dcf"});
  EXPECT_EQ(o.eds, (std::vector<EdsOption>{{5, "drive.eds"}, {7, "dir/io=x.dcf"}}));
  EXPECT_TRUE(parse_cli({"--can", "can0"}).eds.empty());
  EXPECT_EQ(parse_cli({"--can", "can0", "--eds", "1=a", "--eds", "127=b"}).eds.size(), 2U);
}

TEST(Cli, EdsNodeEqualsFileErrorsAreNamed) {
  EXPECT_THAT(usage_error({"--can", "can0", "--eds", "drive.eds"}), HasSubstr("not NODE=FILE"));
  EXPECT_THAT(usage_error({"--can", "can0", "--eds", "x=drive.eds"}), HasSubstr("'x' is not a number"));
  EXPECT_THAT(usage_error({"--can", "can0", "--eds", "=drive.eds"}), HasSubstr("is not a number"));
  EXPECT_THAT(usage_error({"--can", "can0", "--eds", "0=drive.eds"}), HasSubstr("out of range 1..127"));
  EXPECT_THAT(usage_error({"--can", "can0", "--eds", "128=drive.eds"}), HasSubstr("out of range 1..127"));
  EXPECT_THAT(usage_error({"--can", "can0", "--eds", "5="}), HasSubstr("no file given for node 5"));
  EXPECT_THAT(usage_error({"--can", "can0", "--eds", "5=a", "--eds", "5=b"}), HasSubstr("node 5 given twice"));
  EXPECT_THAT(usage_error({"--can", "can0", "--eds"}), HasSubstr("--eds: missing value"));
  for (const auto& msg : {usage_error({"--can", "can0", "--eds", "0x5=a"}), usage_error({"--eds", "5"})}) {
    EXPECT_THAT(msg, HasSubstr("--eds"));
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

// A control character given on the command line is not echoed raw.
TEST(Cli, UsageErrorsEscapeControlCharacters) {
  const std::string msg = usage_error({"--can", "can0", "--log-level", "x\x1b[2Jy"});
  EXPECT_THAT(msg, HasSubstr("'x\\x1B[2Jy'"));
  EXPECT_EQ(msg.find('\x1b'), std::string::npos);
  EXPECT_THAT(usage_error({"--gateway-id", "a\nb", "--demo"}), HasSubstr("'a\\x0Ab'"));
}

TEST(Cli, UsageErrorIsOneLine) {
  const std::vector<std::vector<std::string>> bad = {
      {}, {"--can"}, {"--can", "can0", "--node-id", "0"}, {"--bogus"}, {"--can", "can0", "--log-level", "x"}};
  for (const auto& args : bad) {
    const std::string msg = usage_error(args);
    EXPECT_FALSE(msg.empty());
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(Cli, LastValueWinsForSingleValuedFlags) {
  const CliOptions o = parse_cli({"--can", "can0", "--node-id", "5", "--node-id", "6", "--log-level", "debug",
                                  "--log-level", "error"});
  EXPECT_EQ(o.node_id, 6);
  EXPECT_EQ(o.log_level, LogLevel::Error);
}

TEST(Cli, UsageTextListsContractFlags) {
  const std::string u = usage_text();
  for (const char* flag : {"--config", "--can", "--node-id", "--eds", "--mqtt", "--mqtt-format", "--http",
                           "--gateway-id", "--sparkplug", "--demo", "--log-level"}) {
    EXPECT_THAT(u, HasSubstr(flag));
  }
  EXPECT_EQ(u.rfind("usage: canopen-gateway", 0), 0U);
}

// --help: each flag's paragraph ("  --flag ..." up to the next flag), by flag.
std::map<std::string, std::string> help_paragraphs() {
  std::map<std::string, std::string> out;
  std::istringstream in(help_text());
  std::string line, current;
  const std::regex flag_line(R"(^  (-h, )?(--[a-z-]+))");
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, flag_line)) current = m[2];
    else if (line.empty()) current.clear();
    if (!current.empty()) out[current] += line + "\n";
  }
  return out;
}

// Issue 13 item 2: --help describes every flag of the contract's command
// line with its default (the values the contract and merge() use).
TEST(Cli, HelpDescribesEveryContractFlagWithItsDefault) {
  const auto p = help_paragraphs();
  const std::map<std::string, std::string> defaults = {
      {"--config", "Default: none"},
      {"--can", "Default: the file's networks"},
      {"--node-id", "else 127"},
      {"--eds", "Default: the file's nodes"},
      {"--mqtt", "else MQTT off"},
      {"--mqtt-format", "else json"},
      {"--http", "127.0.0.1:8080"},
      {"--gateway-id", "else the host"},
      {"--demo", "Default: off"},
      {"--sparkplug", "else off"},
      {"--ascii", "else off"},
      {"--log-level", "else info"},
  };
  for (const auto& [flag, text] : defaults) {
    ASSERT_TRUE(p.contains(flag)) << flag << " is not described in:\n" << help_text();
    EXPECT_THAT(p.at(flag), HasSubstr(text)) << flag;
  }
  EXPECT_TRUE(p.contains("--help"));
  EXPECT_TRUE(p.contains("--version"));
  EXPECT_EQ(help_text().rfind(usage_text(), 0), 0U) << "starts with the synopsis";
  EXPECT_THAT(help_text(), HasSubstr("Exit status"));
}

// The help names only flags the parser takes.
TEST(Cli, EveryFlagInTheHelpIsAccepted) {
  const std::set<std::string> valueless = {"--demo", "--help", "--version"};
  const std::regex flag(R"(--[a-z][a-z-]*)");
  const std::string text = help_text();
  std::set<std::string> seen;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), flag); it != std::sregex_iterator(); ++it)
    seen.insert(it->str());
  EXPECT_GE(seen.size(), 12U);
  const std::map<std::string, std::string> sample = {
      {"--config", "gw.yaml"}, {"--can", "can0"},         {"--node-id", "5"},          {"--eds", "5=d.eds"},
      {"--mqtt", "tcp://b:1883"}, {"--mqtt-format", "json"}, {"--http", "127.0.0.1:80"}, {"--gateway-id", "gw"},
      {"--log-level", "debug"}, {"--sparkplug", "plant1"}, {"--ascii", "127.0.0.1:60000"}};
  for (const auto& f : seen) {
    std::vector<std::string> args = {"--demo", f};
    if (!valueless.contains(f)) {
      ASSERT_TRUE(sample.contains(f)) << f << " is in the help but not known to this test";
      args.push_back(sample.at(f));
    }
    EXPECT_NO_THROW(parse_cli(args)) << f;
  }
}

// Contract "CiA 309-3 ASCII interface": --ascii ADDR with ADDR
// 127.0.0.1:PORT or unix:/path; anything else is refused by name.
TEST(Cli, AsciiTakesAnAddressOrAUnixPath) {
  EXPECT_EQ(parse_cli({"--demo", "--ascii", "127.0.0.1:60000"}).ascii, "127.0.0.1:60000");
  EXPECT_EQ(parse_cli({"--demo", "--ascii=unix:/run/gw/ascii.sock"}).ascii, "unix:/run/gw/ascii.sock");
  EXPECT_FALSE(parse_cli({"--demo"}).ascii.has_value());
  for (const char* bad : {"60000", "unix:", "tcp-60000", "host:"})
    EXPECT_THAT(usage_error({"--demo", "--ascii", bad}), HasSubstr("--ascii: '")) << bad;
}

TEST(Cli, HelpFitsEightyColumns) {
  std::istringstream in(help_text());
  std::string line;
  while (std::getline(in, line)) EXPECT_LE(line.size(), 80U) << line;
}

TEST(Cli, AFlagIsNotTakenAsTheValueOfTheOneBefore) {
  EXPECT_THAT(usage_error({"--can", "--help"}), HasSubstr("--can: missing value"));
  EXPECT_THAT(usage_error({"--node-id", "--can", "vcan0"}), HasSubstr("--node-id: missing value"));
}

TEST(Cli, FlagsWithoutValueRefuseOne) {
  EXPECT_THAT(usage_error({"--help=x"}), HasSubstr("--help takes no value"));
  EXPECT_THAT(usage_error({"--version=1"}), HasSubstr("--version takes no value"));
}

TEST(Cli, InterfaceNamesFollowLinuxRules) {
  for (const char* bad : {"a/b", "can 0", "can:0", ".", ".."}) {
    EXPECT_THAT(usage_error({"--can", bad}), HasSubstr("is not an interface name")) << bad;
  }
  EXPECT_EQ(parse_cli({"--can", "can0.1"}).can_interfaces.front(), "can0.1");
}

}  // namespace
}  // namespace gateway
