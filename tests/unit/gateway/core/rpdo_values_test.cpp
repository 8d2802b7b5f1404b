// An RPDO write's values typed against the RPDO's mapping (CiA 301 7.5.2.36
// RPDO mapping): the core's half of PUT .../rpdo/{n} and Sparkplug writes.
#include "core/rpdo_values.hpp"

#include <gtest/gtest.h>

namespace gateway::core {
namespace {

using CT = canopen::DataType;

canopen::pdo::PdoConfig two_bytes() {
  canopen::pdo::PdoConfig p;
  canopen::pdo::MappingEntry a;
  a.index = 0x6200;
  a.sub = 1;
  a.type = CT::Unsigned8;
  a.bits = 8;
  canopen::pdo::MappingEntry b = a;
  b.sub = 2;
  p.entries = {a, b};
  return p;
}

TEST(RpdoValues, LiteralsAreTypedByTheMappingAndRawMustHaveItsLength) {
  const auto pdo = two_bytes();
  const canopen::od::ObjectDictionary od;
  std::string error;
  RpdoWrite w{5, 1, {RpdoItem{0x6200, 2, canopen::Literal(7), {}}}, {}, {}};
  auto body = typed_rpdo_values(w, pdo, od, "node 5 RPDO1", error);
  ASSERT_TRUE(body) << error;
  ASSERT_EQ(body->values.size(), 1u);
  EXPECT_EQ(body->values[0].value, canopen::Value::of_unsigned(CT::Unsigned8, 7));
  RpdoWrite raw{5, 1, {}, canopen::Bytes{1, 2, 3}, {}};
  EXPECT_FALSE(typed_rpdo_values(raw, pdo, od, "node 5 RPDO1", error));
  EXPECT_EQ(error, "node 5 RPDO1 carries 2 bytes, not 3");
}

// Items are checked in order: a malformed item after an unmapped one is
// not what the caller hears first (as when REST parsed the body itself).
TEST(RpdoValues, ItemsAreCheckedInTheOrderSent) {
  const auto pdo = two_bytes();
  const canopen::od::ObjectDictionary od;
  std::string error;
  RpdoWrite w{5, 1, {RpdoItem{0x6000, 1, canopen::Literal(1), {}}, RpdoItem{0, 0, {}, "malformed"}}, {}, {}};
  EXPECT_FALSE(typed_rpdo_values(w, pdo, od, "node 5 RPDO1", error));
  EXPECT_EQ(error, "node 5 RPDO1 does not map 6000h sub 1");
  w.values[0].index = 0x6200;
  EXPECT_FALSE(typed_rpdo_values(w, pdo, od, "node 5 RPDO1", error));
  EXPECT_EQ(error, "malformed");
  EXPECT_FALSE(typed_rpdo_values(RpdoWrite{5, 1, {}, {}, "the body needs \"values\""}, pdo, od, "x", error));
  EXPECT_EQ(error, "the body needs \"values\"");
}

TEST(RpdoValues, TypedValuesMustHaveTheMappedTypeAndFitIt) {
  const auto pdo = two_bytes();
  const canopen::od::ObjectDictionary od;
  std::string error;
  RpdoWrite w{5, 1, {RpdoItem{0x6200, 1, canopen::Value::of_unsigned(CT::Unsigned16, 7), {}}}, {}, {}};
  EXPECT_FALSE(typed_rpdo_values(w, pdo, od, "node 5 RPDO1", error));
  EXPECT_EQ(error, "6200h sub 1: a u16 value for an object node 5 RPDO1 maps as u8");
  w.values[0].value = canopen::Literal(300);
  EXPECT_FALSE(typed_rpdo_values(w, pdo, od, "node 5 RPDO1", error));
  EXPECT_EQ(error, "6200h sub 1: 300 is above 255 (u8)");
}

}  // namespace
}  // namespace gateway::core
