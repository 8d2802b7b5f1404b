// canopen-eds (gateway/edstool): what it prints is the contract's format
// (../shared/api-contract.md "Command line") and what it accepts is exactly
// what the gateway's reader accepts; `show` prints the shape of GET .../od.
#include "edstool/eds_report.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <boost/json/parse.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace gateway::edstool {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::StartsWith;

const std::filesystem::path kSource = CANOPEN_SOURCE_DIR;
const std::string kQuirks = (kSource / "tests/support/eds/quirks").string();
const std::string kDrive = (kSource / "deploy/eds/cia402-drive.eds").string();

TEST(EdsCheck, CleanFileIsOneOkLine) {
  const auto r = check_file(kDrive, 5);
  EXPECT_TRUE(r.accepted);
  EXPECT_THAT(r.lines, ElementsAre(kDrive + ": ok"));
}

TEST(EdsCheck, WarningsFollowTheOkLineAsFileLineWarningReason) {
  const auto file = kQuirks + "/counts-disagree.eds";
  const auto r = check_file(file, 5);
  EXPECT_TRUE(r.accepted);
  ASSERT_EQ(r.lines.size(), 3u);
  EXPECT_EQ(r.lines[0], file + ": ok, 2 warnings");
  EXPECT_EQ(r.lines[1], file + ":26: warning: SubNumber=7 but [1800] has 5 sub-object sections; those are used");
  EXPECT_THAT(r.lines[2], StartsWith(file + ":59: warning: NrOfEntries=3"));
}

TEST(EdsCheck, WholeFileWarningHasNoLineNumber) {
  const auto file = kQuirks + "/no-fileinfo.eds";
  const auto r = check_file(file);
  EXPECT_THAT(r.lines, ElementsAre(file + ": ok, 2 warnings", file + ": warning: no [FileInfo] section",
                                   file + ": warning: no [DeviceInfo] section"));
}

TEST(EdsCheck, RefusedFileIsOneErrorLine) {
  const auto file = kQuirks + "/duplicates-conflict.eds";
  const auto r = check_file(file, 5);
  EXPECT_FALSE(r.accepted);
  ASSERT_EQ(r.lines.size(), 1u);
  EXPECT_THAT(r.lines[0], StartsWith(file + ":28: error: key 'ParameterName' in [1009] repeated with a different value"));
  const auto missing = check_file("/nonexistent.eds");
  EXPECT_THAT(missing.lines, ElementsAre("/nonexistent.eds: error: cannot open the file"));
}

// Issue 13: a control character in the file is quoted as \xNN, never raw.
TEST(EdsCheck, ControlCharactersInTheFileAreEscaped) {
  const auto file = (std::filesystem::path(::testing::TempDir()) / "control-chars.eds").string();
  {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "w"), &std::fclose);
    ASSERT_TRUE(f);
    std::fputs("[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\n"
               "AccessType=r\x1b[2J\n",
               f.get());
  }
  const auto r = check_file(file, 5);
  EXPECT_FALSE(r.accepted);
  ASSERT_EQ(r.lines.size(), 1u);
  EXPECT_THAT(r.lines[0], StartsWith(file + ":6: error: key 'AccessType' in [1000] repeated with a different value: 'ro' at line 5, 'r\\x1B[2J' here"));
  EXPECT_EQ(r.lines[0].find('\x1b'), std::string::npos) << r.lines[0];
  std::filesystem::remove(file);
}

// Without --node-id a file with $NODEID is still checked (node-ID 1, or a
// DCF's own NodeID); with one, the values it gives are the node's.
TEST(EdsCheck, NodeIdExpressionsAreCheckedWithoutANodeId) {
  EXPECT_TRUE(check_file(kQuirks + "/nodeid-ff.dcf").accepted);
  EXPECT_TRUE(check_file(kDrive).accepted);
}

TEST(EdsShow, DictionaryJsonHasTheShapeOfTheOdRoute) {
  const auto d = canopen::eds::load_device_description(kQuirks + "/limits.eds", 5);
  const auto j = dictionary_json(d);
  EXPECT_EQ(j.at("vendorName").as_string(), "Quirk Test");
  EXPECT_FALSE(j.at("dcf").as_bool());
  const auto& objects = j.at("objects").as_array();
  ASSERT_FALSE(objects.empty());
  const auto& o = objects.back().as_object();  // 2004h: INTEGER32 with hex limits
  EXPECT_EQ(o.at("index").to_number<std::int64_t>(), 0x2004);
  EXPECT_EQ(o.at("indexHex").as_string(), "2004");
  EXPECT_EQ(o.at("objectCode").as_string(), "VAR");
  const auto& sub = o.at("subs").as_array().at(0).as_object();
  EXPECT_EQ(sub.at("type").as_string(), "i32");
  EXPECT_EQ(sub.at("access").as_string(), "rw");
  EXPECT_EQ(sub.at("low").to_number<std::int64_t>(), -2147483648LL);
  EXPECT_EQ(sub.at("high").to_number<std::int64_t>(), 2147483647);
  EXPECT_EQ(sub.at("default").to_number<std::int64_t>(), 0);
}

// GET .../od and `canopen-eds show` give each sub-entry its unit and factor
// from the file (null where it gives none, so clients show the raw value).
TEST(EdsShow, SubEntriesCarryUnitAndFactorFromTheFile) {
  const auto d = canopen::eds::parse_device_description(
      "[FileInfo]\n[DeviceInfo]\n[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n"
      "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0\n"
      "[OptionalObjects]\nSupportedObjects=1\n1=0x2000\n"
      "[2000]\nParameterName=Analog input\nObjectType=0x7\nDataType=0x0003\nAccessType=ro\nUnit=mV\nFactor=0.1\n",
      "units.eds");
  const auto objects = objects_json(d.od, &d);
  ASSERT_EQ(objects.size(), 2u);
  const auto& plain = objects.at(0).at("subs").as_array().at(0).as_object();
  EXPECT_TRUE(plain.at("unit").is_null());
  EXPECT_TRUE(plain.at("factor").is_null());
  const auto& analog = objects.at(1).at("subs").as_array().at(0).as_object();
  EXPECT_EQ(analog.at("unit").as_string(), "mV");
  EXPECT_DOUBLE_EQ(analog.at("factor").as_double(), 0.1);
  // A dictionary without a file (the gateway's own node): no units.
  EXPECT_TRUE(objects_json(d.od).at(1).at("subs").as_array().at(0).at("unit").is_null());
  // The example drive: the velocity the demo TPDO carries is in rpm.
  const auto drive = dictionary_json(canopen::eds::load_device_description(kDrive, 5));
  bool found = false;
  for (const auto& o : drive.at("objects").as_array()) {
    if (o.at("index").to_number<std::int64_t>() != 0x606C) continue;
    found = true;
    EXPECT_EQ(o.at("subs").as_array().at(0).at("unit").as_string(), "rpm");
  }
  EXPECT_TRUE(found);
}

// The installed command: exit codes and output as the contract says.
struct Run {
  int status;
  std::string out;
};
Run run(const std::string& args) {
  const std::string cmd = std::string(CANOPEN_EDS_BIN) + " " + args + " 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
  std::string out;
  std::array<char, 4096> buf{};
  while (const auto n = fread(buf.data(), 1, buf.size(), p.get())) out.append(buf.data(), n);
  const int status = pclose(p.release());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(EdsCommand, CheckExitsZeroOnlyWhenEveryFileIsAccepted) {
  const auto ok = run("check " + kDrive + " " + kQuirks + "/limits.eds");
  EXPECT_EQ(ok.status, 0) << ok.out;
  EXPECT_THAT(ok.out, HasSubstr(kDrive + ": ok\n"));
  EXPECT_THAT(ok.out, HasSubstr(kQuirks + "/limits.eds: ok, 7 warnings\n"));
  const auto bad = run("check " + kDrive + " " + kQuirks + "/duplicates-conflict.eds");
  EXPECT_EQ(bad.status, 1) << bad.out;
  EXPECT_THAT(bad.out, HasSubstr(kQuirks + "/duplicates-conflict.eds:28: error: "));
}

TEST(EdsCommand, ShowPrintsJsonAndUsageErrorsExitTwo) {
  const auto show = run("show " + kDrive + " --node-id 5");
  ASSERT_EQ(show.status, 0) << show.out;
  const auto j = boost::json::parse(show.out).as_object();
  EXPECT_EQ(j.at("objects").as_array().size(), canopen::eds::load_device_description(kDrive, 5).od.objects().size());
  EXPECT_EQ(j.at("productName").as_string(), canopen::eds::load_device_description(kDrive, 5).device.product_name);
  EXPECT_EQ(run("show").status, 2);
  EXPECT_EQ(run("check --node-id 200 " + kDrive).status, 2);
  EXPECT_EQ(run("frobnicate x").status, 2);
  const auto help = run("--help");
  EXPECT_EQ(help.status, 0);
  EXPECT_THAT(help.out, HasSubstr("usage: canopen-eds check"));
}

}  // namespace
}  // namespace gateway::edstool
