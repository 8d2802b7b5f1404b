// CiA 301 7.1 data types: names, sizes, transfer syntax, text and limits.
#include "canopen/types.hpp"
#include "support/value_samples.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>

#include "canopen/sdo/abort.hpp"

namespace canopen {
namespace {

constexpr DataType kAllTypes[] = {
    DataType::Boolean,        DataType::Integer8,      DataType::Integer16,   DataType::Integer24,
    DataType::Integer32,      DataType::Integer40,     DataType::Integer48,   DataType::Integer56,
    DataType::Integer64,      DataType::Unsigned8,     DataType::Unsigned16,  DataType::Unsigned24,
    DataType::Unsigned32,     DataType::Unsigned40,    DataType::Unsigned48,  DataType::Unsigned56,
    DataType::Unsigned64,     DataType::Real32,        DataType::Real64,      DataType::TimeOfDay,
    DataType::TimeDifference, DataType::VisibleString, DataType::OctetString, DataType::UnicodeString,
    DataType::Domain,
};

constexpr DataType kSigned[] = {DataType::Integer8,  DataType::Integer16, DataType::Integer24, DataType::Integer32,
                                DataType::Integer40, DataType::Integer48, DataType::Integer56, DataType::Integer64};
constexpr DataType kUnsigned[] = {DataType::Unsigned8,  DataType::Unsigned16, DataType::Unsigned24,
                                  DataType::Unsigned32, DataType::Unsigned40, DataType::Unsigned48,
                                  DataType::Unsigned56, DataType::Unsigned64};

std::error_code code(SdoAbort a) { return make_error_code(a); }

Bytes enc(const Value& v) { return encode(v); }

Value dec(DataType t, const Bytes& b) {
  auto r = decode(t, b);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().detail);
  return r.ok() ? *r : Value{};
}

Value parse(DataType t, std::string_view text) {
  auto r = parse_value(t, text);
  EXPECT_TRUE(r.ok()) << text << ": " << (r.ok() ? "" : r.error().detail);
  return r.ok() ? *r : Value{};
}

std::error_code parse_error(DataType t, std::string_view text, std::string* detail = nullptr) {
  auto r = parse_value(t, text);
  if (r.ok()) return {};
  if (detail) *detail = r.error().detail;
  return r.code();
}

std::int64_t unix_ms(int y, unsigned m, unsigned d, std::int64_t ms_of_day = 0) {
  using namespace std::chrono;
  return sys_days{year{y} / month{m} / day{d}}.time_since_epoch().count() * 86'400'000 + ms_of_day;
}

// ---- names (CiA 301 table 44, CiA 309-3) ----

TEST(TypeNames, Cia309NamesMapBothWays) {
  const std::pair<DataType, std::string_view> names[] = {
      {DataType::Boolean, "b"},        {DataType::Integer8, "i8"},    {DataType::Integer16, "i16"},
      {DataType::Integer24, "i24"},    {DataType::Integer32, "i32"},  {DataType::Integer40, "i40"},
      {DataType::Integer48, "i48"},    {DataType::Integer56, "i56"},  {DataType::Integer64, "i64"},
      {DataType::Unsigned8, "u8"},     {DataType::Unsigned16, "u16"}, {DataType::Unsigned24, "u24"},
      {DataType::Unsigned32, "u32"},   {DataType::Unsigned40, "u40"}, {DataType::Unsigned48, "u48"},
      {DataType::Unsigned56, "u56"},   {DataType::Unsigned64, "u64"}, {DataType::Real32, "r32"},
      {DataType::Real64, "r64"},       {DataType::TimeOfDay, "t"},    {DataType::TimeDifference, "td"},
      {DataType::VisibleString, "vs"}, {DataType::OctetString, "os"}, {DataType::UnicodeString, "us"},
      {DataType::Domain, "d"},
  };
  for (auto [t, n] : names) {
    EXPECT_EQ(cia309_name(t), n);
    EXPECT_EQ(parse_type_name(n), t) << n;
  }
}

TEST(TypeNames, StandardNamesMapBothWaysCaseInsensitive) {
  const std::pair<DataType, std::string_view> names[] = {
      {DataType::Boolean, "BOOLEAN"},
      {DataType::Integer8, "INTEGER8"},
      {DataType::Integer16, "INTEGER16"},
      {DataType::Integer24, "INTEGER24"},
      {DataType::Integer32, "INTEGER32"},
      {DataType::Integer40, "INTEGER40"},
      {DataType::Integer48, "INTEGER48"},
      {DataType::Integer56, "INTEGER56"},
      {DataType::Integer64, "INTEGER64"},
      {DataType::Unsigned8, "UNSIGNED8"},
      {DataType::Unsigned16, "UNSIGNED16"},
      {DataType::Unsigned24, "UNSIGNED24"},
      {DataType::Unsigned32, "UNSIGNED32"},
      {DataType::Unsigned40, "UNSIGNED40"},
      {DataType::Unsigned48, "UNSIGNED48"},
      {DataType::Unsigned56, "UNSIGNED56"},
      {DataType::Unsigned64, "UNSIGNED64"},
      {DataType::Real32, "REAL32"},
      {DataType::Real64, "REAL64"},
      {DataType::TimeOfDay, "TIME_OF_DAY"},
      {DataType::TimeDifference, "TIME_DIFFERENCE"},
      {DataType::VisibleString, "VISIBLE_STRING"},
      {DataType::OctetString, "OCTET_STRING"},
      {DataType::UnicodeString, "UNICODE_STRING"},
      {DataType::Domain, "DOMAIN"},
  };
  for (auto [t, n] : names) {
    EXPECT_EQ(standard_name(t), n);
    EXPECT_EQ(parse_type_name(n), t) << n;
    std::string lower(n);
    for (auto& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    EXPECT_EQ(parse_type_name(lower), t) << lower;
  }
  EXPECT_EQ(parse_type_name("Unsigned16"), DataType::Unsigned16);
}

TEST(TypeNames, UnknownNamesAreRejected) {
  for (std::string_view n : {"", "u", "u12", "x8", "UNSIGNED", "UNSIGNED12", "VOID8", "i16 ", " u8", "REAL"}) {
    EXPECT_EQ(parse_type_name(n), std::nullopt) << n;
  }
}

TEST(TypeNames, DataTypeIndexes) {
  for (auto t : kAllTypes) EXPECT_EQ(data_type_from_index(static_cast<std::uint16_t>(t)), t);
  // 0000h, 000Eh (reserved), 0017h (reserved), 0020h (PDO_COMMUNICATION_PARAMETER) and beyond.
  for (int i : {0x0000, 0x000E, 0x0017, 0x001C, 0x0020, 0x0021, 0x0040, 0xFFFF}) {
    EXPECT_EQ(data_type_from_index(static_cast<std::uint16_t>(i)), std::nullopt) << i;
  }
  EXPECT_EQ(data_type_from_index(0x0007), DataType::Unsigned32);
}

// ---- sizes ----

TEST(TypeSizes, FixedAndPdoSizes) {
  const std::pair<DataType, std::size_t> sizes[] = {
      {DataType::Boolean, 1},        {DataType::Integer8, 1},   {DataType::Integer16, 2},  {DataType::Integer24, 3},
      {DataType::Integer32, 4},      {DataType::Integer40, 5},  {DataType::Integer48, 6},  {DataType::Integer56, 7},
      {DataType::Integer64, 8},      {DataType::Unsigned8, 1},  {DataType::Unsigned16, 2}, {DataType::Unsigned24, 3},
      {DataType::Unsigned32, 4},     {DataType::Unsigned40, 5}, {DataType::Unsigned48, 6}, {DataType::Unsigned56, 7},
      {DataType::Unsigned64, 8},     {DataType::Real32, 4},     {DataType::Real64, 8},     {DataType::TimeOfDay, 6},
      {DataType::TimeDifference, 6},
  };
  for (auto [t, s] : sizes) {
    EXPECT_EQ(fixed_size(t), s) << standard_name(t);
    EXPECT_FALSE(is_variable_length(t));
    EXPECT_EQ(pdo_bit_size(t), t == DataType::Boolean ? 1u : s * 8) << standard_name(t);
  }
  for (auto t : {DataType::VisibleString, DataType::OctetString, DataType::UnicodeString, DataType::Domain}) {
    EXPECT_EQ(fixed_size(t), std::nullopt);
    EXPECT_TRUE(is_variable_length(t));
    EXPECT_EQ(pdo_bit_size(t), 0u);
  }
}

TEST(TypeSizes, Classification) {
  for (auto t : kAllTypes) {
    const bool s = std::find(std::begin(kSigned), std::end(kSigned), t) != std::end(kSigned);
    const bool u = std::find(std::begin(kUnsigned), std::end(kUnsigned), t) != std::end(kUnsigned);
    EXPECT_EQ(is_signed_integer(t), s) << standard_name(t);
    EXPECT_EQ(is_unsigned_integer(t), u) << standard_name(t);
    EXPECT_EQ(is_real(t), t == DataType::Real32 || t == DataType::Real64);
  }
}

// 7.1.4.5 / 7.1.4.6: ranges 0..2^n-1 and -2^(n-1)..2^(n-1)-1.
TEST(TypeRanges, MinMax) {
  EXPECT_EQ(signed_min(DataType::Integer8), -128);
  EXPECT_EQ(signed_max(DataType::Integer8), 127);
  EXPECT_EQ(signed_min(DataType::Integer24), -8388608);
  EXPECT_EQ(signed_max(DataType::Integer24), 8388607);
  EXPECT_EQ(signed_min(DataType::Integer40), -549755813888);
  EXPECT_EQ(signed_max(DataType::Integer48), 140737488355327);
  EXPECT_EQ(signed_min(DataType::Integer56), -36028797018963968);
  EXPECT_EQ(signed_min(DataType::Integer64), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(signed_max(DataType::Integer64), std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(unsigned_max(DataType::Unsigned8), 255u);
  EXPECT_EQ(unsigned_max(DataType::Unsigned24), 16777215u);
  EXPECT_EQ(unsigned_max(DataType::Unsigned40), 1099511627775u);
  EXPECT_EQ(unsigned_max(DataType::Unsigned56), 72057594037927935u);
  EXPECT_EQ(unsigned_max(DataType::Unsigned64), std::numeric_limits<std::uint64_t>::max());
  // Cross queries stay consistent.
  EXPECT_EQ(signed_min(DataType::Unsigned16), 0);
  EXPECT_EQ(signed_max(DataType::Unsigned16), 65535);
  EXPECT_EQ(signed_max(DataType::Unsigned64), std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(unsigned_max(DataType::Integer16), 32767u);
}

TEST(TypeValues, ZeroOfEveryType) {
  for (auto t : kAllTypes) {
    const Value z = Value::zero(t);
    EXPECT_EQ(z.type, t);
    EXPECT_EQ(encode(z).size(), fixed_size(t).value_or(0)) << standard_name(t);
    EXPECT_EQ(dec(t, encode(z)), z) << standard_name(t);
  }
  EXPECT_EQ(Value::zero(DataType::Integer8).data, ValueData{std::int64_t{0}});
  EXPECT_EQ(Value::zero(DataType::Unsigned8).data, ValueData{std::uint64_t{0}});
  EXPECT_EQ(Value::zero(DataType::Real32).data, ValueData{0.0f});
  EXPECT_EQ(Value::zero(DataType::UnicodeString).data, ValueData{std::u16string{}});
}

// ---- 7.1.3.2 transfer syntax: little-endian, exactly n/8 bytes ----

TEST(TransferSyntax, Unsigned_7_1_4_5) {
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned16, 0x1234)), (Bytes{0x34, 0x12}));
  // The standard's example: 266 = 10Ah as UNSIGNED16 is 0Ah 01h.
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned16, 266)), (Bytes{0x0A, 0x01}));
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned8, 0xAB)), (Bytes{0xAB}));
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned24, 0x123456)), (Bytes{0x56, 0x34, 0x12}));
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned32, 0x12345678)), (Bytes{0x78, 0x56, 0x34, 0x12}));
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned40, 0x123456789A)), (Bytes{0x9A, 0x78, 0x56, 0x34, 0x12}));
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned48, 0xFFFFFFFFFFFF)), (Bytes(6, 0xFF)));
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned56, 0x01020304050607)),
            (Bytes{0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01}));
  EXPECT_EQ(enc(Value::of_unsigned(DataType::Unsigned64, 0x0102030405060708)),
            (Bytes{0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01}));
  EXPECT_EQ(dec(DataType::Unsigned24, {0xFF, 0xFF, 0xFF}), Value::of_unsigned(DataType::Unsigned24, 0xFFFFFF));
  EXPECT_EQ(dec(DataType::Unsigned56, Bytes(7, 0xFF)), Value::of_unsigned(DataType::Unsigned56, 0xFFFFFFFFFFFFFF));
}

TEST(TransferSyntax, SignedTwosComplement_7_1_4_6) {
  // The standard's example: -266 = FEF6h as INTEGER16 is F6h FEh.
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer16, -266)), (Bytes{0xF6, 0xFE}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer8, -1)), (Bytes{0xFF}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer24, -1)), (Bytes{0xFF, 0xFF, 0xFF}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer24, -8388608)), (Bytes{0x00, 0x00, 0x80}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer24, 8388607)), (Bytes{0xFF, 0xFF, 0x7F}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer40, signed_min(DataType::Integer40))),
            (Bytes{0x00, 0x00, 0x00, 0x00, 0x80}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer40, signed_max(DataType::Integer40))),
            (Bytes{0xFF, 0xFF, 0xFF, 0xFF, 0x7F}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer48, signed_min(DataType::Integer48))),
            (Bytes{0x00, 0x00, 0x00, 0x00, 0x00, 0x80}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer48, -2)), (Bytes{0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer56, signed_max(DataType::Integer56))),
            (Bytes{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x7F}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer56, signed_min(DataType::Integer56))),
            (Bytes{0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80}));
  EXPECT_EQ(enc(Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::min())),
            (Bytes{0, 0, 0, 0, 0, 0, 0, 0x80}));
  // Sign extension on decode.
  EXPECT_EQ(dec(DataType::Integer24, {0xFF, 0xFF, 0xFF}), Value::of_signed(DataType::Integer24, -1));
  EXPECT_EQ(dec(DataType::Integer24, {0x00, 0x00, 0x80}), Value::of_signed(DataType::Integer24, -8388608));
  EXPECT_EQ(dec(DataType::Integer40, {0xFF, 0xFF, 0xFF, 0xFF, 0x7F}),
            Value::of_signed(DataType::Integer40, 549755813887));
  EXPECT_EQ(dec(DataType::Integer48, {0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}), Value::of_signed(DataType::Integer48, -2));
  EXPECT_EQ(dec(DataType::Integer56, {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80}),
            Value::of_signed(DataType::Integer56, signed_min(DataType::Integer56)));
  EXPECT_EQ(dec(DataType::Integer16, {0xF6, 0xFE}), Value::of_signed(DataType::Integer16, -266));
}

TEST(TransferSyntax, EveryIntegerTypeMinMaxRoundTrip) {
  for (auto t : kSigned) {
    for (auto v : {signed_min(t), signed_min(t) + 1, std::int64_t{-1}, std::int64_t{0}, std::int64_t{1},
                   signed_max(t) - 1, signed_max(t)}) {
      const auto x = Value::of_signed(t, v);
      const auto bytes = encode(x);
      ASSERT_EQ(bytes.size(), *fixed_size(t));
      EXPECT_EQ(dec(t, bytes), x) << standard_name(t) << " " << v;
      EXPECT_EQ(parse(t, format_value(x)), x) << standard_name(t) << " " << v;
    }
  }
  for (auto t : kUnsigned) {
    for (auto v : {std::uint64_t{0}, std::uint64_t{1}, unsigned_max(t) - 1, unsigned_max(t)}) {
      const auto x = Value::of_unsigned(t, v);
      const auto bytes = encode(x);
      ASSERT_EQ(bytes.size(), *fixed_size(t));
      EXPECT_EQ(dec(t, bytes), x) << standard_name(t) << " " << v;
      EXPECT_EQ(parse(t, format_value(x)), x) << standard_name(t) << " " << v;
    }
  }
}

TEST(TransferSyntax, Boolean_7_1_4_3) {
  EXPECT_EQ(enc(Value::of_bool(true)), (Bytes{0x01}));
  EXPECT_EQ(enc(Value::of_bool(false)), (Bytes{0x00}));
  EXPECT_EQ(dec(DataType::Boolean, {0x00}), Value::of_bool(false));
  EXPECT_EQ(dec(DataType::Boolean, {0x01}), Value::of_bool(true));
  // Lenient on receive: any non-zero byte is TRUE.
  EXPECT_EQ(dec(DataType::Boolean, {0xFF}), Value::of_bool(true));
}

TEST(TransferSyntax, Real_7_1_4_7) {
  // The standard's example: 6.25 as REAL32 is 00h 00h C8h 40h.
  EXPECT_EQ(enc(Value::of_real32(6.25f)), (Bytes{0x00, 0x00, 0xC8, 0x40}));
  EXPECT_EQ(dec(DataType::Real32, {0x00, 0x00, 0xC8, 0x40}), Value::of_real32(6.25f));
  EXPECT_EQ(enc(Value::of_real64(1.0)), (Bytes{0, 0, 0, 0, 0, 0, 0xF0, 0x3F}));
  EXPECT_EQ(enc(Value::of_real64(-2.0)), (Bytes{0, 0, 0, 0, 0, 0, 0x00, 0xC0}));
  EXPECT_EQ(enc(Value::of_real32(-0.0f)), (Bytes{0, 0, 0, 0x80}));
  EXPECT_EQ(enc(Value::of_real32(std::numeric_limits<float>::infinity())), (Bytes{0, 0, 0x80, 0x7F}));
  for (float f : {std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(),
                  std::numeric_limits<float>::min(), std::numeric_limits<float>::denorm_min(), 0.1f}) {
    EXPECT_EQ(dec(DataType::Real32, encode(Value::of_real32(f))), Value::of_real32(f));
  }
  for (double d : {std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
                   std::numeric_limits<double>::denorm_min(), 0.1}) {
    EXPECT_EQ(dec(DataType::Real64, encode(Value::of_real64(d))), Value::of_real64(d));
  }
  auto nan = decode(DataType::Real32, Bytes{0x00, 0x00, 0xC0, 0x7F});
  ASSERT_TRUE(nan.ok());
  EXPECT_TRUE(std::isnan(std::get<float>(nan->data)));
}

// 7.1.6.5 / 7.1.6.6: UNSIGNED28 ms, VOID4 reserved, UNSIGNED16 days.
TEST(TransferSyntax, TimeOfDay_7_1_6_5) {
  const Value t{DataType::TimeOfDay, TimeOfDay{0x0ABCDEF, 0x1234}};
  EXPECT_EQ(enc(t), (Bytes{0xEF, 0xCD, 0xAB, 0x00, 0x34, 0x12}));
  EXPECT_EQ(dec(DataType::TimeOfDay, {0xEF, 0xCD, 0xAB, 0x00, 0x34, 0x12}), t);
  // The reserved bits are sent as 0 and ignored on receive.
  EXPECT_EQ(dec(DataType::TimeOfDay, {0xEF, 0xCD, 0xAB, 0xF0, 0x34, 0x12}), t);
  EXPECT_EQ(enc(Value{DataType::TimeOfDay, TimeOfDay{0xFFFFFFFF, 0}}), (Bytes{0xFF, 0xFF, 0xFF, 0x0F, 0, 0}));
  const Value td{DataType::TimeDifference, TimeOfDay{86'399'999, 65535}};
  EXPECT_EQ(enc(td), (Bytes{0xFF, 0x5B, 0x26, 0x05, 0xFF, 0xFF}));
  EXPECT_EQ(dec(DataType::TimeDifference, enc(td)), td);
}

TEST(TransferSyntax, EncodeIntoAppends) {
  Bytes out{0xAA};
  encode_into(Value::of_unsigned(DataType::Unsigned16, 0x0102), out);
  encode_into(Value::of_string("hi"), out);
  EXPECT_EQ(out, (Bytes{0xAA, 0x02, 0x01, 'h', 'i'}));
}

TEST(Decode, FixedSizeNeedsExactLength) {
  std::string detail;
  auto low = decode(DataType::Unsigned16, Bytes{0x01});
  EXPECT_EQ(low.code(), code(SdoAbort::LengthTooLow));
  auto high = decode(DataType::Unsigned16, Bytes{0x01, 0x02, 0x03});
  EXPECT_EQ(high.code(), code(SdoAbort::LengthTooHigh));
  EXPECT_EQ(high.error().detail, "3 bytes, u16 needs 2");
  EXPECT_EQ(decode(DataType::Boolean, Bytes{}).code(), code(SdoAbort::LengthTooLow));
  EXPECT_EQ(decode(DataType::TimeOfDay, Bytes(5, 0)).code(), code(SdoAbort::LengthTooLow));
  EXPECT_EQ(decode(DataType::TimeOfDay, Bytes(7, 0)).code(), code(SdoAbort::LengthTooHigh));
  EXPECT_EQ(decode(DataType::Integer24, Bytes(4, 0)).code(), code(SdoAbort::LengthTooHigh));
  EXPECT_EQ(decode(DataType::Integer56, Bytes(8, 0)).code(), code(SdoAbort::LengthTooHigh));
  EXPECT_EQ(decode(DataType::Real64, Bytes(4, 0)).code(), code(SdoAbort::LengthTooLow));
  for (auto t : kAllTypes) {
    if (auto s = fixed_size(t)) {
      EXPECT_EQ(decode(t, Bytes(*s - 1, 0)).code(), code(SdoAbort::LengthTooLow)) << standard_name(t);
      EXPECT_EQ(decode(t, Bytes(*s + 1, 0)).code(), code(SdoAbort::LengthTooHigh)) << standard_name(t);
    }
  }
}

TEST(Decode, UnknownTypeIsRejected) {
  EXPECT_EQ(decode(static_cast<DataType>(0x0020), Bytes{1}).code(), code(SdoAbort::InvalidValue));
}

// 7.1.6.3: a NUL is allowed but not required; text ends at the first one.
TEST(Strings, VisibleStringStopsAtNul_7_1_6_3) {
  EXPECT_EQ(dec(DataType::VisibleString, {'a', 'b', 0, 'c', 'd'}), Value::of_string("ab"));
  EXPECT_EQ(dec(DataType::VisibleString, {'a', 'b'}), Value::of_string("ab"));
  EXPECT_EQ(dec(DataType::VisibleString, {}), Value::of_string(""));
  EXPECT_EQ(dec(DataType::VisibleString, {0, 'x'}), Value::of_string(""));
  EXPECT_EQ(enc(Value::of_string("CANopen")), (Bytes{'C', 'A', 'N', 'o', 'p', 'e', 'n'}));
  // OCTET_STRING and DOMAIN keep every byte.
  EXPECT_EQ(dec(DataType::OctetString, {0, 1, 0}), Value::of_bytes(DataType::OctetString, {0, 1, 0}));
  EXPECT_EQ(dec(DataType::Domain, {0, 0xFF}), Value::of_bytes(DataType::Domain, {0, 0xFF}));
  EXPECT_EQ(enc(Value::of_bytes(DataType::Domain, {1, 2, 3})), (Bytes{1, 2, 3}));
}

// 7.1.6.4: ARRAY OF UNSIGNED16, so UTF-16LE on the wire.
TEST(Strings, UnicodeString_7_1_6_4) {
  const Value v{DataType::UnicodeString, std::u16string{u"A\u20AC\U0001F600"}};
  EXPECT_EQ(enc(v), (Bytes{0x41, 0x00, 0xAC, 0x20, 0x3D, 0xD8, 0x00, 0xDE}));
  EXPECT_EQ(dec(DataType::UnicodeString, enc(v)), v);
  EXPECT_EQ(format_value(v), "A\xE2\x82\xAC\xF0\x9F\x98\x80");
  EXPECT_EQ(parse(DataType::UnicodeString, "A\xE2\x82\xAC\xF0\x9F\x98\x80"), v);
  EXPECT_EQ(dec(DataType::UnicodeString, {'h', 0, 'i', 0, 0, 0, 'x', 0}),
            (Value{DataType::UnicodeString, std::u16string{u"hi"}}));
  EXPECT_EQ(decode(DataType::UnicodeString, Bytes{0x41, 0x00, 0x42}).code(), code(SdoAbort::LengthMismatch));
  EXPECT_EQ(decode(DataType::UnicodeString, Bytes{0x41}).code(), code(SdoAbort::LengthMismatch));
  // A lone surrogate formats as U+FFFD so the text stays valid UTF-8.
  EXPECT_EQ(format_value(Value{DataType::UnicodeString, std::u16string(1, char16_t{0xD800})}), "\xEF\xBF\xBD");
}

TEST(Strings, UnicodeStringRejectsInvalidUtf8) {
  for (std::string_view bad : {"\xFF", "\xC0\x80", "\xE2\x82", "\xED\xA0\x80", "\xF4\x90\x80\x80", "a\x80"}) {
    EXPECT_EQ(parse_error(DataType::UnicodeString, bad), code(SdoAbort::InvalidValue));
  }
}

// ---- text forms ----

TEST(ParseValue, IntegerBases) {
  EXPECT_EQ(parse(DataType::Unsigned16, "0x1A"), Value::of_unsigned(DataType::Unsigned16, 26));
  EXPECT_EQ(parse(DataType::Unsigned16, "0X1a"), Value::of_unsigned(DataType::Unsigned16, 26));
  EXPECT_EQ(parse(DataType::Unsigned16, "010"), Value::of_unsigned(DataType::Unsigned16, 8));  // CiA 306 octal
  EXPECT_EQ(parse(DataType::Unsigned16, "0"), Value::of_unsigned(DataType::Unsigned16, 0));
  EXPECT_EQ(parse(DataType::Unsigned16, "00"), Value::of_unsigned(DataType::Unsigned16, 0));
  EXPECT_EQ(parse(DataType::Unsigned16, "65535"), Value::of_unsigned(DataType::Unsigned16, 65535));
  EXPECT_EQ(parse(DataType::Unsigned32, "0xFFFFFFFF"), Value::of_unsigned(DataType::Unsigned32, 0xFFFFFFFF));
  EXPECT_EQ(parse(DataType::Integer16, "-0x10"), Value::of_signed(DataType::Integer16, -16));
  EXPECT_EQ(parse(DataType::Integer16, "-010"), Value::of_signed(DataType::Integer16, -8));
  EXPECT_EQ(parse(DataType::Integer16, "+5"), Value::of_signed(DataType::Integer16, 5));
  EXPECT_EQ(parse(DataType::Integer8, "-128"), Value::of_signed(DataType::Integer8, -128));
  EXPECT_EQ(parse(DataType::Integer8, "-0x80"), Value::of_signed(DataType::Integer8, -128));
  EXPECT_EQ(parse(DataType::Unsigned8, "+7"), Value::of_unsigned(DataType::Unsigned8, 7));
  EXPECT_EQ(parse(DataType::Unsigned8, "-0"), Value::of_unsigned(DataType::Unsigned8, 0));
  EXPECT_EQ(parse(DataType::Integer64, "-9223372036854775808"),
            Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::min()));
  EXPECT_EQ(parse(DataType::Integer64, "0x7FFFFFFFFFFFFFFF"),
            Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::max()));
  EXPECT_EQ(parse(DataType::Unsigned64, "18446744073709551615"),
            Value::of_unsigned(DataType::Unsigned64, std::numeric_limits<std::uint64_t>::max()));
  EXPECT_EQ(parse(DataType::Unsigned64, "01777777777777777777777"),
            Value::of_unsigned(DataType::Unsigned64, std::numeric_limits<std::uint64_t>::max()));
}

TEST(ParseValue, SurroundingWhitespaceIsIgnoredForNonStrings) {
  EXPECT_EQ(parse(DataType::Unsigned8, " 42 "), Value::of_unsigned(DataType::Unsigned8, 42));
  EXPECT_EQ(parse(DataType::Integer8, "\t-3\r\n"), Value::of_signed(DataType::Integer8, -3));
  EXPECT_EQ(parse(DataType::Real32, " 1.5 "), Value::of_real32(1.5f));
  EXPECT_EQ(parse(DataType::Boolean, " true "), Value::of_bool(true));
  // VISIBLE_STRING is taken as is.
  EXPECT_EQ(parse(DataType::VisibleString, " a b "), Value::of_string(" a b "));
}

TEST(ParseValue, BadIntegerText) {
  for (std::string_view bad : {"",    "   ", "4 2", "- 5", "+-5",   "--5", "08", "0x", "0xG",   "12abc",
                               "1.5", "1.0", "1e3", "abc", "0b101", "5-",  "+",  "-",  "1_000", "\xEF\xBC\x91"}) {
    EXPECT_EQ(parse_error(DataType::Integer32, bad), code(SdoAbort::InvalidValue)) << bad;
    EXPECT_EQ(parse_error(DataType::Unsigned32, bad), code(SdoAbort::InvalidValue)) << bad;
  }
  std::string detail;
  EXPECT_EQ(parse_error(DataType::Unsigned16, "1.5", &detail), code(SdoAbort::InvalidValue));
  EXPECT_EQ(detail, "\"1.5\" is not an integer (u16)");
}

TEST(ParseValue, RangeErrorsNameTheLimitAndType) {
  std::string detail;
  EXPECT_EQ(parse_error(DataType::Unsigned16, "70000", &detail), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(detail, "70000 is above 65535 (u16)");
  EXPECT_EQ(parse_error(DataType::Unsigned8, "-1", &detail), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(detail, "-1 is below 0 (u8)");
  EXPECT_EQ(parse_error(DataType::Integer8, "-129", &detail), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(detail, "-129 is below -128 (i8)");
  EXPECT_EQ(parse_error(DataType::Integer8, "0x80", &detail), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(detail, "0x80 is above 127 (i8)");
  EXPECT_EQ(parse_error(DataType::Integer24, "8388608"), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::Integer24, "-8388609"), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(parse_error(DataType::Unsigned40, "0x10000000000"), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::Integer64, "9223372036854775808"), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::Integer64, "-9223372036854775809"), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(parse_error(DataType::Unsigned64, "18446744073709551616", &detail), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(detail, "18446744073709551616 is above 18446744073709551615 (u64)");
  EXPECT_EQ(parse_error(DataType::Unsigned64, "99999999999999999999999999"), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::Integer64, "-99999999999999999999999999"), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(parse_error(DataType::Unsigned64, "-99999999999999999999999999"), code(SdoAbort::ValueTooLow));
}

TEST(ParseValue, EveryIntegerTypeOneBeyondItsRange) {
  for (auto t : kSigned) {
    if (t == DataType::Integer64) continue;
    EXPECT_EQ(parse_error(t, std::to_string(signed_max(t) + 1)), code(SdoAbort::ValueTooHigh)) << standard_name(t);
    EXPECT_EQ(parse_error(t, std::to_string(signed_min(t) - 1)), code(SdoAbort::ValueTooLow)) << standard_name(t);
  }
  for (auto t : kUnsigned) {
    if (t == DataType::Unsigned64) continue;
    EXPECT_EQ(parse_error(t, std::to_string(unsigned_max(t) + 1)), code(SdoAbort::ValueTooHigh)) << standard_name(t);
    EXPECT_EQ(parse_error(t, "-1"), code(SdoAbort::ValueTooLow)) << standard_name(t);
  }
}

TEST(ParseValue, Boolean) {
  EXPECT_EQ(parse(DataType::Boolean, "1"), Value::of_bool(true));
  EXPECT_EQ(parse(DataType::Boolean, "0"), Value::of_bool(false));
  EXPECT_EQ(parse(DataType::Boolean, "TRUE"), Value::of_bool(true));
  EXPECT_EQ(parse(DataType::Boolean, "false"), Value::of_bool(false));
  for (std::string_view bad : {"", "2", "yes", "-1", "01x", "truee"}) {
    EXPECT_EQ(parse_error(DataType::Boolean, bad), code(SdoAbort::InvalidValue)) << bad;
  }
  EXPECT_EQ(format_value(Value::of_bool(true)), "1");
  EXPECT_EQ(format_value(Value::of_bool(false)), "0");
}

TEST(ParseValue, Reals) {
  EXPECT_EQ(parse(DataType::Real32, "1.5"), Value::of_real32(1.5f));
  EXPECT_EQ(parse(DataType::Real32, "-2.5e3"), Value::of_real32(-2500.0f));
  EXPECT_EQ(parse(DataType::Real32, "+6.25"), Value::of_real32(6.25f));
  EXPECT_EQ(parse(DataType::Real32, "7"), Value::of_real32(7.0f));
  EXPECT_EQ(parse(DataType::Real64, "1E-3"), Value::of_real64(1e-3));
  EXPECT_EQ(parse(DataType::Real64, ".5"), Value::of_real64(0.5));
  EXPECT_EQ(parse(DataType::Real32, "inf"), Value::of_real32(std::numeric_limits<float>::infinity()));
  EXPECT_EQ(parse(DataType::Real32, "-Infinity"), Value::of_real32(-std::numeric_limits<float>::infinity()));
  EXPECT_EQ(parse(DataType::Real64, "-inf"), Value::of_real64(-std::numeric_limits<double>::infinity()));
  EXPECT_TRUE(std::isnan(std::get<float>(parse(DataType::Real32, "nan").data)));
  EXPECT_TRUE(std::isnan(std::get<double>(parse(DataType::Real64, "NaN").data)));
  // Underflow rounds to zero; overflow is a range error.
  EXPECT_EQ(parse(DataType::Real32, "1e-50"), Value::of_real32(0.0f));
  EXPECT_EQ(parse(DataType::Real64, "1e-400"), Value::of_real64(0.0));
  EXPECT_EQ(parse(DataType::Real64, "0." + std::string(400, '0') + "1"), Value::of_real64(0.0));
  EXPECT_EQ(parse_error(DataType::Real64, "1" + std::string(400, '0')), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::Real64, "-1" + std::string(400, '0') + ".5"), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(parse(DataType::Real32, "3.4028234e38"), Value::of_real32(std::numeric_limits<float>::max()));
  // Up to FLT_MAX + half an ulp (3.40282357e38) still rounds to FLT_MAX; beyond is out of range.
  EXPECT_EQ(parse(DataType::Real32, "3.40282356e38"), Value::of_real32(std::numeric_limits<float>::max()));
  EXPECT_EQ(parse_error(DataType::Real32, "3.40282357e38"), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::Real32, "-3.40282357e38"), code(SdoAbort::ValueTooLow));
  std::string detail;
  EXPECT_EQ(parse_error(DataType::Real32, "1e39", &detail), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(detail, "1e39 is above 3.4028235e+38 (r32)");
  EXPECT_EQ(parse_error(DataType::Real32, "-1e39"), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(parse_error(DataType::Real64, "1e400"), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::Real64, "-1e400"), code(SdoAbort::ValueTooLow));
  for (std::string_view bad : {"", "abc", "1.5x", "1,5", "--1", "+-1", "0x10", "1e", "nanx", "- 1"}) {
    EXPECT_EQ(parse_error(DataType::Real32, bad), code(SdoAbort::InvalidValue)) << bad;
    EXPECT_EQ(parse_error(DataType::Real64, bad), code(SdoAbort::InvalidValue)) << bad;
  }
}

TEST(FormatValue, Reals) {
  EXPECT_EQ(format_value(Value::of_real32(0.1f)), "0.1");
  EXPECT_EQ(format_value(Value::of_real32(6.25f)), "6.25");
  EXPECT_EQ(format_value(Value::of_real64(0.1)), "0.1");
  EXPECT_EQ(format_value(Value::of_real64(-1e300)), "-1e+300");
  EXPECT_EQ(format_value(Value::of_real32(std::numeric_limits<float>::quiet_NaN())), "nan");
  EXPECT_EQ(format_value(Value::of_real64(std::numeric_limits<double>::infinity())), "inf");
  EXPECT_EQ(format_value(Value::of_real64(-std::numeric_limits<double>::infinity())), "-inf");
  for (float f : {0.1f, 1e-45f, 3.4028235e38f, -123.456f}) {
    EXPECT_EQ(parse(DataType::Real32, format_value(Value::of_real32(f))), Value::of_real32(f));
  }
  for (double d : {0.1, 5e-324, 1.7976931348623157e308, -123.456}) {
    EXPECT_EQ(parse(DataType::Real64, format_value(Value::of_real64(d))), Value::of_real64(d));
  }
}

TEST(ParseValue, OctetStringAndDomainAsHex) {
  EXPECT_EQ(parse(DataType::OctetString, "01 02 ff"), Value::of_bytes(DataType::OctetString, {1, 2, 0xFF}));
  EXPECT_EQ(parse(DataType::OctetString, "0102FF"), Value::of_bytes(DataType::OctetString, {1, 2, 0xFF}));
  EXPECT_EQ(parse(DataType::Domain, "DeadBeef"), Value::of_bytes(DataType::Domain, {0xDE, 0xAD, 0xBE, 0xEF}));
  EXPECT_EQ(parse(DataType::Domain, ""), Value::of_bytes(DataType::Domain, {}));
  EXPECT_EQ(parse_error(DataType::OctetString, "0G"), code(SdoAbort::InvalidValue));
  EXPECT_EQ(parse_error(DataType::OctetString, "123"), code(SdoAbort::InvalidValue));
  EXPECT_EQ(parse_error(DataType::Domain, "0x12"), code(SdoAbort::InvalidValue));
  EXPECT_EQ(format_value(Value::of_bytes(DataType::OctetString, {0x0A, 0xFF, 0x00})), "0aff00");
  EXPECT_EQ(format_value(Value::of_bytes(DataType::Domain, {})), "");
}

TEST(FormatValue, IntegersAndStrings) {
  EXPECT_EQ(format_value(Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::min())),
            "-9223372036854775808");
  EXPECT_EQ(format_value(Value::of_unsigned(DataType::Unsigned64, std::numeric_limits<std::uint64_t>::max())),
            "18446744073709551615");
  EXPECT_EQ(format_value(Value::of_signed(DataType::Integer24, -5)), "-5");
  EXPECT_EQ(format_value(Value::of_string("hello world")), "hello world");
}

TEST(ParseValue, UnknownTypeIsRejected) {
  EXPECT_EQ(parse_error(static_cast<DataType>(0x0017), "1"), code(SdoAbort::InvalidValue));
}

// ---- TIME_OF_DAY (7.1.6.5): days since 1984-01-01 ----

TEST(TimeOfDay_7_1_6_5, EpochIsDayZero) {
  EXPECT_EQ(unix_ms(1984, 1, 1), 441763200000);
  EXPECT_EQ(time_of_day_from_unix_ms(441763200000), (TimeOfDay{0, 0}));
  EXPECT_EQ(unix_ms_from_time_of_day(TimeOfDay{0, 0}), 441763200000);
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(1984, 1, 2, 1)), (TimeOfDay{1, 1}));
}

TEST(TimeOfDay_7_1_6_5, LeapYears) {
  // 1984 and 2000 are leap years (2000: divisible by 400), 2100 is not.
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(1984, 12, 31)).days, 365);
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(1985, 1, 1)).days, 366);
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(2000, 2, 29)).days, 5903);
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(2000, 3, 1)).days, 5904);
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(2024, 12, 31)).days, 14975);
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(2100, 2, 28)).days, 42427);
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(2100, 3, 1)).days, 42428);
  EXPECT_EQ(format_value(Value{DataType::TimeOfDay, TimeOfDay{0, 5903}}), "2000-02-29T00:00:00.000Z");
  EXPECT_EQ(format_value(Value{DataType::TimeOfDay, TimeOfDay{86'399'999, 14975}}), "2024-12-31T23:59:59.999Z");
  EXPECT_EQ(format_value(Value{DataType::TimeOfDay, TimeOfDay{0, 42428}}), "2100-03-01T00:00:00.000Z");
  EXPECT_EQ(parse(DataType::TimeOfDay, "2100-03-01T00:00:00Z"), (Value{DataType::TimeOfDay, TimeOfDay{0, 42428}}));
  EXPECT_EQ(parse_error(DataType::TimeOfDay, "2100-02-29T00:00:00Z"), code(SdoAbort::InvalidValue));
  EXPECT_EQ(parse(DataType::TimeOfDay, "2000-02-29T12:00:00Z"),
            (Value{DataType::TimeOfDay, TimeOfDay{43'200'000, 5903}}));
}

TEST(TimeOfDay_7_1_6_5, UnixRoundTrip) {
  for (std::int64_t ms : {unix_ms(1984, 1, 1), unix_ms(1999, 12, 31, 86'399'999), unix_ms(2026, 11, 22, 36'930'123),
                          std::int64_t{1795342530123}, unix_ms(2163, 6, 6, 86'399'999)}) {
    EXPECT_EQ(unix_ms_from_time_of_day(time_of_day_from_unix_ms(ms)), ms) << ms;
  }
  EXPECT_EQ(time_of_day_from_unix_ms(1795342530123), (TimeOfDay{36'930'123, 15666}));
  // Outside 1984-01-01 .. day 65535 (2163-06-06): clamped.
  EXPECT_EQ(time_of_day_from_unix_ms(0), (TimeOfDay{0, 0}));
  EXPECT_EQ(time_of_day_from_unix_ms(unix_ms(2163, 6, 7)), (TimeOfDay{86'399'999, 65535}));
}

TEST(TimeOfDay_7_1_6_5, TextForms) {
  const Value t{DataType::TimeOfDay, TimeOfDay{36'930'123, 15666}};
  EXPECT_EQ(format_value(t), "2026-11-22T10:15:30.123Z");
  EXPECT_EQ(parse(DataType::TimeOfDay, "2026-11-22T10:15:30.123Z"), t);
  EXPECT_EQ(parse(DataType::TimeOfDay, "2026-11-22t10:15:30.123z"), t);
  EXPECT_EQ(parse(DataType::TimeOfDay, "2026-11-22 10:15:30.123Z"), t);
  EXPECT_EQ(parse(DataType::TimeOfDay, "2026-11-22T11:15:30.123+01:00"), t);
  EXPECT_EQ(parse(DataType::TimeOfDay, "2026-11-22T05:00:30.123-05:15"), t);
  EXPECT_EQ(parse(DataType::TimeOfDay, "2026-11-22T10:15:30.1234567Z"), t);  // sub-ms truncated
  EXPECT_EQ(parse(DataType::TimeOfDay, "2026-11-22T10:15:30.1Z"),
            (Value{DataType::TimeOfDay, TimeOfDay{36'930'100, 15666}}));
  EXPECT_EQ(parse(DataType::TimeOfDay, "15666 36930123"), t);
  EXPECT_EQ(parse(DataType::TimeOfDay, "1984-01-01T00:00:00Z"), (Value{DataType::TimeOfDay, TimeOfDay{0, 0}}));
  EXPECT_EQ(parse(DataType::TimeOfDay, "2163-06-06T23:59:59.999Z"),
            (Value{DataType::TimeOfDay, TimeOfDay{86'399'999, 65535}}));
  std::string detail;
  EXPECT_EQ(parse_error(DataType::TimeOfDay, "1983-12-31T23:59:59.999Z", &detail), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(detail, "1983-12-31T23:59:59.999Z is below 1984-01-01T00:00:00.000Z (t)");
  EXPECT_EQ(parse_error(DataType::TimeOfDay, "2163-06-07T00:00:00Z"), code(SdoAbort::ValueTooHigh));
  for (std::string_view bad :
       {"", "2026-11-22", "2026-11-22T10:15:30", "2026-13-01T00:00:00Z", "2026-11-22T24:00:00Z", "2026-11-22T10:60:00Z",
        "2026-11-22T10:15:30.Z", "2026-11-22T10:15:30Zx", "26-11-22T10:15:30Z", "x 5", "1 2 3"}) {
    EXPECT_EQ(parse_error(DataType::TimeOfDay, bad), code(SdoAbort::InvalidValue)) << bad;
  }
  EXPECT_EQ(parse_error(DataType::TimeOfDay, "0 86400000"), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(parse_error(DataType::TimeOfDay, "65536 0"), code(SdoAbort::ValueTooHigh));
}

TEST(TimeDifference_7_1_6_6, TextForms) {
  const Value td{DataType::TimeDifference, TimeOfDay{500, 2}};
  EXPECT_EQ(format_value(td), "2 500");
  EXPECT_EQ(parse(DataType::TimeDifference, "2 500"), td);
  EXPECT_EQ(parse(DataType::TimeDifference, " 2\t500 "), td);
  EXPECT_EQ(parse_error(DataType::TimeDifference, "2026-11-22T10:15:30Z"), code(SdoAbort::InvalidValue));
  EXPECT_EQ(parse_error(DataType::TimeDifference, "-1 0"), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(parse_error(DataType::TimeDifference, "1"), code(SdoAbort::InvalidValue));
}

// ---- check_limits ----

std::error_code limits(const Value& v, std::optional<Value> lo, std::optional<Value> hi, std::string* d = nullptr) {
  return check_limits(v, lo, hi, d);
}

TEST(CheckLimits, SameType) {
  const auto u16 = [](std::uint64_t x) { return Value::of_unsigned(DataType::Unsigned16, x); };
  std::string detail;
  EXPECT_EQ(limits(u16(50), u16(10), u16(100)), std::error_code{});
  EXPECT_EQ(limits(u16(10), u16(10), u16(100)), std::error_code{});
  EXPECT_EQ(limits(u16(100), u16(10), u16(100)), std::error_code{});
  EXPECT_EQ(limits(u16(150), u16(10), u16(100), &detail), code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(detail, "150 is above the high limit 100 (u16)");
  EXPECT_EQ(limits(u16(5), u16(10), u16(100), &detail), code(SdoAbort::ValueTooLow));
  EXPECT_EQ(detail, "5 is below the low limit 10 (u16)");
  EXPECT_EQ(limits(u16(5), std::nullopt, std::nullopt), std::error_code{});
  EXPECT_EQ(limits(u16(500), u16(10), std::nullopt), std::error_code{});
  EXPECT_EQ(limits(u16(5), std::nullopt, u16(100)), std::error_code{});
}

TEST(CheckLimits, SignedVersusUnsigned) {
  // A naive cast would make -1 huge (or 2^64-1 negative).
  EXPECT_EQ(limits(Value::of_signed(DataType::Integer8, -1), Value::of_unsigned(DataType::Unsigned8, 0), std::nullopt),
            code(SdoAbort::ValueTooLow));
  EXPECT_EQ(limits(Value::of_signed(DataType::Integer8, -1), std::nullopt, Value::of_unsigned(DataType::Unsigned8, 5)),
            std::error_code{});
  EXPECT_EQ(limits(Value::of_unsigned(DataType::Unsigned64, std::numeric_limits<std::uint64_t>::max()),
                   Value::of_signed(DataType::Integer64, -10), Value::of_signed(DataType::Integer64, 10)),
            code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(limits(Value::of_unsigned(DataType::Unsigned64, 5), Value::of_signed(DataType::Integer64, -10),
                   Value::of_signed(DataType::Integer64, 10)),
            std::error_code{});
  EXPECT_EQ(limits(Value::of_unsigned(DataType::Unsigned32, 0), Value::of_signed(DataType::Integer32, 1), std::nullopt),
            code(SdoAbort::ValueTooLow));
}

TEST(CheckLimits, RealsAndIntegers) {
  EXPECT_EQ(limits(Value::of_real32(1.5f), std::nullopt, Value::of_signed(DataType::Integer16, 1)),
            code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(limits(Value::of_real32(0.5f), Value::of_signed(DataType::Integer16, 1), std::nullopt),
            code(SdoAbort::ValueTooLow));
  EXPECT_EQ(limits(Value::of_signed(DataType::Integer16, 2), std::nullopt, Value::of_real64(1.5)),
            code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(limits(Value::of_signed(DataType::Integer16, 1), Value::of_real64(0.5), Value::of_real64(1.5)),
            std::error_code{});
  // 2^63 as a double: i64 max is below it, and u64 2^63 + 1 above it, though both round to it.
  EXPECT_EQ(limits(Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::max()), std::nullopt,
                   Value::of_real64(9223372036854775808.0)),
            std::error_code{});
  EXPECT_EQ(limits(Value::of_unsigned(DataType::Unsigned64, (std::uint64_t{1} << 63) + 1), std::nullopt,
                   Value::of_real64(9223372036854775808.0)),
            code(SdoAbort::ValueTooHigh));
  EXPECT_EQ(limits(Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::min()),
                   Value::of_real64(-1e300), Value::of_real64(1e300)),
            std::error_code{});
  EXPECT_EQ(limits(Value::of_real64(-std::numeric_limits<double>::infinity()), Value::of_signed(DataType::Integer8, -5),
                   std::nullopt),
            code(SdoAbort::ValueTooLow));
  std::string detail;
  EXPECT_EQ(limits(Value::of_real32(std::numeric_limits<float>::quiet_NaN()), Value::of_real32(0.0f), std::nullopt,
                   &detail),
            code(SdoAbort::InvalidValue));
  EXPECT_EQ(detail, "nan cannot be compared with the low limit 0 (r32)");  // names the type like every range error
}

TEST(CheckLimits, NonNumericValuesAreNotChecked) {
  EXPECT_EQ(limits(Value::of_string("zzz"), Value::of_string("a"), Value::of_string("b")), std::error_code{});
  EXPECT_EQ(limits(Value::of_bool(true), Value::of_bool(false), Value::of_bool(true)), std::error_code{});
  EXPECT_EQ(limits(Value::of_bool(true), std::nullopt, Value::of_unsigned(DataType::Unsigned8, 0)),
            code(SdoAbort::ValueTooHigh));
}

// ---- every type: text and wire round trips ----

TEST(RoundTrip, EveryTypeThroughTextAndWire) {
  const auto& samples = test::kEveryTypeSamples;
  for (auto [t, text] : samples) {
    const Value v = parse(t, text);
    EXPECT_EQ(v.type, t);
    EXPECT_EQ(format_value(v), text) << standard_name(t);
    EXPECT_EQ(dec(t, encode(v)), v) << standard_name(t);
  }
}

}  // namespace
}  // namespace canopen

namespace canopen {
namespace {

TEST(Value, EncodedSizeEqualsTheSizeOfTheEncoding) {
  for (const auto& [t, text] : test::kEveryTypeSamples) {
    const Value v = parse_value(t, text).value();
    EXPECT_EQ(encoded_size(v), encode(v).size()) << standard_name(t);
  }
}

TEST(Value, HoldsItsTypeChecksTheRepresentation) {
  EXPECT_TRUE(holds_its_type(Value::of_unsigned(DataType::Unsigned24, 5)));
  EXPECT_TRUE(holds_its_type(Value::zero(DataType::TimeOfDay)));
  EXPECT_TRUE(holds_its_type(Value::of_bytes(DataType::Domain, {1, 2})));
  EXPECT_FALSE(holds_its_type(Value{DataType::Unsigned16, std::int64_t{5}})) << "unsigned held as signed";
  EXPECT_FALSE(holds_its_type(Value{DataType::Real32, 1.0})) << "REAL32 held as double";
  EXPECT_FALSE(holds_its_type(Value{DataType::VisibleString, Bytes{}}));
  for (auto t : {DataType::Boolean, DataType::Integer56, DataType::Unsigned64, DataType::Real64,
                 DataType::UnicodeString, DataType::OctetString, DataType::TimeDifference}) {
    EXPECT_TRUE(holds_its_type(Value::zero(t))) << standard_name(t);
  }
}

}  // namespace
}  // namespace canopen
