// The one way object addresses, hex and path numbers are written and read.
#include "core/format.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace gateway::core {
namespace {

TEST(Format, ObjectAddresses) {
  EXPECT_EQ(index_text(0x1017), "1017h");
  EXPECT_EQ(index_text(0x00A), "000Ah");
  EXPECT_EQ(object_label(0x1017, 0), "1017h sub 0");
  EXPECT_EQ(object_label(0x6041, 255), "6041h sub 255");
}

TEST(Format, FixedWidthHexKeepsWiderValues) {
  EXPECT_EQ(hex_number(0x0A, 2), "0A");
  EXPECT_EQ(hex_number(0x1017, 4), "1017");
  EXPECT_EQ(hex_number(0x1017, 2), "1017");
  EXPECT_EQ(hex_number(0, 4), "0000");
  EXPECT_EQ(hex_number(0xFFFFFFFF, 4), "FFFFFFFF");
  EXPECT_EQ(abort_code_text(0x06020000), "0x06020000");
  EXPECT_EQ(abort_code_text(0x0504000A), "0x0504000A");
}

TEST(Format, BytesLowerForTheApiUpperForLogs) {
  const std::vector<std::uint8_t> b = {0x0f, 0x00, 0xAB};
  EXPECT_EQ(hex_bytes(b), "0f00ab");
  EXPECT_EQ(hex_bytes(b, HexCase::upper), "0F00AB");
  EXPECT_EQ(hex_bytes({}), "");
  std::string out = "raw ";
  append_hex(out, b);
  EXPECT_EQ(out, "raw 0f00ab");
}

TEST(Format, DecimalPathNumbers) {
  EXPECT_EQ(parse_decimal("1"), 1u);
  EXPECT_EQ(parse_decimal("127"), 127u);
  EXPECT_EQ(parse_decimal("999999999"), 999999999u);
  EXPECT_FALSE(parse_decimal("1234567890")) << "at most 9 digits";
  EXPECT_FALSE(parse_decimal(""));
  EXPECT_FALSE(parse_decimal("+1"));
  EXPECT_FALSE(parse_decimal("-1"));
  EXPECT_FALSE(parse_decimal(" 1"));
  EXPECT_FALSE(parse_decimal("0x10"));
}

}  // namespace
}  // namespace gateway::core
