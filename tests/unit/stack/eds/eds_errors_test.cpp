// What the reader rejects (EdsError naming file:line and a reason) and what
// it accepts with a warning.
#include <gtest/gtest.h>

#include "eds_test_util.hpp"

namespace canopen::eds::test {
namespace {

// Expects an EdsError on the first line containing `needle` (after the first
// line containing `after`), whose reason contains `reason_part`.
void expect_error_at(const std::string& text, std::string_view needle, std::string_view reason_part,
                     std::string_view after = {}, std::optional<std::uint8_t> node_id = 5) {
  const auto e = parse_error(text, node_id);
  const auto line = line_of(text, needle, after);
  ASSERT_NE(line, 0u) << "test bug: no line with " << needle;
  EXPECT_EQ(e.line(), line) << e.what();
  EXPECT_NE(e.reason().find(reason_part), std::string::npos) << e.what();
  EXPECT_EQ(std::string(e.what()), "test.eds:" + std::to_string(line) + ": " + e.reason());
}

std::string var(std::string_view index, std::string_view extra, std::string_view type = "0x0006",
                std::string_view access = "rw") {
  return "[" + std::string(index) + "]\nParameterName=x\nObjectType=0x7\nDataType=" + std::string(type) +
         "\nAccessType=" + std::string(access) + "\n" + std::string(extra);
}

// ---- lines -------------------------------------------------------------------------

// Inside a section such a line is skipped (eds_quirks_test.cpp); before
// any section there is nothing it could belong to.
TEST(EdsReject, LineWithoutEqualsOutsideAnySection) {
  expect_error_at("DefaultValue 5\n[FileInfo]\n", "DefaultValue 5", "no '='");
}

TEST(EdsReject, LineWithoutKey) { expect_error_at(file_with(var("2000", "=5\n"), {0x2000}), "=5", "no key"); }

TEST(EdsReject, KeyOutsideAnySection) {
  expect_error_at("FileName=x.eds\n[FileInfo]\n", "FileName", "outside any section");
}

TEST(EdsReject, UnterminatedSectionHeader) {
  expect_error_at(file_with("[2000\nParameterName=x\n"), "[2000", "no closing ']'");
}

TEST(EdsReject, TextAfterSectionHeader) {
  expect_error_at(file_with("[2000] x\n"), "[2000] x", "text after the section header");
  expect_error_at(file_with("[2000]]\n"), "[2000]]", "text after the section header");
}

TEST(EdsReject, EmptySectionName) { expect_error_at(file_with("[ ]\n"), "[ ]", "empty section name"); }

TEST(EdsReject, DuplicateKeyWithDifferentValue) {
  const auto text = file_with(var("2000", "DefaultValue=5\nPDOMapping=0\ndefaultvalue=6\n"), {0x2000});
  const auto e = parse_error(text);
  EXPECT_EQ(e.line(), line_of(text, "defaultvalue=6"));
  EXPECT_NE(e.reason().find("different value"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("'5' at line " + std::to_string(line_of(text, "DefaultValue=5"))), std::string::npos)
      << e.what();
}

TEST(EdsReject, DuplicateKeyInARepeatedSection) {
  const auto text =
      file_with(var("2000", "DefaultValue=5\n") + "[OptionalObjects]\n" + "[2000]\nDefaultValue=6\n", {0x2000});
  expect_error_at(text, "DefaultValue=6", "different value");
}

// ---- values ------------------------------------------------------------------------

TEST(EdsReject, PdoMappingNotABoolean) {
  expect_error_at(file_with(var("2000", "PDOMapping=2\n"), {0x2000}), "PDOMapping=2", "expected 0 or 1");
}

// ---- structure ---------------------------------------------------------------------

TEST(EdsReject, SubIndexAboveFF) {
  const auto body =
      "[2000]\nParameterName=r\nObjectType=0x9\n"
      "[2000sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n";
  // [2000subFF] is skipped with a warning (eds_quirks_test.cpp).
  expect_error_at(
      file_with(std::string(body) + "[2000sub100]\nParameterName=a\nDataType=0x0005\nAccessType=rw\n", {0x2000}),
      "[2000sub100]", "sub-index above 0xFF");
}

TEST(EdsReject, MalformedSubSectionName) {
  expect_error_at(file_with("[2000subX]\nParameterName=a\n"), "[2000subX]", "malformed sub-object section name");
}

TEST(EdsReject, IndexZero) {
  expect_error_at(file_with("[0000]\nParameterName=a\n"), "[0000]", "index 0 is not an object");
  expect_error_at(file_with("[0sub1]\nParameterName=a\n"), "[0sub1]", "index 0 is not an object");
  expect_error_at(file_with("[OptionalObjects]\nSupportedObjects=1\n1=0x0000\n"), "1=0x0000",
                  "index 0 is not an object");
}

TEST(EdsReject, IndexAboveFFFF) {
  expect_error_at(file_with("[10000]\nParameterName=a\n"), "[10000]", "index above 0xFFFF");
}

TEST(EdsReject, SameObjectSpelledTwice) {
  const auto text = file_with(var("100", "") + var("0100", ""));
  expect_error_at(text, "[0100]", "describes the same thing as [100]");
}

TEST(EdsReject, CompactSubObjTogetherWithSubSections) {
  const auto text = file_with(
      "[2000]\nParameterName=r\nObjectType=0x8\nDataType=0x0005\nAccessType=rw\nCompactSubObj=2\n"
      "[2000sub1]\nParameterName=n\nDataType=0x0005\nAccessType=rw\n",
      {0x2000});
  expect_error_at(text, "[2000sub1]", "has CompactSubObj and also sub-object section");
}

TEST(EdsReject, DummyUsageNotABoolean) {
  expect_error_at(file_with("[DummyUsage]\nDummy0005=2\n"), "Dummy0005=2", "expected 0 or 1");
}

TEST(EdsReject, BadDeviceInfoNumber) {
  expect_error_at("[DeviceInfo]\nVendorNumber=0x1FFFFFFFF\n", "VendorNumber", "VendorNumber");
  expect_error_at("[DeviceInfo]\nGranularity=65\n", "Granularity", "above 64");
}

TEST(EdsReject, FileOnDiskWithDuplicateKey) {
  const auto path = test_data("duplicate-key.eds");
  const auto text = read_text(path);
  try {
    (void)load_device_description(path, 5);
    FAIL() << "expected an EdsError";
  } catch (const EdsError& e) {
    EXPECT_EQ(e.line(), line_of(text, "DataType=0x0007", "[2000]"));
    EXPECT_EQ(e.file(), path.string());
    EXPECT_NE(e.reason().find("key 'DataType' in [2000] repeated with a different value"), std::string::npos)
        << e.what();
  }
}

// ---- accepted with a warning ----------------------------------------------------------

TEST(EdsWarn, UnknownSectionsAndKeys) {
  const auto text = file_with(var("2000", "Vendor_Specific=1\n") + "[Tools]\nItems=0\n", {0x2000});
  const auto d = parse(text);
  ASSERT_EQ(d.warnings.size(), 2u) << d.warnings.front();
  EXPECT_EQ(d.warnings[0],
            "test.eds:" + std::to_string(line_of(text, "[Tools]")) + ": unknown section [Tools] ignored");
  EXPECT_EQ(d.warnings[1], "test.eds:" + std::to_string(line_of(text, "Vendor_Specific")) +
                               ": unknown key 'Vendor_Specific' in [2000] ignored");
}

TEST(EdsWarn, DuplicateIdenticalKey) {
  const auto text = file_with(var("2000", "DefaultValue=5\nDefaultValue=5\n"), {0x2000});
  const auto d = parse(text);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_TRUE(has_warning(d, "key 'DefaultValue' in [2000] repeated with the same value (first at line " +
                                 std::to_string(line_of(text, "DefaultValue=5")) + ")"));
  EXPECT_EQ(u(d.od.find(0x2000, 0)->value), 5u);
}

TEST(EdsWarn, CommentAfterSectionHeader) {
  const auto text = file_with("[2000] ; speed\nParameterName=x\nDataType=0x0005\nAccessType=rw\n", {0x2000});
  const auto d = parse(text);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_EQ(d.warnings[0], "test.eds:" + std::to_string(line_of(text, "[2000]")) +
                               ": comment after the section header [2000] ignored");
  EXPECT_NE(d.od.find(0x2000, 0), nullptr);
}

TEST(EdsWarn, LimitsOnAStringAreIgnored) {
  const auto text = file_with(var("2000", "LowLimit=zz\nHighLimit=\nDefaultValue=0102\n", "0x000A"), {0x2000});
  const auto d = parse(text);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_EQ(d.warnings[0], "test.eds:" + std::to_string(line_of(text, "LowLimit=zz")) +
                               ": LowLimit ignored: OCTET_STRING has no limits");
  EXPECT_FALSE(d.od.find(0x2000, 0)->low.has_value());
}

TEST(EdsWarn, RepeatedSectionHeaderMerges) {
  const auto text = file_with(var("2000", "") + "[2000]\nDefaultValue=9\n", {0x2000});
  const auto d = parse(text);
  EXPECT_TRUE(has_warning(d, "section [2000] repeated"));
  EXPECT_EQ(u(d.od.find(0x2000, 0)->value), 9u);
}

TEST(EdsWarn, UnlistedObjectIsLoaded) {
  const auto text = file_with(var("2000", "DefaultValue=1\n"));
  const auto d = parse(text);
  EXPECT_NE(d.od.find(0x2000, 0), nullptr);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_EQ(d.warnings[0], "test.eds:" + std::to_string(line_of(text, "[2000]")) +
                               ": object section [2000] is not in any object list; loaded anyway");
}

TEST(EdsWarn, ObjectListedTwice) {
  const auto d = parse(file_with(var("2000", ""), {0x2000, 0x2000}));
  EXPECT_TRUE(has_warning(d, "object 0x2000 listed again"));
  EXPECT_EQ(d.optional_objects, (std::vector<std::uint16_t>{0x2000}));
}

TEST(EdsWarn, DefTypeAndDefStructAreSkipped) {
  const auto text = file_with(
      "[0007]\nParameterName=UNSIGNED32\nObjectType=0x5\nDataType=0x0007\nAccessType=ro\nDefaultValue=32\n"
      "[0021]\nParameterName=PDO_MAPPING\nObjectType=0x6\nSubNumber=1\n"
      "[0021sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=64\n");
  const auto d = parse(text);
  EXPECT_EQ(d.od.find(0x0007), nullptr);
  EXPECT_EQ(d.od.find(0x0021), nullptr);
  ASSERT_EQ(d.warnings.size(), 2u) << d.warnings.front();
  EXPECT_TRUE(has_warning(d, "test.eds:" + std::to_string(line_of(text, "ObjectType=0x5")) +
                                 ": ObjectType 0x5 (NULL/DEFTYPE/DEFSTRUCT) of [0007] is not used; object skipped"));
  EXPECT_TRUE(has_warning(d, "ObjectType 0x6"));
}

TEST(EdsWarn, HexBeyondSignedRangeIsTwosComplement) {
  const auto text = file_with(var("2000", "LowLimit=0x8000\nHighLimit=0x7FFF\nDefaultValue=0xFFFF\n", "0x0003") +
                                  var("2001", "DefaultValue=0X80000000\n", "0x0004"),
                              {0x2000, 0x2001});
  const auto d = parse(text);
  const auto* e = d.od.find(0x2000, 0);
  EXPECT_EQ(i(*e->low), -32768);
  EXPECT_EQ(i(*e->high), 32767);
  EXPECT_EQ(i(e->value), -1);
  EXPECT_EQ(i(d.od.find(0x2001, 0)->value), -2147483648LL);
  EXPECT_EQ(d.warnings.size(), 3u);
  EXPECT_TRUE(has_warning(d, "test.eds:" + std::to_string(line_of(text, "DefaultValue=0xFFFF")) +
                                 ": DefaultValue '0xFFFF' read as two's complement -1 (INTEGER16)"));
}

TEST(EdsWarn, MissingSub0IsAssumed) {
  const auto text = file_with(
      "[2000]\nParameterName=r\nObjectType=0x8\nSubNumber=2\n"
      "[2000sub1]\nParameterName=a\nDataType=0x0005\nAccessType=rw\n"
      "[2000sub3]\nParameterName=c\nDataType=0x0005\nAccessType=rw\n",
      {0x2000});
  const auto d = parse(text);
  EXPECT_TRUE(has_warning(d, "[2000] has no sub-index 0; assumed UNSIGNED8 ro = 3"));
  const auto* sub0 = d.od.find(0x2000, 0);
  ASSERT_NE(sub0, nullptr);
  EXPECT_EQ(sub0->type, DataType::Unsigned8);
  EXPECT_EQ(sub0->access, od::Access::ReadOnly);
  EXPECT_EQ(u(sub0->value), 3u);
}

TEST(EdsWarn, MissingParameterNameAndMetadata) {
  const auto text =
      "[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n"
      "[1000]\nDataType=0x0007\nAccessType=ro\n";
  const auto d = parse(text);
  EXPECT_TRUE(has_warning(d, "test.eds: no [FileInfo] section"));
  EXPECT_TRUE(has_warning(d, "test.eds: no [DeviceInfo] section"));
  EXPECT_TRUE(has_warning(d, "test.eds:4: [1000] has no ParameterName"));
}

TEST(EdsWarn, CompactOddities) {
  const auto text = file_with(
      "[2000]\nParameterName=a\nObjectType=0x8\nDataType=0x0005\nAccessType=rw\nCompactSubObj=2\nSubNumber=5\n"
      "[2001]\nParameterName=b\nDataType=0x0005\nAccessType=rw\nCompactSubObj=2\n"
      "[2002]\nParameterName=c\nObjectType=0x8\nSubNumber=1\n"
      "[2002sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\n"
      "[2002Name]\nNrOfEntries=1\n1=x\n",
      {0x2000, 0x2001, 0x2002});
  const auto d = parse(text);
  EXPECT_TRUE(has_warning(d, "SubNumber=5 ignored: CompactSubObj=2 gives 3 sub-objects"));
  EXPECT_TRUE(has_warning(d, "CompactSubObj ignored: [2001] is not an ARRAY or RECORD"));
  EXPECT_TRUE(has_warning(d, "section [2002Name] ignored: no CompactSubObj"));
  EXPECT_EQ(d.od.find(0x2000)->subs.size(), 3u);
  EXPECT_EQ(d.od.find(0x2001)->subs.size(), 1u);
}

TEST(EdsWarn, NoSupportedObjectsAndCommentCount) {
  const auto text = file_with(var("2000", "") + "[OptionalObjects]\n1=0x2000\n[Comments]\nLines=3\nLine1=only one\n");
  const auto d = parse(text);
  EXPECT_TRUE(has_warning(d, "[OptionalObjects] has no SupportedObjects; using its 1 entries"));
  EXPECT_TRUE(has_warning(d, "Lines=3 but 1 comment lines follow"));
  EXPECT_EQ(d.optional_objects, (std::vector<std::uint16_t>{0x2000}));
}

TEST(EdsWarn, VendorQuirksFileLoads) {
  const auto path = test_data("vendor-quirks.eds");
  const auto d = load_device_description(path, 0x22);
  EXPECT_EQ(d.warnings.size(), 8u);
  for (const auto& w : d.warnings) EXPECT_EQ(w.rfind(path.string() + ":", 0), 0u) << w;
  EXPECT_EQ(u(d.od.find(0x1800, 1)->value), 0x1A2u);
  EXPECT_EQ(u(d.od.find(0x1017, 0)->value), 0x1Fu);
  EXPECT_EQ(d.od.find(0x2100, 0)->value, Value::of_string("vendor text"));
  EXPECT_EQ(i(d.od.find(0x2101, 0)->value), -2);
  EXPECT_NE(d.od.find(0x2102, 0), nullptr);  // unlisted, loaded anyway
  EXPECT_EQ(d.od.find(0x0002), nullptr);     // DEFTYPE skipped
}

}  // namespace
}  // namespace canopen::eds::test
