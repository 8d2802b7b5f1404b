// The Sparkplug payload writer, checked with protobuf's generated parser of
// proto/sparkplug_b.proto; the command decoder; the contract's datatype
// mapping (api-contract.md "Sparkplug B"; facts A.7 for the wire mapping).
#include "sparkplug/payload.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "unit/gateway/sparkplug/sparkplug_support.hpp"

namespace gateway::sparkplug {
namespace {

using sparkplug_test::parse;
using CT = canopen::DataType;

// The contract: b Boolean, i8..i64 Int8..Int64, u8..u64 UInt8..UInt64,
// 24/40/48/56-bit to the next wider, r32 Float, r64 Double, vs String,
// os/d Bytes, t DateTime.
TEST(SparkplugDatatype, CanopenTypesMapAsTheContractSays) {
  const std::pair<CT, DataType> cases[] = {
      {CT::Boolean, DataType::Boolean},      {CT::Integer8, DataType::Int8},
      {CT::Integer16, DataType::Int16},      {CT::Integer24, DataType::Int32},
      {CT::Integer32, DataType::Int32},      {CT::Integer40, DataType::Int64},
      {CT::Integer48, DataType::Int64},      {CT::Integer56, DataType::Int64},
      {CT::Integer64, DataType::Int64},      {CT::Unsigned8, DataType::UInt8},
      {CT::Unsigned16, DataType::UInt16},    {CT::Unsigned24, DataType::UInt32},
      {CT::Unsigned32, DataType::UInt32},    {CT::Unsigned40, DataType::UInt64},
      {CT::Unsigned48, DataType::UInt64},    {CT::Unsigned56, DataType::UInt64},
      {CT::Unsigned64, DataType::UInt64},    {CT::Real32, DataType::Float},
      {CT::Real64, DataType::Double},        {CT::VisibleString, DataType::String},
      {CT::OctetString, DataType::Bytes},    {CT::Domain, DataType::Bytes},
      {CT::TimeOfDay, DataType::DateTime},
      // Not in the contract; the facts' table (A.13): us as String (UTF-8), td as Int64 ms.
      {CT::UnicodeString, DataType::String}, {CT::TimeDifference, DataType::Int64},
  };
  for (const auto& [c, s] : cases) EXPECT_EQ(datatype_of(c), s) << canopen::cia309_name(c);
}

// Facts A.7: the DataType enum values, fixed by the specification.
TEST(SparkplugDatatype, EnumValuesAreTheSpecifications) {
  EXPECT_EQ(sparkplug_test::pb::Int8, 1);
  EXPECT_EQ(sparkplug_test::pb::UInt64, 8);
  EXPECT_EQ(sparkplug_test::pb::Boolean, 11);
  EXPECT_EQ(sparkplug_test::pb::DateTime, 13);
  EXPECT_EQ(sparkplug_test::pb::Bytes, 17);
  EXPECT_EQ(sparkplug_test::pb::DateTimeArray, 34);
  EXPECT_EQ(static_cast<int>(DataType::String), sparkplug_test::pb::String);
  EXPECT_EQ(static_cast<int>(DataType::Template), sparkplug_test::pb::Template);
}

Metric object_metric() {
  Metric m;
  m.name = "Digital Inputs/Input 1";
  m.alias = 42;
  m.datatype = DataType::UInt8;
  m.value = std::uint64_t{0xA5};
  m.timestamp = 1'767'225'600'123;
  m.object = ObjectRef{0x6000, 1};
  return m;
}

// Birth form (spec ch6 "Metric"): name, alias, timestamp, datatype, value
// and the index/subIndex properties (contract: index UInt16, subIndex UInt8).
TEST(SparkplugPayload, BirthMetricRoundTripsThroughTheGeneratedParser) {
  std::string out;
  append_header(out, 1000);
  append_metric(out, object_metric(), Form::Birth);
  append_seq(out, 7);
  const auto p = parse(out);
  ASSERT_NE(p.seq(), 9999U) << "not a Payload";
  EXPECT_EQ(p.timestamp(), 1000U);
  EXPECT_EQ(p.seq(), 7U);
  ASSERT_EQ(p.metrics_size(), 1);
  const auto& m = p.metrics(0);
  EXPECT_EQ(m.name(), "Digital Inputs/Input 1");
  EXPECT_EQ(m.alias(), 42U);
  EXPECT_EQ(m.timestamp(), 1'767'225'600'123U);
  EXPECT_EQ(m.datatype(), static_cast<unsigned>(sparkplug_test::pb::UInt8));
  EXPECT_EQ(m.int_value(), 0xA5U);
  ASSERT_TRUE(m.has_properties());
  ASSERT_EQ(m.properties().keys_size(), 2);
  ASSERT_EQ(m.properties().values_size(), 2);
  EXPECT_EQ(m.properties().keys(0), "index");
  EXPECT_EQ(m.properties().values(0).type(), static_cast<unsigned>(sparkplug_test::pb::UInt16));
  EXPECT_EQ(m.properties().values(0).int_value(), 0x6000U);
  EXPECT_EQ(m.properties().keys(1), "subIndex");
  EXPECT_EQ(m.properties().values(1).type(), static_cast<unsigned>(sparkplug_test::pb::UInt8));
  EXPECT_EQ(m.properties().values(1).int_value(), 1U);
  // And byte for byte what the generated serializer writes for the same message.
  EXPECT_EQ(p.SerializeAsString(), out);
}

// Data form: with an alias only the alias, no name, no datatype, no
// properties (spec ch6 payloads-alias-*, "datatype SHOULD NOT" in DATA).
TEST(SparkplugPayload, DataMetricCarriesTheAliasOnlyAndNoDatatype) {
  std::string out;
  append_header(out, 1);
  append_metric(out, object_metric(), Form::Data);
  const auto p = parse(out);
  ASSERT_EQ(p.metrics_size(), 1);
  const auto& m = p.metrics(0);
  EXPECT_FALSE(m.has_name());
  EXPECT_EQ(m.alias(), 42U);
  EXPECT_FALSE(m.has_datatype());
  EXPECT_FALSE(m.has_properties());
  EXPECT_EQ(m.int_value(), 0xA5U);
  EXPECT_FALSE(p.has_seq()) << "no seq appended";
}

TEST(SparkplugPayload, DataMetricWithoutAliasCarriesTheName) {
  Metric m = object_metric();
  m.alias.reset();
  std::string out;
  append_metric(out, m, Form::Data);
  const auto p = parse(out);
  ASSERT_EQ(p.metrics_size(), 1);
  EXPECT_EQ(p.metrics(0).name(), m.name);
  EXPECT_FALSE(p.metrics(0).has_alias());
}

// Spec ch6 "Datatype Details", as Tahu Java and Ignition read it (contract,
// issue 27 items 5 and 6): Int8..Int32, UInt8 and UInt16 in int_value, the
// signed ones sign-extended to 32 bits (-1234 as Int16 is 0xFFFFFB2E, not
// 0xFB2E, which Tahu JS reads as 64302); UInt32, Int64, UInt64 and DateTime
// in long_value; a null value is is_null with no value.
TEST(SparkplugPayload, ValuesGoInTheFieldTheirDatatypeNames) {
  struct Case {
    DataType t;
    Value v;
  };
  const Case cases[] = {
      {DataType::Int8, std::int64_t{-1}},
      {DataType::Int16, std::int64_t{-1234}},
      {DataType::Int32, std::int64_t{-3}},
      {DataType::Int64, std::int64_t{-4}},
      {DataType::UInt32, std::uint64_t{0xFFFFFFFF}},
      {DataType::UInt64, std::numeric_limits<std::uint64_t>::max()},
      {DataType::DateTime, std::uint64_t{1'767'225'600'000}},
      {DataType::Float, 1.5f},
      {DataType::Double, -2.25},
      {DataType::Boolean, true},
      {DataType::String, std::string("Operational")},
      {DataType::Bytes, canopen::Bytes{0x00, 0xFF, 0x10}},
      {DataType::String, std::monostate{}},
  };
  std::string out;
  for (const auto& c : cases) {
    Metric m;
    m.name = "m";
    m.datatype = c.t;
    m.value = c.v;
    append_metric(out, m, Form::Birth);
  }
  const auto p = parse(out);
  ASSERT_EQ(p.metrics_size(), static_cast<int>(std::size(cases)));
  EXPECT_EQ(p.metrics(0).int_value(), 0xFFFFFFFFU);
  EXPECT_EQ(p.metrics(1).int_value(), 0xFFFFFB2EU);
  EXPECT_EQ(static_cast<std::int32_t>(p.metrics(1).int_value()), -1234) << "as Tahu Java reads it";
  EXPECT_EQ(p.metrics(2).int_value(), 0xFFFFFFFDU);
  EXPECT_EQ(p.metrics(3).long_value(), static_cast<std::uint64_t>(-4));
  EXPECT_EQ(p.metrics(4).value_case(), sparkplug_test::pb::Payload::Metric::kLongValue);
  EXPECT_EQ(p.metrics(4).long_value(), 0xFFFFFFFFU);
  EXPECT_EQ(p.metrics(5).long_value(), std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(p.metrics(6).long_value(), 1'767'225'600'000U);
  EXPECT_EQ(p.metrics(7).float_value(), 1.5f);
  EXPECT_EQ(p.metrics(8).double_value(), -2.25);
  EXPECT_TRUE(p.metrics(9).boolean_value());
  EXPECT_EQ(p.metrics(10).string_value(), "Operational");
  EXPECT_EQ(p.metrics(11).bytes_value(), std::string("\x00\xFF\x10", 3));
  EXPECT_TRUE(p.metrics(12).is_null());
  EXPECT_EQ(p.metrics(12).value_case(), sparkplug_test::pb::Payload::Metric::VALUE_NOT_SET);
  EXPECT_EQ(p.SerializeAsString(), out);
}

// NCMD/DCMD written by a host with the generated code, as Tahu does.
TEST(SparkplugPayload, CommandsDecodeWithNameAliasAndWireValue) {
  sparkplug_test::pb::Payload p;
  p.set_timestamp(5);
  auto* a = p.add_metrics();
  a->set_name("Node Control/Rebirth");
  a->set_boolean_value(true);
  auto* b = p.add_metrics();
  b->set_alias(42);
  b->set_int_value(0xFFFFFFFF);  // Int8 -1 as Tahu Java writes it
  auto* c = p.add_metrics();
  c->set_name("Name");
  c->set_string_value("x");
  const auto cmd = decode_command(p.SerializeAsString());
  ASSERT_TRUE(cmd);
  EXPECT_EQ(cmd->timestamp, 5U);
  ASSERT_EQ(cmd->metrics.size(), 3U);
  EXPECT_EQ(cmd->metrics[0].name, "Node Control/Rebirth");
  EXPECT_EQ(cmd->metrics[0].value, Value{true});
  EXPECT_EQ(cmd->metrics[1].alias, 42U);
  EXPECT_EQ(typed_value(cmd->metrics[1].value, DataType::Int8), Value{std::int64_t{-1}});
  EXPECT_EQ(cmd->metrics[2].value, Value{std::string("x")});
  EXPECT_FALSE(decode_command("\xFF\xFF\xFF"));
}

// Both ways hosts write a negative Int8/Int16 in int_value are accepted
// (width: Tahu Python; sign-extended to 32 bits: Tahu Java); values that fit
// neither are refused rather than truncated.
TEST(SparkplugPayload, TypedValueChecksTheRangeOfTheMetricsType) {
  EXPECT_EQ(typed_value(std::uint64_t{255}, DataType::Int8), Value{std::int64_t{-1}});
  EXPECT_EQ(typed_value(std::uint64_t{0xFFFFFF80}, DataType::Int8), Value{std::int64_t{-128}});
  EXPECT_EQ(typed_value(std::uint64_t{300}, DataType::Int8), std::nullopt);
  EXPECT_EQ(typed_value(std::uint64_t{0xFFFF8000}, DataType::Int16), Value{std::int64_t{-32768}});
  EXPECT_EQ(typed_value(std::uint64_t{0x80000000}, DataType::Int32), Value{std::int64_t{INT32_MIN}});
  EXPECT_EQ(typed_value(std::uint64_t{256}, DataType::UInt8), std::nullopt);
  EXPECT_EQ(typed_value(std::uint64_t{65535}, DataType::UInt16), Value{std::uint64_t{65535}});
  EXPECT_EQ(typed_value(true, DataType::Int32), std::nullopt);
  EXPECT_EQ(typed_value(1.0, DataType::Float), std::nullopt);
  EXPECT_EQ(typed_value(1.0f, DataType::Float), Value{1.0f});
}

// Issue 27 items 5 and 6: a DCMD is accepted in either form hosts write:
// Int16 -1234 in its own width (Tahu JS, Python) or sign-extended (Tahu
// Java), a UInt32 in int_value (older hosts) or long_value (Tahu, Ignition).
TEST(SparkplugPayload, CommandsAreAcceptedInEitherFormHostsWrite) {
  sparkplug_test::pb::Payload p;
  p.set_timestamp(5);
  p.add_metrics()->set_int_value(0xFB2E);
  p.add_metrics()->set_int_value(0xFFFFFB2E);
  p.add_metrics()->set_int_value(0xDEADBEEF);
  p.add_metrics()->set_long_value(0xDEADBEEF);
  p.add_metrics()->set_long_value(0x1'0000'0000);
  const auto cmd = decode_command(p.SerializeAsString());
  ASSERT_TRUE(cmd);
  ASSERT_EQ(cmd->metrics.size(), 5U);
  EXPECT_EQ(typed_value(cmd->metrics[0].value, DataType::Int16), Value{std::int64_t{-1234}});
  EXPECT_EQ(typed_value(cmd->metrics[1].value, DataType::Int16), Value{std::int64_t{-1234}});
  EXPECT_EQ(typed_value(cmd->metrics[2].value, DataType::UInt32), Value{std::uint64_t{0xDEADBEEF}});
  EXPECT_EQ(typed_value(cmd->metrics[3].value, DataType::UInt32), Value{std::uint64_t{0xDEADBEEF}});
  EXPECT_EQ(typed_value(cmd->metrics[4].value, DataType::UInt32), std::nullopt) << "too wide: refused, not truncated";
}

}  // namespace
}  // namespace gateway::sparkplug
