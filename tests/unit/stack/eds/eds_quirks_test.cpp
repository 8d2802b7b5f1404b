// What real vendor EDS/DCF files contain, one small file of the project's
// own per quirk (tests/support/eds/quirks/), each reproducing what was
// seen in public vendor files: the file is accepted, the warning names
// file:line and what was assumed, and the dictionary holds what the file
// unambiguously means. Refused are only files that cannot be read without
// guessing (CiA 306, as eds.hpp states the rules).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "eds_test_util.hpp"

namespace canopen::eds::test {
namespace {

struct Loaded {
  std::filesystem::path path;
  std::string text;
  DeviceDescription d;
};

Loaded load_quirk(std::string_view name, std::optional<std::uint8_t> node_id = 5) {
  const auto path = test_data("quirks") / name;
  return {path, read_text(path), load_device_description(path, node_id)};
}

// A warning "<path>:<line>: ...part..." must be there.
void expect_warning_on(const Loaded& q, std::size_t line, std::string_view part) {
  const auto prefix = q.path.string() + ":" + std::to_string(line) + ": ";
  for (const auto& w : q.d.warnings) {
    if (w.starts_with(prefix) && w.find(part) != std::string::npos) return;
  }
  ADD_FAILURE() << "no warning " << prefix << "..." << part << "; warnings:\n"
                << [&] {
                     std::string all;
                     for (const auto& w : q.d.warnings) all += "  " + w + "\n";
                     return all;
                   }();
}

// The same, naming the line by the first line holding `needle` (at or after `after`).
void expect_warning(const Loaded& q, std::string_view needle, std::string_view part, std::string_view after = {}) {
  const auto line = line_of(q.text, needle, after);
  ASSERT_NE(line, 0u) << "test bug: no line with " << needle;
  expect_warning_on(q, line, part);
}

const od::SubEntry& at(const Loaded& q, std::uint16_t index, std::uint8_t sub) {
  const auto* e = q.d.od.find(index, sub);
  if (e == nullptr) throw std::runtime_error("no entry " + std::to_string(index) + "sub" + std::to_string(sub));
  return *e;
}

TEST(EdsQuirk, ObjectListCountsThatDisagreeWithTheirEntries) {
  const auto q = load_quirk("object-list-counts.eds");
  expect_warning(q, "SupportedObjects=0", "SupportedObjects=0 but [MandatoryObjects] has 1 entries");
  expect_warning(q, "SupportedObjects=3", "SupportedObjects=3 but [OptionalObjects] has 2 entries");
  expect_warning(q, "SupportedObjects=1", "[ManufacturerObjects] has 2 entries", "[ManufacturerObjects]");
  // The entries present are the lists.
  EXPECT_EQ(q.d.mandatory_objects, (std::vector<std::uint16_t>{0x1000}));
  EXPECT_EQ(q.d.optional_objects, (std::vector<std::uint16_t>{0x2000, 0x2001}));
  EXPECT_EQ(q.d.manufacturer_objects, (std::vector<std::uint16_t>{0x2002, 0x2003}));
}

TEST(EdsQuirk, ListedWithoutSectionUnlistedSectionsAndStraySubSections) {
  const auto q = load_quirk("sections-and-lists.eds");
  expect_warning(q, "3=0x2004", "object 0x2004 is listed in [OptionalObjects] but has no [2004] section");
  expect_warning(q, "[2002]", "object section [2002] is not in any object list; loaded anyway");
  expect_warning(q, "[2001sub0]", "VAR object [2001] cannot have sub-object sections; [2001sub0] ignored");
  expect_warning(q, "[2003sub1]", "sub-object section [2003sub1] without an object section [2003]; ignored");
  EXPECT_EQ(q.d.od.find(0x2004), nullptr);
  EXPECT_EQ(q.d.od.find(0x2003), nullptr);
  EXPECT_EQ(at(q, 0x2001, 0).type, DataType::Unsigned16);
  EXPECT_EQ(q.d.od.find(0x2001)->subs.size(), 1u);
  EXPECT_NE(q.d.od.find(0x2002), nullptr);
  EXPECT_EQ(q.d.optional_objects, (std::vector<std::uint16_t>{0x2000, 0x2001}));
}

TEST(EdsQuirk, SubNumberAndNrOfEntriesDisagreeingWithWhatIsPresent) {
  const auto q = load_quirk("counts-disagree.eds");
  expect_warning(q, "SubNumber=7", "SubNumber=7 but [1800] has 5 sub-object sections; those are used");
  expect_warning(q, "NrOfEntries=3", "NrOfEntries=3 but [2000Name] has 2 entries; those are used");
  EXPECT_EQ(q.d.od.find(0x1800)->subs.size(), 5u);
  EXPECT_EQ(u(at(q, 0x1800, 1).value), 0x185u);
  EXPECT_EQ(u(at(q, 0x1800, 5).value), 100u);
  EXPECT_EQ(at(q, 0x2000, 2).name, "Gain I");
  EXPECT_EQ(at(q, 0x2000, 3).name, "Gains3");  // no name given: ParameterName + sub-index
}

TEST(EdsQuirk, LimitsDefaultsAndSignedTypesInUnsignedHex) {
  const auto q = load_quirk("limits.eds");
  // Default outside its limits: kept, the device holds it at power-on.
  expect_warning(q, "DefaultValue=5", "DefaultValue 5 is outside LowLimit/HighLimit");
  EXPECT_EQ(u(at(q, 0x2000, 0).value), 5u);
  EXPECT_EQ(u(*at(q, 0x2000, 0).high), 1u);
  // INTEGER8 0xFF is -1; limits 0x80..0x7F are -128..127.
  expect_warning(q, "DefaultValue=0xFF", "DefaultValue '0xFF' read as two's complement -1 (INTEGER8)");
  expect_warning(q, "LowLimit=0x80", "LowLimit '0x80' read as two's complement -128 (INTEGER8)");
  EXPECT_EQ(i(at(q, 0x2001, 0).value), -1);
  EXPECT_EQ(i(*at(q, 0x2001, 0).low), -128);
  EXPECT_EQ(i(*at(q, 0x2001, 0).high), 127);
  // 0..0xFF on an INTEGER8 contradicts itself: no limits.
  expect_warning(q, "LowLimit=0", "LowLimit 0 is above HighLimit -1 in [2002]; both ignored", "[2002]");
  EXPECT_FALSE(at(q, 0x2002, 0).low.has_value());
  EXPECT_FALSE(at(q, 0x2002, 0).high.has_value());
  // A limit the type cannot hold limits nothing.
  expect_warning(q, "HighLimit=494967295", "HighLimit '494967295' is not a valid UNSIGNED16");
  EXPECT_FALSE(at(q, 0x2003, 0).high.has_value());
  EXPECT_EQ(u(*at(q, 0x2003, 0).low), 0u);
  EXPECT_EQ(i(*at(q, 0x2004, 0).low), -2147483648LL);
  EXPECT_EQ(i(*at(q, 0x2004, 0).high), 2147483647);
}

TEST(EdsQuirk, HexWhereZeroOrOneIsExpectedAndAccessTypeCase) {
  const auto q = load_quirk("hex-flags.eds");
  expect_warning(q, "PDOMapping=0x1", "PDOMapping=0x1 read as 1");
  expect_warning(q, "DefaultValue=0x00", "DefaultValue '0x00' read as BOOLEAN 0", "[2001]");
  EXPECT_TRUE(at(q, 0x2000, 0).pdo_mappable);
  EXPECT_EQ(at(q, 0x2000, 0).access, od::Access::ReadWrite);
  EXPECT_FALSE(at(q, 0x2001, 0).pdo_mappable);
  EXPECT_EQ(at(q, 0x2001, 0).value, Value::of_bool(false));
  EXPECT_EQ(at(q, 0x2001, 0).access, od::Access::ReadOnly);
  EXPECT_EQ(at(q, 0x2002, 0).value, Value::of_bool(true));
  EXPECT_EQ(at(q, 0x2002, 0).access, od::Access::ReadWriteWrite);
  EXPECT_EQ(at(q, 0x2003, 0).access, od::Access::Const);
}

TEST(EdsQuirk, InlineCommentsHashLinesAndBlankLines) {
  const auto q = load_quirk("inline-comments.eds");
  expect_warning(q, "# exported", "'#' comment line(s) ignored");
  expect_warning(q, "DefaultValue=0x3ED", "DefaultValue '0x3ED ; prevent homing': an inline comment ignored");
  expect_warning(q, "PDOMapping=0 # No", "PDOMapping=0 # No read as 0");
  expect_warning(q, "DataType=0x0006", "an inline comment ignored");
  expect_warning(q, "[2002] #", "comment after the section header [2002] ignored");
  EXPECT_EQ(u(at(q, 0x2000, 0).value), 0x3EDu);
  EXPECT_FALSE(at(q, 0x2000, 0).pdo_mappable);
  EXPECT_EQ(at(q, 0x2001, 0).type, DataType::Unsigned16);
  EXPECT_EQ(u(at(q, 0x2002, 0).value), 3u);
}

TEST(EdsQuirk, DomainDefaultsRealBitPatternsAndCSuffixes) {
  const auto q = load_quirk("odd-values.eds");
  for (const int index : {0x2000, 0x2001, 0x2002, 0x2003}) {
    EXPECT_EQ(at(q, static_cast<std::uint16_t>(index), 0).value, Value::zero(DataType::Domain)) << std::hex << index;
  }
  expect_warning(q, "DefaultValue=0", "DefaultValue '0' is not hex data; the DOMAIN starts empty", "[2001]");
  expect_warning(q, "DefaultValue=@ABCD", "DefaultValue '@ABCD' is not hex data");
  expect_warning(q, "DefaultValue=NULL", "DefaultValue 'NULL' is not hex data");
  expect_warning(q, "DefaultValue=0x40490FDB", "read as the bit pattern of 3.1415927 (REAL32)");
  EXPECT_FLOAT_EQ(std::get<float>(at(q, 0x2004, 0).value.data), 3.14159265f);
  expect_warning(q, "DefaultValue=0x400921FB54442D18", "(REAL64)");
  EXPECT_DOUBLE_EQ(std::get<double>(at(q, 0x2005, 0).value.data), M_PI);
  expect_warning(q, "DefaultValue=0x1234567890ABCDEFLL", "the C suffix 'LL' ignored");
  EXPECT_EQ(i(at(q, 0x2006, 0).value), 0x1234567890ABCDEFLL);
  EXPECT_EQ(u(at(q, 0x2007, 0).value), 1u);
  EXPECT_FLOAT_EQ(std::get<float>(at(q, 0x2008, 0).value.data), 0.5f);
  EXPECT_EQ(u(at(q, 0x2009, 0).value), 16u);
}

TEST(EdsQuirk, SymbolicObjectTypeAndDataType) {
  const auto q = load_quirk("symbolic-types.eds");
  expect_warning(q, "ObjectType=VAR", "ObjectType=VAR read as 0x7");
  expect_warning(q, "DataType=UNSIGNED16", "DataType=UNSIGNED16 read as 0x0006");
  EXPECT_EQ(at(q, 0x2000, 0).type, DataType::Unsigned16);
  EXPECT_EQ(u(at(q, 0x2000, 0).value), 1500u);
  EXPECT_EQ(q.d.od.find(0x2001)->code, od::ObjectCode::Record);
  EXPECT_EQ(i(at(q, 0x2001, 1).value), -5);
}

// CiA 301 7.4.3: sub-index FFh describes the object's structure; an array
// has at most 254 entries.
TEST(EdsQuirk, CompactSubObj255) {
  const auto q = load_quirk("compact-255.eds");
  expect_warning(q, "CompactSubObj=255", "sub-index FFh is reserved; entries 1..254 used");
  EXPECT_EQ(q.d.od.find(0x1003)->subs.size(), 255u);  // sub 0 and 1..254
  EXPECT_EQ(u(at(q, 0x1003, 0).value), 254u);
}

// A DCF for a node whose ID the configuration gives: NodeID 0 or FFh.
// $NODEID resolves with the configured ID in all its spellings.
TEST(EdsQuirk, DcfNodeIdZeroOrFFAndNodeIdSpellings) {
  for (const char* name : {"nodeid-zero.dcf", "nodeid-ff.dcf"}) {
    const auto q = load_quirk(name, 9);
    expect_warning(q, "NodeID=", "is not a node-ID 1..127; ignored (the configured node-ID is used)");
    EXPECT_TRUE(q.d.is_dcf);
    EXPECT_EQ(q.d.node_id, 9);
    EXPECT_EQ(u(at(q, 0x1200, 1).value), 0x609u) << name;
    EXPECT_EQ(u(at(q, 0x1200, 2).value), 0x589u);
    EXPECT_EQ(u(at(q, 0x1400, 0).value), 0x209u);  // "$NodeID + 0x200"
    EXPECT_EQ(u(at(q, 0x1800, 0).value), 0x189u);  // "$NODEID +0x180"
    EXPECT_EQ(u(at(q, 0x1801, 0).value), 649u);    // "$NODEID+640"
    EXPECT_EQ(u(at(q, 0x1802, 0).value), 0x389u);  // "0x380 + $nodeid"
    EXPECT_EQ(u(at(q, 0x1803, 0).value), 9u);      // "$NODEID"
  }
  // Without a configured node-ID the $NODEID values cannot be resolved.
  const auto path = test_data("quirks") / "nodeid-ff.dcf";
  try {
    (void)load_device_description(path);
    FAIL() << "expected an EdsError";
  } catch (const EdsError& e) {
    EXPECT_NE(e.reason().find("uses $NODEID but no node-ID is known"), std::string::npos) << e.what();
  }
}

TEST(EdsQuirk, OddEdsVersionAndMissingFileInfoOrDeviceInfo) {
  const auto v = load_quirk("eds-version-402.eds");
  expect_warning(v, "EDSVersion=402", "EDSVersion=402 is not a CiA 306 version (4.0); read as a 4.0 file");
  EXPECT_EQ(v.d.file.eds_version, "402");
  const auto n = load_quirk("no-fileinfo.eds");
  EXPECT_TRUE(has_warning(n.d, n.path.string() + ": no [FileInfo] section"));
  EXPECT_TRUE(has_warning(n.d, n.path.string() + ": no [DeviceInfo] section"));
  EXPECT_EQ(u(n.d.od.find(0x1000, 0)->value), 0x191u);
}

TEST(EdsQuirk, Latin1NamesMixedLineEndingsBomAndNoFinalNewline) {
  const auto q = load_quirk("latin1-mixed-endings.eds");
  expect_warning(q, "Temperatur", "text is not UTF-8; the file is read as Latin-1");
  EXPECT_EQ(at(q, 0x2000, 0).name, "Temperatur in \xC2\xB0" "C");
  EXPECT_EQ(at(q, 0x2001, 0).name, "Drehzahl \xC3\x9C" "berwachung");
  EXPECT_EQ(i(at(q, 0x2000, 0).value), -40);
  EXPECT_EQ(u(at(q, 0x2001, 0).value), 3000u);  // the last line, without a newline
  EXPECT_EQ(q.d.file.file_name, "latin1-mixed-endings.eds");  // CRLF part, BOM stripped
}

TEST(EdsQuirk, DuplicatesThatAgreeAreFine) {
  const auto q = load_quirk("duplicates-identical.eds");
  expect_warning_on(q, line_of(q.text, "DefaultValue=5") + 1, "key 'DefaultValue' in [2000] repeated with the same value");
  expect_warning_on(q, line_of(q.text, "DefaultValue=9") - 1, "key 'ParameterName' in [2001] given again empty");
  EXPECT_EQ(u(at(q, 0x2000, 0).value), 5u);
  EXPECT_EQ(at(q, 0x2001, 0).name, "first");
  EXPECT_EQ(u(at(q, 0x2001, 0).value), 9u);
}

// Two [1009] sections with different names: which object is meant cannot
// be known, so the file is refused naming the line.
TEST(EdsQuirk, DuplicatesThatConflictAreRefused) {
  const auto path = test_data("quirks") / "duplicates-conflict.eds";
  const auto text = read_text(path);
  try {
    (void)load_device_description(path, 5);
    FAIL() << "expected an EdsError";
  } catch (const EdsError& e) {
    EXPECT_EQ(e.line(), line_of(text, "ParameterName=Manufacturer software"));
    EXPECT_NE(e.reason().find("repeated with a different value"), std::string::npos) << e.what();
  }
}

TEST(EdsQuirk, ObjectsThatCannotBeReadAreLeftOut) {
  const auto q = load_quirk("unreadable-objects.eds");
  expect_warning(q, "AccessType=UNKNOWN", "unknown AccessType 'UNKNOWN' in [2001]");
  expect_warning(q, "DataType=0x0020", "DataType 0x0020 of [2002] is a structure, not a value type; object [2002] left out");
  expect_warning(q, "ObjectType=0x3", "unknown ObjectType 0x3 in [2003]");
  expect_warning(q, "[2004]", "ARRAY object [2004] has no sub-objects");
  expect_warning(q, "ObjectType=0x08", "sub-object [2005sub1] has ObjectType 0x08; a sub-object is a VAR");
  for (const int gone : {0x2001, 0x2002, 0x2003, 0x2004}) {
    EXPECT_EQ(q.d.od.find(static_cast<std::uint16_t>(gone)), nullptr) << std::hex << gone;
  }
  EXPECT_NE(q.d.od.find(0x2000, 0), nullptr);
  EXPECT_EQ(at(q, 0x2005, 1).type, DataType::Unsigned32);
}

// Issue 28 item 8: a DefaultValue or ParameterValue nobody can read (a
// fraction on an INTEGER32, out of the type's range, a typo, a vendor
// tool's placeholder) leaves that entry without a default / without a value
// and the rest of the file is read; a DCF's entry is then not written at
// boot (no ParameterValue fact), which values_left_out says louder.
// DefaultValue=0 on a TIME_OF_DAY is valid: midnight of day 0.
TEST(EdsQuirk, ValuesThatCannotBeReadAreLeftOutNotTheFile) {
  const auto q = load_quirk("bad-values.dcf");
  expect_warning(q, "DefaultValue=3.141593", "DefaultValue '3.141593' left out (not a valid INTEGER32");
  expect_warning(q, "DefaultValue=0x40500108", "DefaultValue '0x40500108' left out (not a valid UNSIGNED8");
  expect_warning(q, "ParameterValue=0xFFFF0192",
                 "ParameterValue '0xFFFF0192' left out (not a valid UNSIGNED16: ");
  expect_warning(q, "ParameterValue=0xFFFF0192", "no value (in a DCF: not written at boot)");
  expect_warning(q, "DefaultValue=4x0", "DefaultValue '4x0' left out");
  expect_warning(q, "DefaultValue=<!flux", "DefaultValue '<!flux_map_td1.10.6>' left out");
  EXPECT_EQ(q.d.values_left_out.size(), 5u);
  for (const std::uint16_t index : {std::uint16_t{0x2000}, std::uint16_t{0x2001}, std::uint16_t{0x2003}, std::uint16_t{0x2004}}) {
    EXPECT_FALSE(at(q, index, 0).default_value.has_value()) << std::hex << index;
    EXPECT_EQ(at(q, index, 0).value, Value::zero(at(q, index, 0).type)) << std::hex << index;
  }
  // 2002: its DefaultValue stands, its ParameterValue is gone.
  EXPECT_EQ(u(at(q, 0x2002, 0).value), 100u);
  EXPECT_FALSE(q.d.facts(0x2002, 0).parameter_value);
  EXPECT_TRUE(q.d.facts(0x2006, 0).parameter_value);
  EXPECT_EQ(u(at(q, 0x2006, 0).value), 250u);
  EXPECT_EQ(at(q, 0x2005, 0).value, (Value{DataType::TimeOfDay, TimeOfDay{0, 0}}));
  for (const auto& w : q.d.warnings) EXPECT_EQ(w.find("2005"), std::string::npos) << "TIME_OF_DAY 0 is no slip: " << w;
}

// Issue 28 item 8: a CompactSubObj [xxxxValue] entry that does not fit the
// type is left out like a ParameterValue: that sub-object keeps its default.
TEST(EdsQuirk, CompactValueEntryThatCannotBeReadIsLeftOut) {
  const std::string text = file_with(
      "[2000]\nParameterName=r\nObjectType=0x8\nDataType=0x0005\nAccessType=rw\nDefaultValue=3\n"
      "CompactSubObj=2\n[2000Value]\nNrOfEntries=2\n1=9\n2=300\n",
      {0x2000});
  const auto d = parse(text);
  EXPECT_TRUE(has_warning(d, "test.eds:" + std::to_string(line_of(text, "2=300")) + ": [2000Value] entry 2 '300' left out"));
  EXPECT_EQ(u(d.od.find(0x2000, 1)->value), 9u);
  EXPECT_EQ(u(d.od.find(0x2000, 2)->value), 3u);
  EXPECT_FALSE(d.facts(0x2000, 2).parameter_value);
}

// Issue 28 items 9, 10, 11, 12: a stray word in a section (no '='), an
// object-list number given twice with two objects (both are taken), and a
// [xxxxsubFF] section (the structure sub-index, CiA 301 7.4.3: skipped).
TEST(EdsQuirk, StrayLinesTwiceNumberedObjectsAndSubFF) {
  const auto q = load_quirk("stray-lines.eds");
  expect_warning(q, "reserved", "line 'reserved' in [1000] has no '='; ignored");
  expect_warning(q, "2=0x2002", "key '2' in [OptionalObjects] repeated with another object '0x2002'");
  expect_warning(q, "[2000subFF]", "sub-index FFh is the object's structure");
  EXPECT_EQ(q.d.optional_objects, (std::vector<std::uint16_t>{0x2000, 0x2001, 0x2002}));
  EXPECT_EQ(u(at(q, 0x2002, 0).value), 2u);
  EXPECT_EQ(q.d.od.find(0x2000)->subs.size(), 2u);
  EXPECT_EQ(q.d.od.find(0x2000, 0xFF), nullptr);
  EXPECT_EQ(u(at(q, 0x2000, 1).value), 7u);
}

// Issue 28 item 9: classic Mac OS line ends (CR alone) are line ends, as
// LF and CR LF are: the same file with each reads the same.
TEST(EdsQuirk, CrOnlyLineEndsAreLineEnds) {
  const auto path = test_data("quirks") / "stray-lines.eds";
  const auto lf = read_text(path);
  std::string cr = lf, crlf;
  std::replace(cr.begin(), cr.end(), '\n', '\r');
  for (char c : lf) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  const auto a = parse(lf), b = parse(cr), c = parse(crlf);
  EXPECT_EQ(b.optional_objects, a.optional_objects);
  EXPECT_EQ(c.optional_objects, a.optional_objects);
  for (const auto* d : {&b, &c}) {
    ASSERT_EQ(d->od.objects().size(), a.od.objects().size());
    EXPECT_EQ(u(d->od.find(0x2000, 1)->value), 7u);
    EXPECT_EQ(d->file.file_name, "stray-lines.eds");
  }
  EXPECT_TRUE(has_warning(b, "test.eds:1: lines end with CR alone"));
  EXPECT_FALSE(has_warning(c, "CR alone"));
  // The line numbers in messages count CR line ends.
  EXPECT_TRUE(has_warning(b, "test.eds:" + std::to_string(line_of(lf, "reserved")) + ": line 'reserved'"));
}

}  // namespace
}  // namespace canopen::eds::test
