#include "canopen/pdo/mapping.hpp"

#include <gtest/gtest.h>

#include "unit/stack/pdo/pdo_test_util.hpp"

namespace canopen::pdo {
namespace {

using test::add_comm;
using test::add_map;
using test::add_var;

TEST(PdoMapping, Pdo_7_4_8_1_CobIdBitsAndCommParams) {
  od::ObjectDictionary d;
  add_comm(d, Direction::Transmit, 2, 0xE0000123U, 3, 50, 100, 7);
  auto c = read_comm_params(d, Direction::Transmit, 2);
  ASSERT_TRUE(c);
  EXPECT_FALSE(c->cob_id.valid());
  EXPECT_FALSE(c->cob_id.rtr_allowed());
  EXPECT_TRUE(c->cob_id.extended());
  EXPECT_EQ(c->cob_id.can_id(), 0x123U);
  EXPECT_EQ(c->transmission_type, 3);
  EXPECT_EQ(c->inhibit_time, 50);
  EXPECT_EQ(c->event_timer, 100);
  EXPECT_EQ(c->sync_start, 7);
  EXPECT_TRUE(c->cyclic());
  EXPECT_EQ(comm_index(Direction::Receive, 1), 0x1400);
  EXPECT_EQ(mapping_index(Direction::Transmit, 512), 0x1BFF);
  EXPECT_FALSE(read_comm_params(d, Direction::Transmit, 1));
}

TEST(PdoMapping, Pdo_BitLevelMappingWithDummyEntries) {
  od::ObjectDictionary d;
  add_var(d, 0x2000, "Flag", DataType::Boolean);
  add_var(d, 0x2001, "Byte", DataType::Unsigned8);
  add_var(d, 0x2002, "Word", DataType::Integer16);
  add_comm(d, Direction::Transmit, 1, 0x181);
  // BOOLEAN, two 1-bit dummies, U8 at bit 3, a 16-bit dummy, I16 at bit 27.
  add_map(d, Direction::Transmit, 1, {0x20000001, 0x00010001, 0x00010001, 0x20010008, 0x00060010, 0x20020010});
  auto cfg = read_pdo(d, Direction::Transmit, 1);
  ASSERT_TRUE(cfg) << cfg.error().detail;
  EXPECT_EQ(cfg->total_bits(), 43U);
  EXPECT_EQ(cfg->byte_length(), 6U);
  EXPECT_TRUE(cfg->entries[1].dummy);
  EXPECT_EQ(bit_offset_of(*cfg, 0x2001, 0), 3U);

  const Bytes payload{0x59, 0x05, 0x00, 0xF0, 0xFF, 0x07};
  auto values = unpack(*cfg, payload);
  ASSERT_TRUE(values);
  ASSERT_EQ(values->size(), 3U);  // dummies give no value
  EXPECT_EQ((*values)[0].value, Value::of_bool(true));
  EXPECT_EQ((*values)[0].name, "Flag");
  EXPECT_EQ((*values)[1].value, Value::of_unsigned(DataType::Unsigned8, 0xAB));
  EXPECT_EQ((*values)[2].value, Value::of_signed(DataType::Integer16, -2));

  Bytes out(6, 0);
  EXPECT_FALSE(pack_value(Value::of_bool(true), out, 0, 1));
  EXPECT_FALSE(pack_value(Value::of_unsigned(DataType::Unsigned8, 0xAB), out, 3, 8));
  EXPECT_FALSE(pack_value(Value::of_signed(DataType::Integer16, -2), out, 27, 16));
  EXPECT_EQ(out, payload);
}

TEST(PdoMapping, Pdo_SixtyFourEntriesOfOneBit) {
  od::ObjectDictionary d;
  d.insert(od::make_array(0x2100, "Inputs", DataType::Boolean, od::Access::ReadWrite, 64));
  std::vector<std::uint32_t> map;
  for (std::uint32_t s = 1; s <= 64; ++s) map.push_back(0x21000001U | s << 8);
  add_comm(d, Direction::Transmit, 1, 0x181);
  add_map(d, Direction::Transmit, 1, map);
  auto cfg = read_pdo(d, Direction::Transmit, 1);
  ASSERT_TRUE(cfg) << cfg.error().detail;
  EXPECT_EQ(cfg->entries.size(), 64U);
  const Bytes payload{0x01, 0x02, 0x04, 0x08, 0x10, 0x20, 0x40, 0x80};
  auto values = unpack(*cfg, payload);
  ASSERT_TRUE(values);
  ASSERT_EQ(values->size(), 64U);
  for (std::size_t i = 0; i < 64; ++i)
    EXPECT_EQ((*values)[i].value, Value::of_bool(i % 9 == 0)) << "bit " << i;  // bit 8k+k set
  EXPECT_EQ((*values)[63].sub, 64);
}

TEST(PdoMapping, Pdo_7_4_8_2_SixtyFiveEntriesOrTooLongRefused) {
  od::ObjectDictionary d;
  add_var(d, 0x2000, "Big", DataType::Unsigned64);
  add_comm(d, Direction::Transmit, 1, 0x181);
  add_map(d, Direction::Transmit, 1, {0x20000040, 0x00050008});  // 72 bits
  EXPECT_EQ(read_pdo(d, Direction::Transmit, 1).code(), make_error_code(SdoAbort::PdoLengthExceeded));
  EXPECT_TRUE(read_pdo(d, Direction::Transmit, 1, 64));  // fits CAN FD
  add_map(d, Direction::Transmit, 1, std::vector<std::uint32_t>(65, 0x00010001));
  EXPECT_EQ(read_pdo(d, Direction::Transmit, 1, 64).code(), make_error_code(SdoAbort::PdoLengthExceeded));
}

TEST(PdoMapping, Pdo_7_4_8_2_MappedLengthMustMatchType) {
  od::ObjectDictionary d;
  add_var(d, 0x2000, "Word", DataType::Unsigned16);
  add_comm(d, Direction::Transmit, 1, 0x181);
  add_map(d, Direction::Transmit, 1, {0x20000008});
  EXPECT_EQ(read_pdo(d, Direction::Transmit, 1).code(), make_error_code(SdoAbort::LengthMismatch));
  add_map(d, Direction::Transmit, 1, {0x30000010});
  auto r = read_pdo(d, Direction::Transmit, 1);
  EXPECT_EQ(r.code(), make_error_code(SdoAbort::NoSuchObject));
  EXPECT_NE(r.error().detail.find("3000h"), std::string::npos) << r.error().detail;
}

TEST(PdoMapping, Pdo_7_2_3_MpdoMappingKinds) {
  od::ObjectDictionary d;
  add_comm(d, Direction::Transmit, 1, 0x181);
  add_map(d, Direction::Transmit, 1, {}, 0xFE);
  auto cfg = read_pdo(d, Direction::Transmit, 1);
  ASSERT_TRUE(cfg);
  EXPECT_EQ(cfg->kind, MappingKind::SamMpdo);
  EXPECT_EQ(cfg->byte_length(), 8U);
  add_map(d, Direction::Transmit, 1, {}, 0xFF);
  EXPECT_EQ(read_pdo(d, Direction::Transmit, 1)->kind, MappingKind::DamMpdo);
}

TEST(PdoMapping, Pdo_BitHelpersAcrossByteBoundaries) {
  Bytes b(3, 0xFF);
  insert_bits(b, 5, 10, 0);
  EXPECT_EQ(b, (Bytes{0x1F, 0x80, 0xFF}));
  insert_bits(b, 5, 10, 0x2AA);
  EXPECT_EQ(extract_bits(b, 5, 10), 0x2AAU);
  Bytes r32(4, 0);
  EXPECT_FALSE(pack_value(Value::of_real32(1.0F), r32, 0, 32));
  EXPECT_EQ(r32, (Bytes{0x00, 0x00, 0x80, 0x3F}));
  EXPECT_EQ(pack_value(Value::of_unsigned(DataType::Unsigned8, 1), r32, 30, 8),
            make_error_code(SdoAbort::PdoLengthExceeded));
}

}  // namespace
}  // namespace canopen::pdo
