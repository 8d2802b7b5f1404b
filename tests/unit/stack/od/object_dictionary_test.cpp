// Tests for stack/src/od/object_dictionary.cpp: storage, the SDO-side access
// rules of CiA 301 7.4 (access rights, lengths, limits, hooks) and local access.
#include "canopen/od/object_dictionary.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace canopen::od {
namespace {

Bytes le(std::uint64_t v, std::size_t n) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(v >> (8 * i));
  return b;
}

std::uint32_t abort_code(std::error_code ec) { return ec ? to_abort_code(ec) : 0U; }

Value u8(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned8, v); }
Value u16(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned16, v); }
Value u32(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned32, v); }

// Every value in the dictionary, to show that a refused write changed nothing.
std::map<std::pair<std::uint16_t, std::uint8_t>, Value> snapshot(const ObjectDictionary& od) {
  std::map<std::pair<std::uint16_t, std::uint8_t>, Value> out;
  for (const auto& [index, obj] : od.objects()) {
    for (const auto& [sub, e] : obj.subs) out.emplace(std::pair{index, sub}, e.value);
  }
  return out;
}

// 2000h u16 rw with limits 10..1000, 2001h u32 ro, 2002h u8 wo, 2003h u32
// const, 2004h DOMAIN rw, 2005h VISIBLE_STRING rw, 2006h i16 rw -100..100,
// 2007h UNICODE_STRING rw, 2008h ARRAY of 3 u16 rw.
ObjectDictionary sample() {
  ObjectDictionary od;
  Object limited = make_var(0x2000, "Limited", DataType::Unsigned16, Access::ReadWrite, u16(500), true);
  limited.subs.at(0).low = u16(10);
  limited.subs.at(0).high = u16(1000);
  od.insert(std::move(limited));
  od.insert(make_var(0x2001, "Counter", DataType::Unsigned32, Access::ReadOnly, u32(0x12345678)));
  od.insert(make_var(0x2002, "Command", DataType::Unsigned8, Access::WriteOnly, u8(0)));
  od.insert(make_var(0x2003, "Constant", DataType::Unsigned32, Access::Const, u32(7)));
  od.insert(make_var(0x2004, "Blob", DataType::Domain, Access::ReadWrite,
                     Value::of_bytes(DataType::Domain, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10})));
  od.insert(make_var(0x2005, "Name", DataType::VisibleString, Access::ReadWrite, Value::of_string("gateway")));
  Object sgn = make_var(0x2006, "Signed", DataType::Integer16, Access::ReadWrite,
                        Value::of_signed(DataType::Integer16, 0));
  sgn.subs.at(0).low = Value::of_signed(DataType::Integer16, -100);
  sgn.subs.at(0).high = Value::of_signed(DataType::Integer16, 100);
  od.insert(std::move(sgn));
  od.insert(make_var(0x2007, "Text", DataType::UnicodeString, Access::ReadWrite,
                     Value{DataType::UnicodeString, std::u16string{}}));
  od.insert(make_array(0x2008, "Table", DataType::Unsigned16, Access::ReadWrite, 3));
  return od;
}

// ---- names (7.4.3, 7.4.5) -------------------------------------------------------

TEST(ObjectCode, NamesAreTheStandardObjectNames) {
  EXPECT_EQ(to_string(ObjectCode::Null), "NULL");
  EXPECT_EQ(to_string(ObjectCode::Domain), "DOMAIN");
  EXPECT_EQ(to_string(ObjectCode::DefType), "DEFTYPE");
  EXPECT_EQ(to_string(ObjectCode::DefStruct), "DEFSTRUCT");
  EXPECT_EQ(to_string(ObjectCode::Var), "VAR");
  EXPECT_EQ(to_string(ObjectCode::Array), "ARRAY");
  EXPECT_EQ(to_string(ObjectCode::Record), "RECORD");
}

TEST(Access, NamesAreTheEdsSpellings) {
  EXPECT_EQ(to_string(Access::ReadOnly), "ro");
  EXPECT_EQ(to_string(Access::WriteOnly), "wo");
  EXPECT_EQ(to_string(Access::ReadWrite), "rw");
  EXPECT_EQ(to_string(Access::ReadWriteRead), "rwr");
  EXPECT_EQ(to_string(Access::ReadWriteWrite), "rww");
  EXPECT_EQ(to_string(Access::Const), "const");
}

TEST(Access, ParseIsCaseInsensitiveAndRoundTrips) {
  for (Access a : {Access::ReadOnly, Access::WriteOnly, Access::ReadWrite, Access::ReadWriteRead,
                   Access::ReadWriteWrite, Access::Const}) {
    EXPECT_EQ(parse_access(to_string(a)), a);
  }
  EXPECT_EQ(parse_access("RO"), Access::ReadOnly);
  EXPECT_EQ(parse_access("Const"), Access::Const);
  EXPECT_EQ(parse_access("RWW"), Access::ReadWriteWrite);
}

TEST(Access, ParseRejectsOtherSpellings) {
  EXPECT_EQ(parse_access(""), std::nullopt);
  EXPECT_EQ(parse_access("r"), std::nullopt);
  EXPECT_EQ(parse_access("rw "), std::nullopt);
  EXPECT_EQ(parse_access("readonly"), std::nullopt);
}

TEST(Access, ConstAndReadOnlyAreNotWritableWriteOnlyIsNotReadable) {
  EXPECT_FALSE(writable(Access::ReadOnly));
  EXPECT_FALSE(writable(Access::Const));
  EXPECT_TRUE(writable(Access::ReadWriteRead));
  EXPECT_TRUE(writable(Access::ReadWriteWrite));
  EXPECT_FALSE(readable(Access::WriteOnly));
  EXPECT_TRUE(readable(Access::Const));
}

// ---- builders ----------------------------------------------------------------------

TEST(MakeVar, HasSubZeroOnlyWithValueAsDefault) {
  Object o = make_var(0x2100, "Speed", DataType::Integer32, Access::ReadWrite,
                      Value::of_signed(DataType::Integer32, -5), true);
  EXPECT_EQ(o.index, 0x2100);
  EXPECT_EQ(o.name, "Speed");
  EXPECT_EQ(o.code, ObjectCode::Var);
  ASSERT_EQ(o.subs.size(), 1U);
  const SubEntry& e = o.subs.at(0);
  EXPECT_EQ(e.sub, 0);
  EXPECT_EQ(e.type, DataType::Integer32);
  EXPECT_EQ(e.access, Access::ReadWrite);
  EXPECT_TRUE(e.pdo_mappable);
  EXPECT_EQ(e.value, Value::of_signed(DataType::Integer32, -5));
  EXPECT_EQ(e.default_value, e.value);
}

TEST(MakeArray, SubZeroIsTheCountEntriesAreZeroOfTheType) {
  Object o = make_array(0x2200, "Gains", DataType::Integer16, Access::ReadWrite, 4);
  EXPECT_EQ(o.code, ObjectCode::Array);
  ASSERT_EQ(o.subs.size(), 5U);
  EXPECT_EQ(o.subs.at(0).type, DataType::Unsigned8);
  EXPECT_EQ(o.subs.at(0).access, Access::ReadOnly);
  EXPECT_EQ(o.subs.at(0).value, u8(4));
  for (std::uint8_t s = 1; s <= 4; ++s) {
    EXPECT_EQ(o.subs.at(s).sub, s);
    EXPECT_EQ(o.subs.at(s).type, DataType::Integer16);
    EXPECT_EQ(o.subs.at(s).access, Access::ReadWrite);
    EXPECT_EQ(o.subs.at(s).value, Value::zero(DataType::Integer16));
  }
}

TEST(MakeArray, SubZeroAccessCanBeGiven) {
  Object o = make_array(0x2200, "Gains", DataType::Unsigned32, Access::ReadOnly, 2, Access::ReadWrite);
  EXPECT_EQ(o.subs.at(0).access, Access::ReadWrite);
  EXPECT_EQ(o.subs.at(1).access, Access::ReadOnly);
}

// ---- storage -----------------------------------------------------------------------

TEST(ObjectDictionaryStorage, InsertAddsAndFindFindsObjectsAndEntries) {
  ObjectDictionary od = sample();
  ASSERT_NE(od.find(0x2000), nullptr);
  EXPECT_EQ(od.find(0x2000)->name, "Limited");
  ASSERT_NE(od.find(0x2008, 2), nullptr);
  EXPECT_EQ(od.find(0x2008, 2)->sub, 2);
  EXPECT_EQ(od.find(0x3000), nullptr);
  EXPECT_EQ(od.find(0x2000, 1), nullptr);
  EXPECT_EQ(od.find(0x3000, 0), nullptr);
  const ObjectDictionary& c = od;
  EXPECT_NE(c.find(0x2001), nullptr);
  EXPECT_NE(c.find(0x2001, 0), nullptr);
  EXPECT_EQ(od.objects().size(), 9U);
}

TEST(ObjectDictionaryStorage, InsertReplacesTheObjectAtItsIndex) {
  ObjectDictionary od = sample();
  Object& o = od.insert(make_var(0x2001, "Other", DataType::Unsigned8, Access::ReadWrite, u8(3)));
  EXPECT_EQ(o.name, "Other");
  EXPECT_EQ(od.find(0x2001)->name, "Other");
  EXPECT_EQ(od.get(0x2001, 0).value(), u8(3));
  EXPECT_EQ(od.objects().size(), 9U);
}

TEST(ObjectDictionaryStorage, EraseRemovesTheObject) {
  ObjectDictionary od = sample();
  EXPECT_TRUE(od.erase(0x2001));
  EXPECT_EQ(od.find(0x2001), nullptr);
  EXPECT_FALSE(od.erase(0x2001));
  EXPECT_EQ(abort_code(od.read(0x2001, 0).code()), 0x06020000U);
}

// ---- SDO upload ----------------------------------------------------------------------

TEST(ObjectDictionaryRead, ReturnsTheLittleEndianEncoding) {
  ObjectDictionary od = sample();
  auto r = od.read(0x2001, 0);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(*r, (Bytes{0x78, 0x56, 0x34, 0x12}));
}

TEST(ObjectDictionaryRead, MissingObjectAbortsNoSuchObject) {
  ObjectDictionary od = sample();
  auto r = od.read(0x3000, 0);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(abort_code(r.code()), 0x06020000U);
  EXPECT_FALSE(r.error().detail.empty());
}

TEST(ObjectDictionaryRead, MissingSubIndexAbortsNoSuchSubIndex) {
  ObjectDictionary od = sample();
  EXPECT_EQ(abort_code(od.read(0x2000, 1).code()), 0x06090011U);
  EXPECT_EQ(abort_code(od.read(0x2008, 4).code()), 0x06090011U);
}

TEST(ObjectDictionaryRead, WriteOnlyAbortsReadOfWriteOnly) {
  ObjectDictionary od = sample();
  EXPECT_EQ(abort_code(od.read(0x2002, 0).code()), 0x06010001U);
}

TEST(ObjectDictionaryRead, ConstReadOnlyAndReadWriteAreReadable) {
  ObjectDictionary od = sample();
  EXPECT_TRUE(od.read(0x2003, 0).ok());
  EXPECT_TRUE(od.read(0x2001, 0).ok());
  EXPECT_TRUE(od.read(0x2000, 0).ok());
}

TEST(ObjectDictionaryRead, DomainReturnsItsBytes) {
  ObjectDictionary od = sample();
  EXPECT_EQ(od.read(0x2004, 0).value(), (Bytes{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
}

TEST(ObjectDictionaryRead, VisibleStringReturnsItsBytesWithoutTerminator) {
  ObjectDictionary od = sample();
  EXPECT_EQ(od.read(0x2005, 0).value(), (Bytes{'g', 'a', 't', 'e', 'w', 'a', 'y'}));
}

TEST(ObjectDictionaryRead, ArraySubZeroIsTheCount) {
  ObjectDictionary od = sample();
  EXPECT_EQ(od.read(0x2008, 0).value(), (Bytes{3}));
}

TEST(ObjectDictionaryReadHook, IsCalledWithTheEntryAndItsResultIsUploaded) {
  ObjectDictionary od = sample();
  std::vector<std::uint8_t> subs;
  od.on_read(0x2008, [&](const SubEntry& e) -> Result<Bytes> {
    subs.push_back(e.sub);
    EXPECT_EQ(e.type, e.sub == 0 ? DataType::Unsigned8 : DataType::Unsigned16);
    return Bytes{0xAB, e.sub};
  });
  EXPECT_EQ(od.read(0x2008, 2).value(), (Bytes{0xAB, 2}));
  EXPECT_EQ(od.read(0x2008, 0).value(), (Bytes{0xAB, 0}));
  EXPECT_EQ(subs, (std::vector<std::uint8_t>{2, 0}));
}

TEST(ObjectDictionaryReadHook, CanRefuseWithItsOwnCode) {
  ObjectDictionary od = sample();
  od.on_read(0x2001, [](const SubEntry&) -> Result<Bytes> { return {make_error_code(SdoAbort::HardwareError)}; });
  EXPECT_EQ(abort_code(od.read(0x2001, 0).code()), 0x06060000U);
}

TEST(ObjectDictionaryReadHook, IsNotCalledWhenAccessRightsRefuse) {
  ObjectDictionary od = sample();
  bool called = false;
  od.on_read(0x2002, [&](const SubEntry&) -> Result<Bytes> {
    called = true;
    return Bytes{};
  });
  EXPECT_EQ(abort_code(od.read(0x2002, 0).code()), 0x06010001U);
  EXPECT_EQ(abort_code(od.read(0x2002, 1).code()), 0x06090011U);
  EXPECT_FALSE(called);
}

TEST(ObjectDictionaryReadHook, DictionaryFormSeesOtherEntries) {
  ObjectDictionary od = sample();
  od.on_dict_read(0x2001, [](const ObjectDictionary& d, const SubEntry&) -> Result<Bytes> {
    return encode(d.get(0x2000, 0).value());
  });
  EXPECT_EQ(od.read(0x2001, 0).value(), le(500, 2));
}

TEST(ObjectDictionaryReadHook, EmptyFunctionRemovesIt) {
  ObjectDictionary od = sample();
  od.on_read(0x2001, [](const SubEntry&) -> Result<Bytes> { return Bytes{9}; });
  od.on_read(0x2001, nullptr);
  EXPECT_EQ(od.read(0x2001, 0).value(), le(0x12345678, 4));
}

// ---- SDO download ----------------------------------------------------------------------

TEST(ObjectDictionaryWrite, StoresTheDecodedValue) {
  ObjectDictionary od = sample();
  EXPECT_FALSE(od.write(0x2000, 0, le(0x0123, 2)));
  EXPECT_EQ(od.get(0x2000, 0).value(), u16(0x0123));
  EXPECT_FALSE(od.write(0x2008, 3, le(0xBEEF, 2)));
  EXPECT_EQ(od.get(0x2008, 3).value(), u16(0xBEEF));
}

TEST(ObjectDictionaryWrite, WriteOnlyIsWritable) {
  ObjectDictionary od = sample();
  EXPECT_FALSE(od.write(0x2002, 0, Bytes{0x42}));
  EXPECT_EQ(od.get(0x2002, 0).value(), u8(0x42));
}

TEST(ObjectDictionaryWrite, ReadOnlyAbortsWriteOfReadOnlyAndChangesNothing) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2001, 0, le(1, 4))), 0x06010002U);
  EXPECT_EQ(abort_code(od.write(0x2008, 0, Bytes{2})), 0x06010002U);  // array count, ro
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, ConstAbortsWriteOfReadOnlyAndChangesNothing) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2003, 0, le(1, 4))), 0x06010002U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, MissingObjectAbortsNoSuchObject) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x3000, 0, le(1, 2))), 0x06020000U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, MissingSubIndexAbortsNoSuchSubIndex) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2008, 9, le(1, 2))), 0x06090011U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, TooManyBytesForFixedSizeAbortsLengthTooHigh) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2000, 0, le(20, 4))), 0x06070012U);
  EXPECT_EQ(abort_code(od.write(0x2002, 0, le(20, 2))), 0x06070012U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, TooFewBytesForFixedSizeAbortsLengthTooLow) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2000, 0, Bytes{20})), 0x06070013U);
  EXPECT_EQ(abort_code(od.write(0x2002, 0, Bytes{})), 0x06070013U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, OddLengthUnicodeStringAbortsLengthMismatch) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2007, 0, Bytes{'a', 0, 'b'})), 0x06070010U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, VariableLengthTypesTakeAnyLength) {
  ObjectDictionary od = sample();
  EXPECT_FALSE(od.write(0x2004, 0, Bytes{}));
  EXPECT_EQ(od.read(0x2004, 0).value(), Bytes{});
  const Bytes big(1000, 0x5A);
  EXPECT_FALSE(od.write(0x2004, 0, big));
  EXPECT_EQ(od.read(0x2004, 0).value(), big);
  EXPECT_FALSE(od.write(0x2005, 0, Bytes{'a', 'b'}));
  EXPECT_EQ(od.get(0x2005, 0).value(), Value::of_string("ab"));
}

TEST(ObjectDictionaryWrite, AboveHighLimitAbortsValueTooHighAndChangesNothing) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2000, 0, le(1001, 2))), 0x06090031U);
  EXPECT_EQ(abort_code(od.write(0x2006, 0, le(101, 2))), 0x06090031U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, BelowLowLimitAbortsValueTooLowAndChangesNothing) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2000, 0, le(9, 2))), 0x06090032U);
  EXPECT_EQ(abort_code(od.write(0x2006, 0, le(static_cast<std::uint16_t>(-101), 2))), 0x06090032U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWrite, LimitsThemselvesAreAccepted) {
  ObjectDictionary od = sample();
  EXPECT_FALSE(od.write(0x2000, 0, le(10, 2)));
  EXPECT_FALSE(od.write(0x2000, 0, le(1000, 2)));
  EXPECT_FALSE(od.write(0x2006, 0, le(static_cast<std::uint16_t>(-100), 2)));
  EXPECT_EQ(od.get(0x2006, 0).value(), Value::of_signed(DataType::Integer16, -100));
}

// ---- write hooks ---------------------------------------------------------------------------

TEST(ObjectDictionaryWriteHook, IsCalledWithTheEntryBeforeStoring) {
  ObjectDictionary od = sample();
  int calls = 0;
  od.on_write(0x2008, [&](SubEntry& e, const Value& v) -> std::error_code {
    ++calls;
    EXPECT_EQ(e.sub, 2);
    EXPECT_EQ(e.value, u16(0));   // not stored yet
    EXPECT_EQ(v, u16(0x1234));
    return {};
  });
  EXPECT_FALSE(od.write(0x2008, 2, le(0x1234, 2)));
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(od.get(0x2008, 2).value(), u16(0x1234));
}

TEST(ObjectDictionaryWriteHook, CanRefuseAndNothingChanges) {
  ObjectDictionary od = sample();
  od.on_write(0x2008, [](SubEntry&, const Value&) { return make_error_code(SdoAbort::ParameterIncompatible); });
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2008, 1, le(5, 2))), 0x06040043U);
  EXPECT_EQ(snapshot(od), before);
}

TEST(ObjectDictionaryWriteHook, RunsAfterAccessLengthAndLimitChecks) {
  ObjectDictionary od = sample();
  int calls = 0;
  auto hook = [&](SubEntry&, const Value&) -> std::error_code {
    ++calls;
    return {};
  };
  od.on_write(0x2000, hook);
  od.on_write(0x2001, hook);
  EXPECT_EQ(abort_code(od.write(0x2001, 0, le(1, 4))), 0x06010002U);
  EXPECT_EQ(abort_code(od.write(0x2000, 0, le(50, 3))), 0x06070012U);
  EXPECT_EQ(abort_code(od.write(0x2000, 0, le(5000, 2))), 0x06090031U);
  EXPECT_EQ(calls, 0);
}

TEST(ObjectDictionaryWriteHook, DictionaryFormCanChangeOtherEntries) {
  ObjectDictionary od = sample();
  od.on_dict_write(0x2008, [](ObjectDictionary& d, SubEntry& e, const Value& v) -> std::error_code {
    // Mirror into the next entry.
    if (e.sub == 1) return d.set(0x2008, 2, v);
    return {};
  });
  EXPECT_FALSE(od.write(0x2008, 1, le(77, 2)));
  EXPECT_EQ(od.get(0x2008, 1).value(), u16(77));
  EXPECT_EQ(od.get(0x2008, 2).value(), u16(77));
}

TEST(ObjectDictionaryWriteHook, DictionaryFormCanRefuse) {
  ObjectDictionary od = sample();
  od.on_dict_write(0x2000, [](ObjectDictionary& d, SubEntry&, const Value& v) -> std::error_code {
    // Refuse values above 2001h's low half (an inter-object rule).
    return std::get<std::uint64_t>(v.data) > (d.get_unsigned(0x2001, 0).value() & 0xFF)
               ? make_error_code(SdoAbort::InvalidValue)
               : std::error_code{};
  });
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.write(0x2000, 0, le(0x79, 2))), 0x06090030U);
  EXPECT_EQ(snapshot(od), before);
  EXPECT_FALSE(od.write(0x2000, 0, le(0x78, 2)));
}

TEST(ObjectDictionaryWriteHook, HookErasingItsObjectIsSafe) {
  ObjectDictionary od = sample();
  od.on_dict_write(0x2000, [](ObjectDictionary& d, SubEntry&, const Value&) -> std::error_code {
    d.erase(0x2000);
    return {};
  });
  EXPECT_FALSE(od.write(0x2000, 0, le(20, 2)));
  EXPECT_EQ(od.find(0x2000), nullptr);
}

TEST(ObjectDictionaryWriteHook, SettingOneFormReplacesTheOther) {
  ObjectDictionary od = sample();
  int plain = 0;
  int dict = 0;
  od.on_write(0x2000, [&](SubEntry&, const Value&) -> std::error_code {
    ++plain;
    return {};
  });
  od.on_dict_write(0x2000, [&](ObjectDictionary&, SubEntry&, const Value&) -> std::error_code {
    ++dict;
    return {};
  });
  EXPECT_FALSE(od.write(0x2000, 0, le(20, 2)));
  EXPECT_EQ(plain, 0);
  EXPECT_EQ(dict, 1);
  od.on_write(0x2000, [&](SubEntry&, const Value&) -> std::error_code {
    ++plain;
    return {};
  });
  EXPECT_FALSE(od.write(0x2000, 0, le(21, 2)));
  EXPECT_EQ(plain, 1);
  EXPECT_EQ(dict, 1);
}

TEST(ObjectDictionaryWriteHook, EmptyFunctionRemovesIt) {
  ObjectDictionary od = sample();
  od.on_write(0x2000, [](SubEntry&, const Value&) { return make_error_code(SdoAbort::InvalidValue); });
  od.on_write(0x2000, nullptr);
  EXPECT_FALSE(od.write(0x2000, 0, le(20, 2)));
}

TEST(ObjectDictionaryHooks, InsertKeepsThemEraseDropsThem) {
  ObjectDictionary od = sample();
  od.on_write(0x2000, [](SubEntry&, const Value&) { return make_error_code(SdoAbort::InvalidValue); });
  od.insert(make_var(0x2000, "Again", DataType::Unsigned16, Access::ReadWrite, u16(1)));
  EXPECT_EQ(abort_code(od.write(0x2000, 0, le(20, 2))), 0x06090030U);
  od.erase(0x2000);
  od.insert(make_var(0x2000, "Fresh", DataType::Unsigned16, Access::ReadWrite, u16(1)));
  EXPECT_FALSE(od.write(0x2000, 0, le(20, 2)));
}

TEST(ObjectDictionaryHooks, DictionaryFormFollowsCopiesAndMoves) {
  ObjectDictionary od = sample();
  od.on_dict_write(0x2008, [](ObjectDictionary& d, SubEntry& e, const Value& v) -> std::error_code {
    return e.sub == 1 ? d.set(0x2008, 2, v) : std::error_code{};
  });
  ObjectDictionary copy = od;
  EXPECT_FALSE(copy.write(0x2008, 1, le(5, 2)));
  EXPECT_EQ(copy.get(0x2008, 2).value(), u16(5));
  EXPECT_EQ(od.get(0x2008, 2).value(), u16(0));  // the original is untouched
  ObjectDictionary moved = std::move(copy);
  EXPECT_FALSE(moved.write(0x2008, 1, le(6, 2)));
  EXPECT_EQ(moved.get(0x2008, 2).value(), u16(6));
}

// ---- upload size --------------------------------------------------------------------------

TEST(ObjectDictionaryUploadSize, FixedSizeTypesGiveTheirSize) {
  ObjectDictionary od = sample();
  EXPECT_EQ(od.upload_size(0x2000, 0), 2U);
  EXPECT_EQ(od.upload_size(0x2001, 0), 4U);
  EXPECT_EQ(od.upload_size(0x2008, 0), 1U);
}

TEST(ObjectDictionaryUploadSize, VariableLengthTypesGiveTheEncodedSize) {
  ObjectDictionary od = sample();
  EXPECT_EQ(od.upload_size(0x2004, 0), 10U);
  EXPECT_EQ(od.upload_size(0x2005, 0), 7U);
}

TEST(ObjectDictionaryUploadSize, UnknownWithAReadHookOrWhenNotReadable) {
  ObjectDictionary od = sample();
  od.on_read(0x2004, [](const SubEntry&) -> Result<Bytes> { return Bytes{1}; });
  EXPECT_EQ(od.upload_size(0x2004, 0), std::nullopt);
  od.on_dict_read(0x2005, [](const ObjectDictionary&, const SubEntry&) -> Result<Bytes> { return Bytes{1}; });
  EXPECT_EQ(od.upload_size(0x2005, 0), std::nullopt);
  EXPECT_EQ(od.upload_size(0x2002, 0), std::nullopt);
  EXPECT_EQ(od.upload_size(0x3000, 0), std::nullopt);
  EXPECT_EQ(od.upload_size(0x2000, 1), std::nullopt);
}

// ---- local access ------------------------------------------------------------------------

TEST(ObjectDictionaryLocal, GetReturnsTheValueWhateverTheAccess) {
  ObjectDictionary od = sample();
  EXPECT_EQ(od.get(0x2002, 0).value(), u8(0));  // write-only
  EXPECT_EQ(od.get(0x2001, 0).value(), u32(0x12345678));
  EXPECT_EQ(abort_code(od.get(0x3000, 0).code()), 0x06020000U);
  EXPECT_EQ(abort_code(od.get(0x2000, 1).code()), 0x06090011U);
}

TEST(ObjectDictionaryLocal, SetIgnoresAccessAndHooks) {
  ObjectDictionary od = sample();
  bool called = false;
  od.on_write(0x2003, [&](SubEntry&, const Value&) -> std::error_code {
    called = true;
    return make_error_code(SdoAbort::InvalidValue);
  });
  EXPECT_FALSE(od.set(0x2003, 0, u32(99)));
  EXPECT_EQ(od.get(0x2003, 0).value(), u32(99));
  EXPECT_FALSE(called);
}

TEST(ObjectDictionaryLocal, SetOfAnotherTypeAbortsLengthMismatchAndChangesNothing) {
  ObjectDictionary od = sample();
  const auto before = snapshot(od);
  EXPECT_EQ(abort_code(od.set(0x2000, 0, u32(5))), 0x06070010U);
  // Right tag, wrong representation.
  EXPECT_EQ(abort_code(od.set(0x2000, 0, Value{DataType::Unsigned16, std::int64_t{5}})), 0x06070010U);
  EXPECT_EQ(snapshot(od), before);
  EXPECT_EQ(abort_code(od.set(0x3000, 0, u16(5))), 0x06020000U);
  EXPECT_EQ(abort_code(od.set(0x2000, 3, u16(5))), 0x06090011U);
}

TEST(ObjectDictionaryLocal, GetUnsignedOnlyForUnsignedEntries) {
  ObjectDictionary od = sample();
  EXPECT_EQ(od.get_unsigned(0x2001, 0), 0x12345678U);
  EXPECT_EQ(od.get_unsigned(0x2008, 0), 3U);
  EXPECT_EQ(od.get_unsigned(0x2006, 0), std::nullopt);
  EXPECT_EQ(od.get_unsigned(0x2005, 0), std::nullopt);
  EXPECT_EQ(od.get_unsigned(0x3000, 0), std::nullopt);
}

TEST(ObjectDictionaryObservers, RunAfterAStoredWriteOnlyAndInOrder) {
  ObjectDictionary od;
  od.insert(make_array(0x1016, "consumer heartbeat time", DataType::Unsigned32, Access::ReadWrite, 2));
  od.on_write(0x1016, [](SubEntry&, const Value& v) -> std::error_code {
    // Refuse 0xFFFFFFFF; observers must not hear about refused writes.
    return std::get<std::uint64_t>(v.data) == 0xFFFFFFFFU ? make_error_code(SdoAbort::InvalidValue) : std::error_code{};
  });
  std::vector<std::string> calls;
  od.observe(0x1016, [&](std::uint8_t sub) {
    // The new value is already stored when an observer runs.
    calls.push_back("a" + std::to_string(sub) + "=" + std::to_string(*od.get_unsigned(0x1016, sub)));
  });
  od.observe(0x1016, [&](std::uint8_t sub) { calls.push_back("b" + std::to_string(sub)); });

  const std::uint8_t ok[] = {0x2C, 0x01, 0x05, 0x00};
  ASSERT_FALSE(od.write(0x1016, 1, ok));
  const std::uint8_t refused[] = {0xFF, 0xFF, 0xFF, 0xFF};
  EXPECT_EQ(od.write(0x1016, 2, refused), make_error_code(SdoAbort::InvalidValue));
  ASSERT_FALSE(od.set(0x1016, 2, Value::of_unsigned(DataType::Unsigned32, 7)));
  EXPECT_EQ(calls, (std::vector<std::string>{"a1=327980", "b1", "a2=7", "b2"}));
}

TEST(ObjectDictionaryObservers, OtherIndexesAreNotObserved) {
  ObjectDictionary od;
  od.insert(make_var(0x1017, "producer heartbeat time", DataType::Unsigned16, Access::ReadWrite,
                     Value::of_unsigned(DataType::Unsigned16, 0)));
  od.insert(make_var(0x1006, "cycle period", DataType::Unsigned32, Access::ReadWrite,
                     Value::of_unsigned(DataType::Unsigned32, 0)));
  int calls = 0;
  od.observe(0x1017, [&](std::uint8_t) { ++calls; });
  ASSERT_FALSE(od.set(0x1006, 0, Value::of_unsigned(DataType::Unsigned32, 1000)));
  EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace canopen::od
