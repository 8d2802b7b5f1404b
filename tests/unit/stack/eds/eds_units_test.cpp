// Physical units and factors in EDS files. CiA 306 has no key for them, so
// these are the conventions public vendor files use (eds.hpp lists them):
// what a dashboard shows next to a value, and how a raw value is scaled.
#include <gtest/gtest.h>

#include "eds_test_util.hpp"

namespace canopen::eds::test {
namespace {

std::string var(std::string_view index, std::string_view name, std::string_view extra = {}) {
  return "[" + std::string(index) + "]\nParameterName=" + std::string(name) +
         "\nObjectType=0x7\nDataType=0x0003\nAccessType=ro\nPDOMapping=1\nDefaultValue=0\n" + std::string(extra);
}

// python-canopen's convention: Unit= plus Factor= (value in unit = raw x factor).
TEST(EdsUnits, UnitAndFactorKeys) {
  const auto d = parse(file_with(var("2000", "Analog input", "Unit=mV\nFactor=0.1\n") +
                                     var("2001", "Pressure", "PhysicalUnit=bar\n") +
                                     var("2002", "Scaled counter", "Factor=2.5\n"),
                                 {0x2000, 0x2001, 0x2002}));
  EXPECT_EQ(d.facts(0x2000, 0).unit, "mV");
  EXPECT_EQ(d.facts(0x2000, 0).factor, 0.1);
  EXPECT_EQ(d.facts(0x2001, 0).unit, "bar");
  EXPECT_FALSE(d.facts(0x2001, 0).factor);
  EXPECT_EQ(d.facts(0x2002, 0).unit, "");
  EXPECT_EQ(d.facts(0x2002, 0).factor, 2.5);
  // The keys are understood, so they are not "unknown key" warnings.
  EXPECT_FALSE(has_warning(d, "unknown key 'Unit'"));
  EXPECT_FALSE(has_warning(d, "unknown key 'Factor'"));
  EXPECT_FALSE(has_warning(d, "unknown key 'PhysicalUnit'"));
}

// Curtis/Sevcon files: "Unit=0.01A per unit" is a factor and a unit.
TEST(EdsUnits, PerUnitTextGivesFactorAndUnit) {
  const auto d = parse(file_with(var("2000", "Battery Current", "Unit=0.01A per unit\n") +
                                     var("2001", "Battery Voltage", "Unit=0.0625V per unit\n") +
                                     var("2002", "Motor Speed", "Unit=rpm\n") +
                                     var("2003", "Odd", "Unit=A per unit\n"),
                                 {0x2000, 0x2001, 0x2002, 0x2003}));
  EXPECT_EQ(d.facts(0x2000, 0).unit, "A");
  EXPECT_EQ(d.facts(0x2000, 0).factor, 0.01);
  EXPECT_EQ(d.facts(0x2001, 0).unit, "V");
  EXPECT_EQ(d.facts(0x2001, 0).factor, 0.0625);
  EXPECT_EQ(d.facts(0x2002, 0).unit, "rpm");
  EXPECT_FALSE(d.facts(0x2002, 0).factor);
  // No number before "per unit": nothing to scale by; the text is kept as written.
  EXPECT_EQ(d.facts(0x2003, 0).unit, "A per unit");
  EXPECT_FALSE(d.facts(0x2003, 0).factor);
}

// A Factor that is no number is a warning with file:line, never fatal; the
// unit stays, without a factor. An empty Unit= says nothing.
TEST(EdsUnits, BadFactorWarnsWithItsLineAndKeepsTheUnit) {
  const auto text = file_with(var("2000", "Error factor", "Factor=ERROR\nUnit=mV\n") +
                                  var("2001", "Zero factor", "Factor=0\n") + var("2002", "Empty", "Unit=\nFactor=\n"),
                              {0x2000, 0x2001, 0x2002});
  const auto d = parse(text);
  EXPECT_EQ(d.facts(0x2000, 0).unit, "mV");
  EXPECT_FALSE(d.facts(0x2000, 0).factor);
  EXPECT_TRUE(has_warning(d, "test.eds:" + std::to_string(line_of(text, "Factor=ERROR")) + ": Factor 'ERROR'"));
  EXPECT_TRUE(has_warning(d, "test.eds:" + std::to_string(line_of(text, "Factor=0")) + ": Factor '0'"));
  EXPECT_EQ(d.facts(0x2002, 0).unit, "");
  EXPECT_FALSE(d.facts(0x2002, 0).factor);
}

// heig-vd-iai's example.eds and others: "Voltage UB Power [mV]". Only a short
// token counts; parentheses only for a known unit symbol, since vendors
// write words there.
TEST(EdsUnits, UnitAtTheEndOfTheName) {
  const auto d = parse(file_with(var("2000", "Voltage UB Power [mV]") + var("2001", "Gain Kp [mV/A]") +
                                     var("2002", "LmTable[9]") + var("2003", "Mode [see manual page 3]") +
                                     var("2004", "Frequency (Hz)") + var("2005", "Vendor value (manufacturer specific)") +
                                     var("2006", "Mapping (tx)") + var("2007", "Integrator time [?s]") +
                                     var("2008", "Temperature (\u00B0C)") + var("2009", "Supply [mV]", "Unit=V\n"),
                                 {0x2000, 0x2001, 0x2002, 0x2003, 0x2004, 0x2005, 0x2006, 0x2007, 0x2008, 0x2009}));
  EXPECT_EQ(d.facts(0x2000, 0).unit, "mV");
  EXPECT_EQ(d.facts(0x2001, 0).unit, "mV/A");
  EXPECT_EQ(d.facts(0x2002, 0).unit, "") << "an array index is no unit";
  EXPECT_EQ(d.facts(0x2003, 0).unit, "") << "words are no unit";
  EXPECT_EQ(d.facts(0x2004, 0).unit, "Hz");
  EXPECT_EQ(d.facts(0x2005, 0).unit, "");
  EXPECT_EQ(d.facts(0x2006, 0).unit, "");
  EXPECT_EQ(d.facts(0x2007, 0).unit, "") << "a '?' is a character the file lost, not a unit";
  EXPECT_EQ(d.facts(0x2008, 0).unit, "\u00B0C");
  EXPECT_EQ(d.facts(0x2009, 0).unit, "V") << "an explicit Unit= wins over the name";
  // The name itself is kept as written (Sparkplug metric names come from it).
  EXPECT_EQ(d.od.find(0x2000, 0)->name, "Voltage UB Power [mV]");
}

// A sub-object section inherits nothing from its object section (as for
// every other key); CompactSubObj entries are described by the object
// section, so they share its unit.
TEST(EdsUnits, SubObjectsAndCompactObjects) {
  const std::string record =
      "[2100]\nParameterName=Inputs\nObjectType=0x9\nSubNumber=3\nUnit=V\n"
      "[2100sub0]\nParameterName=Highest\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue=2\n"
      "[2100sub1]\nParameterName=Input 1\nObjectType=0x7\nDataType=0x0003\nAccessType=ro\nUnit=mV\nFactor=0.5\n"
      "[2100sub2]\nParameterName=Input 2 [mA]\nObjectType=0x7\nDataType=0x0003\nAccessType=ro\n";
  const std::string compact =
      "[2200]\nParameterName=Speed\nObjectType=0x8\nDataType=0x0003\nAccessType=ro\nCompactSubObj=2\nUnit=rpm\n";
  const auto d = parse(file_with(record + compact, {0x2100, 0x2200}));
  EXPECT_EQ(d.facts(0x2100, 0).unit, "");
  EXPECT_EQ(d.facts(0x2100, 1).unit, "mV");
  EXPECT_EQ(d.facts(0x2100, 1).factor, 0.5);
  EXPECT_EQ(d.facts(0x2100, 2).unit, "mA");
  EXPECT_FALSE(d.facts(0x2100, 2).factor);
  EXPECT_EQ(d.facts(0x2200, 0).unit, "") << "sub 0 is the count, not a speed";
  EXPECT_EQ(d.facts(0x2200, 1).unit, "rpm");
  EXPECT_EQ(d.facts(0x2200, 2).unit, "rpm");
}

// The project's example devices carry units where their values are physical,
// so the demo dashboard shows them (CiA 401 analog inputs, CiA 402 velocity).
TEST(EdsUnits, ExampleDevicesHaveUnits) {
  const auto io = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  EXPECT_EQ(io.facts(0x6401, 1).unit, "mV");
  EXPECT_EQ(io.facts(0x6411, 1).unit, "mV");
  EXPECT_EQ(io.facts(0x6000, 1).unit, "") << "digital inputs are bit patterns";
  const auto drive = load_device_description(deploy_eds("cia402-drive.eds"), 5);
  EXPECT_EQ(drive.facts(0x606C, 0).unit, "rpm");
  EXPECT_EQ(drive.facts(0x60FF, 0).unit, "rpm");
}

// Vendor files from the public corpus beside the checkout (not copied into
// the repository).
TEST(EdsUnits, VendorCorpusFiles) {
  const auto corpus = source_dir() / ".." / "shared" / "eds-corpus";
  const auto curtis = corpus / "victronenergy+dbus-canopen-motordrive" / "tools" / "simulators" / "curtis_f.eds";
  const auto sample = corpus / "christiansandberg+canopen" / "test" / "sample.eds";
  if (!std::filesystem::exists(curtis) || !std::filesystem::exists(sample)) GTEST_SKIP() << corpus << " not found";

  const auto c = load_device_description(curtis, 5);
  EXPECT_EQ(c.facts(0x338F, 0).unit, "A");  // Battery Current, Unit=0.01A per unit
  EXPECT_EQ(c.facts(0x338F, 0).factor, 0.01);
  EXPECT_EQ(c.facts(0x34C1, 0).unit, "V");  // Battery Voltage, Unit=0.01V per unit
  EXPECT_EQ(c.facts(0x34C1, 0).factor, 0.01);
  EXPECT_EQ(c.facts(0x352F, 0).unit, "rpm");  // Motor Speed
  EXPECT_FALSE(c.facts(0x352F, 0).factor);

  const auto text = read_text(sample);
  const auto s = load_device_description(sample, 5);
  EXPECT_EQ(s.facts(0x3050, 1).unit, "mV");
  EXPECT_EQ(s.facts(0x3050, 1).factor, 0.1);
  EXPECT_EQ(s.facts(0x3050, 2).unit, "");  // Unit= empty, Factor=ERROR
  EXPECT_FALSE(s.facts(0x3050, 2).factor);
  const auto line = line_of(text, "Factor=ERROR");
  ASSERT_NE(line, 0u);
  EXPECT_TRUE(has_warning(s, sample.string() + ":" + std::to_string(line) + ": Factor 'ERROR'"));
}

}  // namespace
}  // namespace canopen::eds::test
