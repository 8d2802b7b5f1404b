// The reader on inline text: lexical rules, values, $NODEID, DCF values,
// CompactSubObj, object links, dummy usage.
#include <gtest/gtest.h>

#include "eds_test_util.hpp"

namespace canopen::eds::test {
namespace {

using od::Access;
using od::ObjectCode;

constexpr std::string_view kVar2000 =
    "[2000]\n"
    "ParameterName=Value\n"
    "ObjectType=0x7\n"
    "DataType=0x0006\n"
    "AccessType=rw\n"
    "DefaultValue=0x1234\n"
    "PDOMapping=1\n";

TEST(EdsParse, MinimalFileHasNoWarnings) {
  const auto d = parse(file_with(kVar2000, {0x2000}));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  const auto* e = d.od.find(0x2000, 0);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->name, "Value");
  EXPECT_EQ(e->type, DataType::Unsigned16);
  EXPECT_EQ(e->access, Access::ReadWrite);
  EXPECT_TRUE(e->pdo_mappable);
  EXPECT_EQ(e->value, Value::of_unsigned(DataType::Unsigned16, 0x1234));
  EXPECT_EQ(e->default_value, e->value);
  EXPECT_EQ(d.od.find(0x2000)->code, ObjectCode::Var);
  EXPECT_EQ(d.optional_objects, (std::vector<std::uint16_t>{0x2000}));
}

TEST(EdsParse, BomCrlfCommentsAndTrailingWhitespace) {
  const std::string text =
      "\xEF\xBB\xBF; written by a vendor tool\r\n"
      "[FileInfo]  \r\n"
      "FileName=bom.eds \t\r\n"
      "\r\n"
      "  ; indented comment\r\n"
      "[DeviceInfo]\r\n"
      "VendorName=Vendor GmbH   \r\n"
      "[MandatoryObjects]\r\n"
      "SupportedObjects=1\r\n"
      "1=0x1000\r\n"
      "[1000]\r\n"
      "ParameterName=Device type\r\n"
      "ObjectType=0x7\r\n"
      "DataType=0x0007\r\n"
      "AccessType=ro\r\n"
      "DefaultValue=0x00000191  \r\n"
      "PDOMapping=0";  // no final newline
  const auto d = parse(text);
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_EQ(d.file.file_name, "bom.eds");
  EXPECT_EQ(d.device.vendor_name, "Vendor GmbH");
  EXPECT_EQ(u(d.od.find(0x1000, 0)->value), 0x191u);
}

TEST(EdsParse, BomCrlfFileOnDisk) {
  const auto d = load_device_description(test_data("bom-crlf.eds"));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_EQ(d.device.product_name, "CRLF device");
  EXPECT_EQ(d.od.find(0x2000, 0)->value, Value::of_string("text with trailing spaces cut"));
}

TEST(EdsParse, SectionAndKeyNamesAreCaseInsensitive) {
  const std::string text =
      "[fileinfo]\n"
      "filename=x.eds\n"
      "[DEVICEINFO]\n"
      "vendorNUMBER=0X1a\n"
      "[mandatoryobjects]\n"
      "supportedobjects=1\n"
      "1=0x1000\n"
      "[OptionalObjects]\n"
      "SupportedObjects=1\n"
      "1=0x100a\n"
      "[1000]\n"
      "parametername=Device type\n"
      "OBJECTTYPE=0X7\n"
      "DataType=0x0007\n"
      "accesstype=RO\n"
      "defaultvalue=0xabcd\n"
      "[100a]\n"
      "ParameterName=SW version\n"
      "DataType=0x0009\n"
      "AccessType=Const\n"
      "DefaultValue=1.0\n";
  const auto d = parse(text);
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_EQ(d.device.vendor_number, 0x1Au);
  EXPECT_EQ(u(d.od.find(0x1000, 0)->value), 0xABCDu);
  EXPECT_EQ(d.od.find(0x1000, 0)->access, Access::ReadOnly);
  ASSERT_NE(d.od.find(0x100A, 0), nullptr);
  EXPECT_EQ(d.od.find(0x100A, 0)->access, Access::Const);
  EXPECT_EQ(d.od.find(0x100A, 0)->value, Value::of_string("1.0"));
}

TEST(EdsParse, NumbersInHexDecimalAndOctal) {
  const auto d =
      parse(file_with("[2000]\nParameterName=a\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x10\n"
                      "[2001]\nParameterName=b\nDataType=0x0007\nAccessType=rw\nDefaultValue=10\n"
                      "[2002]\nParameterName=c\nDataType=0x0007\nAccessType=rw\nDefaultValue=010\n"
                      "[2003]\nParameterName=d\nDataType=0x0004\nAccessType=rw\nDefaultValue=-10\n"
                      "[2004]\nParameterName=e\nDataType=0x0007\nAccessType=rw\nDefaultValue=0\n"
                      "[2005]\nParameterName=f\nDataType=0x0007\nAccessType=rw\nDefaultValue=0XFf\n",
                      {0x2000, 0x2001, 0x2002, 0x2003, 0x2004, 0x2005}));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_EQ(u(d.od.find(0x2000, 0)->value), 16u);
  EXPECT_EQ(u(d.od.find(0x2001, 0)->value), 10u);
  EXPECT_EQ(u(d.od.find(0x2002, 0)->value), 8u);
  EXPECT_EQ(i(d.od.find(0x2003, 0)->value), -10);
  EXPECT_EQ(u(d.od.find(0x2004, 0)->value), 0u);
  EXPECT_EQ(u(d.od.find(0x2005, 0)->value), 255u);
}

TEST(EdsParse, SpacesAroundEquals) {
  const auto d =
      parse(file_with("[2000]\nParameterName = Spaced\nDataType = 0x0005\nAccessType = rw\n"
                      "DefaultValue =  7 \n",
                      {0x2000}));
  EXPECT_EQ(d.od.find(0x2000, 0)->name, "Spaced");
  EXPECT_EQ(u(d.od.find(0x2000, 0)->value), 7u);
}

TEST(EdsParse, MissingOptionalKeys) {
  // No ObjectType (VAR), no DefaultValue, no PDOMapping, no limits.
  const auto d = parse(file_with("[2000]\nParameterName=Bare\nDataType=0x0003\nAccessType=ro\n", {0x2000}));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  const auto* e = d.od.find(0x2000, 0);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(d.od.find(0x2000)->code, ObjectCode::Var);
  EXPECT_FALSE(e->pdo_mappable);
  EXPECT_FALSE(e->default_value.has_value());
  EXPECT_FALSE(e->low.has_value());
  EXPECT_FALSE(e->high.has_value());
  EXPECT_EQ(e->value, Value::of_signed(DataType::Integer16, 0));
}

TEST(EdsParse, EmptyValuesForOptionalKeysAreAbsent) {
  const auto d =
      parse(file_with("[2000]\nParameterName=Empty\nObjectType=\nDataType=0x0006\nAccessType=rw\nDefaultValue=\n"
                      "LowLimit=\nHighLimit=\nPDOMapping=\nObjFlags=\n"
                      "[2001]\nParameterName=Empty string\nDataType=0x0009\nAccessType=rw\nDefaultValue=\n",
                      {0x2000, 0x2001}));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  const auto* e = d.od.find(0x2000, 0);
  EXPECT_FALSE(e->default_value.has_value());
  EXPECT_FALSE(e->low.has_value());
  EXPECT_FALSE(e->pdo_mappable);
  EXPECT_EQ(e->value, Value::of_unsigned(DataType::Unsigned16, 0));
  // For a string an empty DefaultValue is the empty string.
  const auto* s = d.od.find(0x2001, 0);
  EXPECT_EQ(s->default_value, Value::of_string(""));
}

TEST(EdsParse, AllAccessTypes) {
  const std::vector<std::pair<std::string, Access>> cases = {
      {"ro", Access::ReadOnly},       {"wo", Access::WriteOnly},       {"rw", Access::ReadWrite},
      {"RWR", Access::ReadWriteRead}, {"rwW", Access::ReadWriteWrite}, {"const", Access::Const}};
  for (const auto& [text, access] : cases) {
    const auto d = parse(file_with("[2000]\nParameterName=x\nDataType=0x0005\nAccessType=" + text + "\n", {0x2000}));
    EXPECT_EQ(d.od.find(0x2000, 0)->access, access) << text;
  }
}

TEST(EdsParse, DataTypesOfEveryKind) {
  const auto d =
      parse(file_with("[2000]\nParameterName=b\nDataType=0x0001\nAccessType=rw\nDefaultValue=1\n"
                      "[2001]\nParameterName=r64\nDataType=0x0011\nAccessType=rw\nDefaultValue=-2.5\n"
                      "[2002]\nParameterName=u64\nDataType=0x001B\nAccessType=rw\nDefaultValue=0xFFFFFFFFFFFFFFFF\n"
                      "[2003]\nParameterName=i24\nDataType=0x0010\nAccessType=rw\nDefaultValue=-8388608\n"
                      "[2004]\nParameterName=os\nDataType=0x000A\nAccessType=rw\nDefaultValue=0102ff\n",
                      {0x2000, 0x2001, 0x2002, 0x2003, 0x2004}));
  EXPECT_EQ(d.od.find(0x2000, 0)->value, Value::of_bool(true));
  EXPECT_EQ(d.od.find(0x2001, 0)->value, Value::of_real64(-2.5));
  EXPECT_EQ(u(d.od.find(0x2002, 0)->value), 0xFFFFFFFFFFFFFFFFu);
  EXPECT_EQ(d.od.find(0x2003, 0)->value, Value::of_signed(DataType::Integer24, -8388608));
  EXPECT_EQ(d.od.find(0x2004, 0)->value, Value::of_bytes(DataType::OctetString, {0x01, 0x02, 0xFF}));
}

TEST(EdsParse, DomainDefaultsToDomainTypeAndReadWrite) {
  const auto d = parse(file_with("[2000]\nParameterName=Program\nObjectType=0x2\n", {0x2000}));
  const auto* e = d.od.find(0x2000, 0);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(d.od.find(0x2000)->code, ObjectCode::Domain);
  EXPECT_EQ(e->type, DataType::Domain);
  EXPECT_EQ(e->access, Access::ReadWrite);
  EXPECT_EQ(e->value, Value::of_bytes(DataType::Domain, {}));
}

TEST(EdsParse, LimitsAreKept) {
  const auto d =
      parse(file_with("[2000]\nParameterName=x\nDataType=0x0003\nAccessType=rw\nLowLimit=-100\n"
                      "HighLimit=100\nDefaultValue=-100\n",
                      {0x2000}));
  const auto* e = d.od.find(0x2000, 0);
  EXPECT_EQ(e->low, Value::of_signed(DataType::Integer16, -100));
  EXPECT_EQ(e->high, Value::of_signed(DataType::Integer16, 100));
  EXPECT_EQ(i(e->value), -100);
}

TEST(EdsParse, RecordWithSubSections) {
  const auto d = parse(
      file_with("[2000]\nParameterName=Rec\nObjectType=0x9\nSubNumber=3\n"
                "[2000sub0]\nParameterName=Highest\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue=3\n"
                "[2000SUB1]\nParameterName=First\nDataType=0x0007\nAccessType=rw\nDefaultValue=1\n"
                "[2000sub03]\nParameterName=Third\nDataType=0x0009\nAccessType=ro\nDefaultValue=three\n",
                {0x2000}));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  const auto* o = d.od.find(0x2000);
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->code, ObjectCode::Record);
  EXPECT_EQ(o->name, "Rec");
  ASSERT_EQ(o->subs.size(), 3u);
  EXPECT_EQ(o->subs.at(1).name, "First");
  EXPECT_EQ(o->subs.at(3).value, Value::of_string("three"));
  EXPECT_EQ(o->subs.at(3).sub, 3);
}

// ---- $NODEID ------------------------------------------------------------------

std::string cob_id_object(std::string_view value) {
  return file_with(
      "[1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n"
      "[1800sub0]\nParameterName=Highest\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"
      "[1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=" +
          std::string(value) + "\n",
      {0x1800});
}

TEST(EdsNodeId, AllForms) {
  const std::vector<std::pair<std::string, std::uint64_t>> cases = {
      {"$NODEID", 5},           {"$NODEID+0x180", 0x185},
      {"0x180+$NODEID", 0x185}, {"$nodeid + 0x200", 0x205},
      {"$NodeId+384", 389},     {"0x80000000+$NODEID+0x180", 0x80000185},
  };
  for (const auto& [text, expected] : cases) {
    const auto d = parse(cob_id_object(text), 5);
    EXPECT_EQ(u(d.od.find(0x1800, 1)->value), expected) << text;
    EXPECT_EQ(u(*d.od.find(0x1800, 1)->default_value), expected) << text;
  }
}

TEST(EdsNodeId, MissingNodeIdIsAnErrorAtTheValue) {
  const auto text = cob_id_object("$NODEID+0x180");
  const auto e = parse_error(text);
  EXPECT_EQ(e.line(), line_of(text, "DefaultValue=$NODEID+0x180"));
  EXPECT_EQ(e.file(), "test.eds");
  EXPECT_NE(e.reason().find("no node-ID is known"), std::string::npos) << e.what();
}

TEST(EdsNodeId, NotNeededWhenParameterValueIsGiven) {
  const auto text = file_with(
      "[1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n"
      "[1800sub0]\nParameterName=Highest\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"
      "[1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x180\n"
      "ParameterValue=0x1A0\n",
      {0x1800});
  const auto d = parse(text, std::nullopt, "test.dcf");
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_TRUE(d.is_dcf);
  EXPECT_FALSE(d.node_id.has_value());
  EXPECT_EQ(u(d.od.find(0x1800, 1)->value), 0x1A0u);
  EXPECT_FALSE(d.od.find(0x1800, 1)->default_value.has_value());
}

TEST(EdsNodeId, InLimitsIsResolved) {
  const auto d = parse(file_with("[2000]\nParameterName=x\nDataType=0x0007\nAccessType=rw\n"
                                 "LowLimit=$NODEID+0x180\nHighLimit=$NODEID+0x1FF\nDefaultValue=$NODEID+0x181\n",
                                 {0x2000}),
                       10);
  const auto* e = d.od.find(0x2000, 0);
  EXPECT_EQ(u(*e->low), 0x18Au);
  EXPECT_EQ(u(*e->high), 0x209u);
  EXPECT_EQ(u(e->value), 0x18Bu);
}

TEST(EdsNodeId, ResultMustFitTheType) {
  const auto text =
      file_with("[2000]\nParameterName=x\nDataType=0x0005\nAccessType=rw\nDefaultValue=$NODEID+0xFF\n", {0x2000});
  const auto e = parse_error(text, 5);
  EXPECT_EQ(e.line(), line_of(text, "DefaultValue=$NODEID"));
  EXPECT_NE(e.reason().find("node-ID 5"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("UNSIGNED8"), std::string::npos) << e.what();
}

TEST(EdsNodeId, MalformedExpressions) {
  for (const std::string bad : {"$NODEID*2", "$NODEID+$NODEID", "$NODE+1", "$NODEID+", "$NODEID-1"}) {
    const auto text = cob_id_object(bad);
    const auto e = parse_error(text, 5);
    EXPECT_EQ(e.line(), line_of(text, "DefaultValue=" + bad)) << bad << ": " << e.what();
  }
  // Without $NODEID it is just a number that cannot be read (issue 28 item
  // 8): the entry has no default, the rest of the file is read.
  const auto text = cob_id_object("0x180+");
  const auto d = parse(text, 5);
  EXPECT_TRUE(has_warning(d, "DefaultValue '0x180+' left out")) << text;
  ASSERT_EQ(d.values_left_out.size(), 1u);
  EXPECT_NE(d.values_left_out[0].find(":" + std::to_string(line_of(text, "DefaultValue=0x180+")) + ": "),
            std::string::npos)
      << d.values_left_out[0];
}

TEST(EdsNodeId, OnlyForIntegers) {
  const auto text =
      file_with("[2000]\nParameterName=x\nDataType=0x0008\nAccessType=rw\nDefaultValue=$NODEID\n", {0x2000});
  // Issue 28 item 8: a value that cannot be read leaves the entry without
  // a default, with a warning, instead of refusing the file.
  const auto bad = parse(text, 5);
  EXPECT_TRUE(has_warning(bad, "DefaultValue '$NODEID' left out ($NODEID in a value of type REAL32)"));
  ASSERT_NE(bad.od.find(0x2000, 0), nullptr);
  EXPECT_FALSE(bad.od.find(0x2000, 0)->default_value.has_value());
  // In a string '$' is just text.
  const auto d =
      parse(file_with("[2001]\nParameterName=s\nDataType=0x0009\nAccessType=rw\nDefaultValue=costs $5\n", {0x2001}));
  EXPECT_EQ(d.od.find(0x2001, 0)->value, Value::of_string("costs $5"));
}

TEST(EdsNodeId, ArgumentOutOfRange) {
  for (int bad : {0, 128, 255}) {
    const auto e = parse_error(file_with(""), static_cast<std::uint8_t>(bad));
    EXPECT_EQ(e.line(), 0u);
    EXPECT_EQ(std::string(e.what()), "test.eds: node-ID " + std::to_string(bad) + " is outside 1..127");
  }
}

// ---- DCF -------------------------------------------------------------------------

TEST(EdsDcfInline, ParameterValueBecomesTheValue) {
  const std::string text = file_with(
      "[DeviceComissioning]\nNodeID=0x10\nNodeName=n\nBaudrate=250\nCANopenManager=1\n"
      "[2000]\nParameterName=x\nDataType=0x0006\nAccessType=rw\nDefaultValue=1\nParameterValue=2\n"
      "[2001]\nParameterName=y\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x100\n",
      {0x2000, 0x2001});
  const auto d = parse(text);
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_TRUE(d.is_dcf);
  EXPECT_EQ(d.node_id, 16);
  EXPECT_TRUE(d.commissioning->canopen_manager);
  EXPECT_EQ(d.commissioning->baud_rate_kbit, 250);
  EXPECT_EQ(u(d.od.find(0x2000, 0)->value), 2u);
  EXPECT_EQ(u(*d.od.find(0x2000, 0)->default_value), 1u);
  EXPECT_EQ(u(d.od.find(0x2001, 0)->value), 0x110u);
}

TEST(EdsDcfInline, DetectedByFileNameToo) {
  const auto d = parse(file_with(""), std::nullopt, "NODE.DCF");
  EXPECT_TRUE(d.is_dcf);
  EXPECT_FALSE(d.commissioning.has_value());
  EXPECT_FALSE(parse(file_with("")).is_dcf);
}

TEST(EdsDcfInline, ParameterValueInAnEdsIsUsedWithOneWarning) {
  const std::string text = file_with(
      "[2000]\nParameterName=x\nDataType=0x0006\nAccessType=rw\nDefaultValue=1\nParameterValue=2\n"
      "[2001]\nParameterName=y\nDataType=0x0006\nAccessType=rw\nDefaultValue=1\nParameterValue=3\n",
      {0x2000, 0x2001});
  const auto d = parse(text);
  EXPECT_EQ(u(d.od.find(0x2000, 0)->value), 2u);
  EXPECT_EQ(u(d.od.find(0x2001, 0)->value), 3u);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_EQ(d.warnings[0], "test.eds:" + std::to_string(line_of(text, "ParameterValue=2")) +
                               ": ParameterValue in a file that is not a DCF; used as the current value");
}

// A DCF made for a node whose ID the configuration (or LSS) gives carries
// NodeID 0 or FFh: not a node-ID, ignored with a warning.
TEST(EdsDcfInline, NodeIdOutside1To127IsIgnored) {
  for (const std::string odd : {"0", "128", "0x80", "0xFF"}) {
    const auto text = file_with("[DeviceComissioning]\nNodeID=" + odd + "\n");
    const auto d = parse(text);
    EXPECT_FALSE(d.node_id.has_value()) << odd;
    EXPECT_TRUE(has_warning(d, "test.eds:" + std::to_string(line_of(text, "NodeID=")) + ": NodeID " + odd +
                                   " is not a node-ID 1..127; ignored"))
        << odd;
  }
  const auto text = file_with("[DeviceComissioning]\nNodeID=abc\n");
  EXPECT_EQ(parse_error(text).line(), line_of(text, "NodeID="));
}

TEST(EdsDcfInline, DoubleMSpellingIsAcceptedWithAWarning) {
  const auto text = file_with("[DeviceCommissioning]\nNodeID=3\n");
  const auto d = parse(text);
  EXPECT_EQ(d.node_id, 3);
  EXPECT_TRUE(d.is_dcf);
  EXPECT_TRUE(has_warning(d, "spells the section [DeviceComissioning]"));
}

// ---- CompactSubObj ----------------------------------------------------------------

TEST(EdsCompact, ExpandsToSub0AndEntries) {
  const auto d =
      parse(file_with("[2000]\nParameterName=Gain\nObjectType=0x8\nDataType=0x0006\nAccessType=rw\n"
                      "DefaultValue=7\nPDOMapping=1\nLowLimit=1\nHighLimit=100\nCompactSubObj=3\n",
                      {0x2000}));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  const auto* o = d.od.find(0x2000);
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->code, ObjectCode::Array);
  ASSERT_EQ(o->subs.size(), 4u);
  const auto& sub0 = o->subs.at(0);
  EXPECT_EQ(sub0.type, DataType::Unsigned8);
  EXPECT_EQ(sub0.access, Access::ReadOnly);
  EXPECT_FALSE(sub0.pdo_mappable);
  EXPECT_EQ(sub0.value, Value::of_unsigned(DataType::Unsigned8, 3));
  EXPECT_EQ(sub0.default_value, sub0.value);
  for (std::uint8_t s = 1; s <= 3; ++s) {
    const auto& e = o->subs.at(s);
    EXPECT_EQ(e.sub, s);
    EXPECT_EQ(e.name, "Gain" + std::to_string(s));
    EXPECT_EQ(e.type, DataType::Unsigned16);
    EXPECT_EQ(e.access, Access::ReadWrite);
    EXPECT_TRUE(e.pdo_mappable);
    EXPECT_EQ(u(e.value), 7u);
    EXPECT_EQ(u(*e.low), 1u);
    EXPECT_EQ(u(*e.high), 100u);
  }
}

TEST(EdsCompact, NamesAndValuesSections) {
  const auto text = file_with(
      "[2000]\nParameterName=Gain\nObjectType=0x9\nDataType=0x0003\nAccessType=rw\nDefaultValue=7\n"
      "CompactSubObj=3\n"
      "[2000Name]\nNrOfEntries=2\n1=Left\n2=Right\n"
      "[2000value]\nNrOfEntries=1\n2=-9\n",
      {0x2000});
  const auto d = parse(text);
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  const auto* o = d.od.find(0x2000);
  EXPECT_EQ(o->code, ObjectCode::Record);
  EXPECT_EQ(o->subs.at(1).name, "Left");
  EXPECT_EQ(o->subs.at(2).name, "Right");
  EXPECT_EQ(o->subs.at(3).name, "Gain3");
  EXPECT_EQ(i(o->subs.at(1).value), 7);
  EXPECT_EQ(i(o->subs.at(2).value), -9);
  EXPECT_EQ(i(*o->subs.at(2).default_value), 7);
}

TEST(EdsCompact, NodeIdDefaultNotNeededWhenEveryValueIsGiven) {
  const auto d =
      parse(file_with("[2000]\nParameterName=Ids\nObjectType=0x8\nDataType=0x0007\nAccessType=rw\n"
                      "DefaultValue=$NODEID+0x100\nCompactSubObj=1\n[2000Value]\nNrOfEntries=1\n1=0x123\n",
                      {0x2000}));
  EXPECT_EQ(u(d.od.find(0x2000, 1)->value), 0x123u);
}

// ---- object links, dummy usage, comments ------------------------------------------

TEST(EdsParse, ObjectLinksAreKept) {
  const auto d =
      parse(file_with(std::string(kVar2000) + "[2000ObjectLinks]\nObjectLinks=2\n1=0x1000\n2=0x6000\n", {0x2000}));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_EQ(d.object_links.at(0x2000), (std::vector<std::uint16_t>{0x1000, 0x6000}));
}

TEST(EdsParse, DummyUsageAndComments) {
  const auto d =
      parse(file_with("[DummyUsage]\nDummy0001=0\nDummy0002=1\ndummy0007=1\nDummy001B=1\n"
                      "[Comments]\nLines=2\nLine1=first\nLine2=second\n"));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_EQ(d.dummy_usage, (std::vector<std::uint16_t>{0x0002, 0x0007, 0x001B}));
  EXPECT_EQ(d.comments, (std::vector<std::string>{"first", "second"}));
}

TEST(EdsParse, ErrorWhatIsFileLineReason) {
  const EdsError e("dev.eds", 12, "something is wrong");
  EXPECT_EQ(std::string(e.what()), "dev.eds:12: something is wrong");
  EXPECT_EQ(e.file(), "dev.eds");
  EXPECT_EQ(e.line(), 12u);
  EXPECT_EQ(e.reason(), "something is wrong");
}

// CiA 306 4.6.3: ObjFlags (bit 0 refuse write on download, bit 1 refuse
// read on scan) of the object section reach its sub-objects; whether a DCF
// entry carried a ParameterValue, and whether its default was written in
// hex, are kept for DCF read-back and apply (master/dcf_transfer.hpp).
TEST(EdsParse, EntryFacts_ObjFlagsParameterValueAndHexDefault) {
  const auto d = parse(file_with("[DeviceComissioning]\nNodeID=5\n"
                                 "[2000]\nParameterName=Flagged\nObjectType=0x7\nDataType=0x0006\nAccessType=rw\n"
                                 "DefaultValue=0x10\nParameterValue=17\nObjFlags=0x2\n"
                                 "[2001]\nParameterName=Rec\nObjectType=0x9\nSubNumber=2\nObjFlags=1\n"
                                 "[2001sub0]\nParameterName=n\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"
                                 "[2001sub1]\nParameterName=v\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\n"
                                 "DefaultValue=7\nObjFlags=0x2\n"
                                 "[2002]\nParameterName=Odd\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\n"
                                 "DefaultValue=3\nObjFlags=NV\n",
                                 {0x2000, 0x2001, 0x2002}),
                       {}, "test.dcf");
  const EntryFacts flagged = d.facts(0x2000, 0);
  EXPECT_EQ(flagged.obj_flags, kObjFlagRefuseReadOnScan);
  EXPECT_TRUE(flagged.parameter_value);
  EXPECT_TRUE(flagged.hex_default);
  EXPECT_EQ(d.od.find(0x2000, 0)->value, Value::of_unsigned(DataType::Unsigned16, 17));
  EXPECT_EQ(d.facts(0x2001, 1).obj_flags, kObjFlagRefuseWriteOnDownload | kObjFlagRefuseReadOnScan);
  EXPECT_EQ(d.facts(0x2001, 0).obj_flags, kObjFlagRefuseWriteOnDownload);
  EXPECT_FALSE(d.facts(0x2001, 1).parameter_value);
  EXPECT_FALSE(d.facts(0x2001, 1).hex_default);
  // Vendor junk in a hint: ignored with a warning, the file is read.
  EXPECT_EQ(d.facts(0x2002, 0).obj_flags, 0U);
  EXPECT_TRUE(has_warning(d, "ObjFlags 'NV'"));
  EXPECT_EQ(d.facts(0x3000, 0).obj_flags, 0U) << "no such entry: no facts";
}

}  // namespace
}  // namespace canopen::eds::test
