// Values <-> JSON with the contract's rules (../shared/api-contract.md):
// numbers up to 53 bits are JSON numbers, wider ones strings, decided per type.
#include <gtest/gtest.h>

#include <boost/json/parse.hpp>
#include <boost/json/serialize.hpp>
#include <cmath>
#include <limits>

#include "canopen/json_value.hpp"
#include "support/value_samples.hpp"
#include "canopen/sdo/abort.hpp"

namespace canopen {
namespace {

namespace json = boost::json;

std::error_code code(SdoAbort a) { return make_error_code(a); }

std::string to_json_text(const Value& v) { return json::serialize(value_to_json(v)); }

Value from(DataType t, std::string_view json_text) {
  auto r = value_from_json(t, json::parse(json_text));
  EXPECT_TRUE(r.ok()) << json_text << ": " << (r.ok() ? "" : r.error().detail);
  return r.ok() ? *r : Value{};
}

Error from_error(DataType t, std::string_view json_text) {
  auto r = value_from_json(t, json::parse(json_text));
  EXPECT_FALSE(r.ok()) << json_text;
  return r.ok() ? Error{} : r.error();
}

TEST(ValueJson, BooleanShape) {
  EXPECT_EQ(to_json_text(Value::of_bool(true)), "true");
  EXPECT_EQ(to_json_text(Value::of_bool(false)), "false");
  EXPECT_EQ(from(DataType::Boolean, "true"), Value::of_bool(true));
  EXPECT_EQ(from(DataType::Boolean, "false"), Value::of_bool(false));
  EXPECT_EQ(from(DataType::Boolean, "1"), Value::of_bool(true));
  EXPECT_EQ(from(DataType::Boolean, "0"), Value::of_bool(false));
  EXPECT_EQ(from(DataType::Boolean, "\"true\""), Value::of_bool(true));
  EXPECT_EQ(from(DataType::Boolean, "\"0\""), Value::of_bool(false));
  EXPECT_EQ(from_error(DataType::Boolean, "2").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::Boolean, "0.5").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::Boolean, "\"yes\"").code, code(SdoAbort::InvalidValue));
  const auto e = from_error(DataType::Boolean, "null");
  EXPECT_EQ(e.code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(e.detail, "expected true, false, 0 or 1 for b, got null");
}

// Every integer type up to 48 bits is a JSON number, from 56 bits a string,
// whatever the value: a field never changes shape.
TEST(ValueJson, IntegerShapeIsDecidedByType) {
  const std::pair<DataType, bool> types[] = {
      {DataType::Integer8, true},    {DataType::Integer16, true},  {DataType::Integer24, true},
      {DataType::Integer32, true},   {DataType::Integer40, true},  {DataType::Integer48, true},
      {DataType::Integer56, false},  {DataType::Integer64, false}, {DataType::Unsigned8, true},
      {DataType::Unsigned16, true},  {DataType::Unsigned24, true}, {DataType::Unsigned32, true},
      {DataType::Unsigned40, true},  {DataType::Unsigned48, true}, {DataType::Unsigned56, false},
      {DataType::Unsigned64, false},
  };
  for (auto [t, number] : types) {
    const bool s = is_signed_integer(t);
    for (int which = 0; which < 3; ++which) {
      const Value v = s ? Value::of_signed(t, which == 0   ? signed_min(t)
                                              : which == 1 ? 0
                                                           : signed_max(t))
                        : Value::of_unsigned(t, which == 0   ? 0
                                                : which == 1 ? 1
                                                             : unsigned_max(t));
      const json::value j = value_to_json(v);
      if (number) {
        EXPECT_TRUE(j.is_int64()) << cia309_name(t) << " " << json::serialize(j);
      } else {
        EXPECT_TRUE(j.is_string()) << cia309_name(t) << " " << json::serialize(j);
      }
      EXPECT_EQ(value_from_json(t, j).value(), v) << cia309_name(t);
      // And through serialized text.
      EXPECT_EQ(value_from_json(t, json::parse(json::serialize(j))).value(), v) << cia309_name(t);
    }
  }
}

TEST(ValueJson, FiftyThreeBitBoundary) {
  // i48/u48 extremes are exact JSON numbers.
  EXPECT_EQ(to_json_text(Value::of_unsigned(DataType::Unsigned48, 281474976710655)), "281474976710655");
  EXPECT_EQ(to_json_text(Value::of_signed(DataType::Integer48, -140737488355328)), "-140737488355328");
  // From 56 bits, decimal strings, even for small values.
  EXPECT_EQ(to_json_text(Value::of_unsigned(DataType::Unsigned56, 1)), "\"1\"");
  EXPECT_EQ(to_json_text(Value::of_unsigned(DataType::Unsigned64, std::numeric_limits<std::uint64_t>::max())),
            "\"18446744073709551615\"");
  EXPECT_EQ(to_json_text(Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::min())),
            "\"-9223372036854775808\"");
  EXPECT_EQ(to_json_text(Value::of_signed(DataType::Integer56, -36028797018963968)), "\"-36028797018963968\"");
  // Wide types also take JSON numbers (exact when the parser gives an integer).
  EXPECT_EQ(from(DataType::Unsigned64, "18446744073709551615"),
            Value::of_unsigned(DataType::Unsigned64, std::numeric_limits<std::uint64_t>::max()));
  EXPECT_EQ(from(DataType::Integer64, "-9223372036854775808"),
            Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::min()));
  EXPECT_EQ(from(DataType::Unsigned56, "\"0xFFFFFFFFFFFFFF\""),
            Value::of_unsigned(DataType::Unsigned56, 0xFFFFFFFFFFFFFF));
}

TEST(ValueJson, IntegersFromJson) {
  EXPECT_EQ(from(DataType::Unsigned16, "4660"), Value::of_unsigned(DataType::Unsigned16, 0x1234));
  EXPECT_EQ(from(DataType::Unsigned16, "\"4660\""), Value::of_unsigned(DataType::Unsigned16, 0x1234));
  EXPECT_EQ(from(DataType::Unsigned16, "\"0x1234\""), Value::of_unsigned(DataType::Unsigned16, 0x1234));
  EXPECT_EQ(from(DataType::Unsigned16, "\"0X12ab\""), Value::of_unsigned(DataType::Unsigned16, 0x12AB));
  EXPECT_EQ(from(DataType::Integer8, "\"-0x80\""), Value::of_signed(DataType::Integer8, -128));
  EXPECT_EQ(from(DataType::Integer8, "-128"), Value::of_signed(DataType::Integer8, -128));
  // Leading zeros in JSON strings are decimal, not octal.
  EXPECT_EQ(from(DataType::Unsigned16, "\"010\""), Value::of_unsigned(DataType::Unsigned16, 10));
  EXPECT_EQ(from(DataType::Integer16, "\"-007\""), Value::of_signed(DataType::Integer16, -7));
  EXPECT_EQ(from(DataType::Unsigned16, "\"000\""), Value::of_unsigned(DataType::Unsigned16, 0));
  // Integral JSON numbers in exponent or fraction form.
  EXPECT_EQ(from(DataType::Unsigned32, "1e3"), Value::of_unsigned(DataType::Unsigned32, 1000));
  EXPECT_EQ(from(DataType::Integer32, "-5.0"), Value::of_signed(DataType::Integer32, -5));
}

TEST(ValueJson, IntegerErrors) {
  auto e = from_error(DataType::Unsigned16, "70000");
  EXPECT_EQ(e.code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(e.detail, "70000 is above 65535 (u16)");
  e = from_error(DataType::Unsigned16, "\"70000\"");
  EXPECT_EQ(e.code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(e.detail, "70000 is above 65535 (u16)");
  e = from_error(DataType::Unsigned8, "-1");
  EXPECT_EQ(e.code, code(SdoAbort::ValueTooLow));
  EXPECT_EQ(e.detail, "-1 is below 0 (u8)");
  e = from_error(DataType::Integer8, "-129");
  EXPECT_EQ(e.code, code(SdoAbort::ValueTooLow));
  EXPECT_EQ(e.detail, "-129 is below -128 (i8)");
  e = from_error(DataType::Unsigned16, "1.5");
  EXPECT_EQ(e.code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(e.detail, "1.5 is not an integer (u16)");
  EXPECT_EQ(from_error(DataType::Unsigned16, "\"1.5\"").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::Unsigned16, "\"\"").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::Unsigned16, "\"12abc\"").code, code(SdoAbort::InvalidValue));
  e = from_error(DataType::Unsigned64, "1e20");
  EXPECT_EQ(e.code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(e.detail, "1e+20 is above 18446744073709551615 (u64)");
  EXPECT_EQ(from_error(DataType::Integer64, "-1e20").code, code(SdoAbort::ValueTooLow));
  EXPECT_EQ(from_error(DataType::Unsigned64, "-1e20").code, code(SdoAbort::ValueTooLow));
  EXPECT_EQ(from_error(DataType::Integer64, "9223372036854775808").code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(from_error(DataType::Unsigned8, "\"-1\"").code, code(SdoAbort::ValueTooLow));
  e = from_error(DataType::Unsigned16, "true");
  EXPECT_EQ(e.code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(e.detail, "expected an integer or a numeric string for u16, got a boolean");
  EXPECT_EQ(from_error(DataType::Integer32, "[1]").detail,
            "expected an integer or a numeric string for i32, got an array");
  EXPECT_EQ(from_error(DataType::Integer32, "{}").detail,
            "expected an integer or a numeric string for i32, got an object");
  EXPECT_EQ(from_error(DataType::Integer32, "null").code, code(SdoAbort::InvalidValue));
}

TEST(ValueJson, Reals) {
  EXPECT_EQ(to_json_text(Value::of_real32(0.1f)), "1E-1");
  EXPECT_EQ(value_to_json(Value::of_real32(0.1f)).as_double(), 0.1);  // shortest float text, not 0.100000001
  EXPECT_EQ(value_to_json(Value::of_real64(0.1)).as_double(), 0.1);
  EXPECT_TRUE(value_to_json(Value::of_real32(2.0f)).is_double());  // a JSON number either way
  EXPECT_EQ(from(DataType::Real32, "0.1"), Value::of_real32(0.1f));
  EXPECT_EQ(from(DataType::Real32, "7"), Value::of_real32(7.0f));
  EXPECT_EQ(from(DataType::Real64, "-7"), Value::of_real64(-7.0));
  EXPECT_EQ(from(DataType::Real64, "18446744073709551615"), Value::of_real64(18446744073709551615.0));
  EXPECT_EQ(from(DataType::Real64, "\"1.5e3\""), Value::of_real64(1500.0));
  EXPECT_EQ(from(DataType::Real32, "\"0x10\""), Value::of_real32(16.0f));
  EXPECT_EQ(from(DataType::Real64, "\"-0x10\""), Value::of_real64(-16.0));
  EXPECT_EQ(from(DataType::Real64, "\"0xFFFFFFFFFFFFFFFF\""), Value::of_real64(18446744073709551615.0));
  EXPECT_EQ(from_error(DataType::Real32, "\"0xZZ\"").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from(DataType::Real32, "3.4028234663852886e38"), Value::of_real32(std::numeric_limits<float>::max()));
  const auto e = from_error(DataType::Real32, "1e39");
  EXPECT_EQ(e.code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(e.detail, "1e+39 is above 3.4028235e+38 (r32)");
  EXPECT_EQ(from_error(DataType::Real32, "-1e39").code, code(SdoAbort::ValueTooLow));
  EXPECT_EQ(from_error(DataType::Real64, "\"x\"").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::Real64, "false").detail,
            "expected a number or a numeric string for r64, got a boolean");
  for (float f : {0.1f, -1e-45f, 3.4028235e38f, 123.456f}) {
    EXPECT_EQ(value_from_json(DataType::Real32, json::parse(to_json_text(Value::of_real32(f)))).value(),
              Value::of_real32(f));
  }
  for (double d : {0.1, 5e-324, 1.7976931348623157e308, -123.456}) {
    EXPECT_EQ(value_from_json(DataType::Real64, json::parse(to_json_text(Value::of_real64(d)))).value(),
              Value::of_real64(d));
  }
}

// JSON has no NaN or infinity: those are strings, and are accepted back.
TEST(ValueJson, NonFiniteReals) {
  EXPECT_EQ(to_json_text(Value::of_real32(std::numeric_limits<float>::quiet_NaN())), "\"nan\"");
  EXPECT_EQ(to_json_text(Value::of_real64(std::numeric_limits<double>::infinity())), "\"inf\"");
  EXPECT_EQ(to_json_text(Value::of_real64(-std::numeric_limits<double>::infinity())), "\"-inf\"");
  EXPECT_TRUE(std::isnan(std::get<float>(from(DataType::Real32, "\"nan\"").data)));
  EXPECT_EQ(from(DataType::Real64, "\"-inf\""), Value::of_real64(-std::numeric_limits<double>::infinity()));
}

TEST(ValueJson, Strings) {
  EXPECT_EQ(to_json_text(Value::of_string("Device \"A\"")), "\"Device \\\"A\\\"\"");
  EXPECT_EQ(from(DataType::VisibleString, "\"Device\""), Value::of_string("Device"));
  EXPECT_EQ(from(DataType::VisibleString, "\" spaced \""), Value::of_string(" spaced "));
  // Bytes that are not UTF-8 are read as Latin-1, so the JSON stays valid.
  EXPECT_EQ(value_to_json(Value::of_string("caf\xE9")).as_string(), "caf\xC3\xA9");
  EXPECT_EQ(value_to_json(Value::of_string("caf\xC3\xA9")).as_string(), "caf\xC3\xA9");
  EXPECT_EQ(from_error(DataType::VisibleString, "5").detail, "expected a string for vs, got a number");

  const Value us{DataType::UnicodeString, std::u16string{u"gr\u00FC\u00DF \U0001F600"}};
  EXPECT_EQ(value_to_json(us).as_string(), "gr\xC3\xBC\xC3\x9F \xF0\x9F\x98\x80");
  EXPECT_EQ(value_from_json(DataType::UnicodeString, value_to_json(us)).value(), us);
  EXPECT_EQ(from(DataType::UnicodeString, "\"\\u00fc\""), (Value{DataType::UnicodeString, std::u16string{u"\u00FC"}}));
  EXPECT_EQ(from_error(DataType::UnicodeString, "[]").code, code(SdoAbort::InvalidValue));
}

TEST(ValueJson, OctetStringAndDomainAsHex) {
  EXPECT_EQ(to_json_text(Value::of_bytes(DataType::OctetString, {0x0A, 0xFF, 0x00})), "\"0aff00\"");
  EXPECT_EQ(to_json_text(Value::of_bytes(DataType::Domain, {})), "\"\"");
  EXPECT_EQ(from(DataType::OctetString, "\"0AFF00\""), Value::of_bytes(DataType::OctetString, {0x0A, 0xFF, 0x00}));
  EXPECT_EQ(from(DataType::Domain, "\"deadBEEF\""), Value::of_bytes(DataType::Domain, {0xDE, 0xAD, 0xBE, 0xEF}));
  EXPECT_EQ(from_error(DataType::OctetString, "\"abc\"").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::OctetString, "\"zz\"").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::Domain, "[1,2]").detail, "expected a hex string for d, got an array");
}

TEST(ValueJson, TimeOfDayAsRfc3339) {
  const Value t{DataType::TimeOfDay, TimeOfDay{36'930'123, 15666}};
  EXPECT_EQ(to_json_text(t), "\"2026-11-22T10:15:30.123Z\"");
  EXPECT_EQ(from(DataType::TimeOfDay, "\"2026-11-22T10:15:30.123Z\""), t);
  EXPECT_EQ(from(DataType::TimeOfDay, "\"2026-11-22T11:15:30.123+01:00\""), t);
  EXPECT_EQ(to_json_text(Value{DataType::TimeOfDay, TimeOfDay{}}), "\"1984-01-01T00:00:00.000Z\"");
  EXPECT_EQ(from_error(DataType::TimeOfDay, "\"1970-01-01T00:00:00Z\"").code, code(SdoAbort::ValueTooLow));
  EXPECT_EQ(from_error(DataType::TimeOfDay, "\"yesterday\"").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::TimeOfDay, "1000").detail, "expected an RFC 3339 string for t, got a number");
}

TEST(ValueJson, TimeDifferenceAsMilliseconds) {
  EXPECT_EQ(to_json_text(Value{DataType::TimeDifference, TimeOfDay{500, 2}}), "172800500");
  const Value max{DataType::TimeDifference, TimeOfDay{86'399'999, 65535}};
  EXPECT_EQ(to_json_text(max), "5662310399999");
  EXPECT_EQ(from(DataType::TimeDifference, "5662310399999"), max);
  EXPECT_EQ(from(DataType::TimeDifference, "172800500"), (Value{DataType::TimeDifference, TimeOfDay{500, 2}}));
  EXPECT_EQ(from(DataType::TimeDifference, "\"172800500\""), (Value{DataType::TimeDifference, TimeOfDay{500, 2}}));
  EXPECT_EQ(from(DataType::TimeDifference, "\"2 500\""), (Value{DataType::TimeDifference, TimeOfDay{500, 2}}));
  EXPECT_EQ(from(DataType::TimeDifference, "1e3"), (Value{DataType::TimeDifference, TimeOfDay{1000, 0}}));
  auto e = from_error(DataType::TimeDifference, "5662310400000");
  EXPECT_EQ(e.code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(e.detail, "5662310400000 is above 5662310399999 (td)");
  EXPECT_EQ(from_error(DataType::TimeDifference, "18446744073709551615").code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(from_error(DataType::TimeDifference, "1e20").code, code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(from_error(DataType::TimeDifference, "-1").code, code(SdoAbort::ValueTooLow));
  EXPECT_EQ(from_error(DataType::TimeDifference, "1.5").code, code(SdoAbort::InvalidValue));
  EXPECT_EQ(from_error(DataType::TimeDifference, "true").code, code(SdoAbort::InvalidValue));
}

TEST(ValueJson, EveryTypeRoundTrips) {
  const auto& samples = test::kEveryTypeSamples;
  for (auto [t, text] : samples) {
    const Value v = parse_value(t, text).value();
    const std::string serialized = to_json_text(v);
    auto back = value_from_json(t, json::parse(serialized));
    ASSERT_TRUE(back.ok()) << cia309_name(t) << " " << serialized << ": " << back.error().detail;
    EXPECT_EQ(*back, v) << cia309_name(t) << " " << serialized;
  }
}

TEST(ValueJson, UnknownTypeIsRejected) {
  EXPECT_EQ(value_from_json(static_cast<DataType>(0x0020), json::value("x")).code(), code(SdoAbort::InvalidValue));
}

}  // namespace
}  // namespace canopen
