// Tests for stack/src/lss/frames.cpp: every LSS frame byte for byte (CiA 305;
// facts C.1), and which received frames count as LSS frames.
#include <gtest/gtest.h>

#include "canopen/lss/frames.hpp"
#include "unit/stack/lss/lss_test_support.hpp"

namespace canopen::lss {
namespace {

using test::parse;
std::string text(const can::Frame& f) { return can::to_string(f); }

TEST(LssFrames, MasterRequestsFactsC1) {
  EXPECT_EQ(text(switch_state_global(Mode::Waiting)), "7E5#0400000000000000");
  EXPECT_EQ(text(switch_state_global(Mode::Configuration)), "7E5#0401000000000000");
  EXPECT_EQ(text(switch_state_selective(Part::Vendor, 0x12345678)), "7E5#4078563412000000");
  EXPECT_EQ(text(switch_state_selective(Part::Product, 1)), "7E5#4101000000000000");
  EXPECT_EQ(text(switch_state_selective(Part::Revision, 2)), "7E5#4202000000000000");
  EXPECT_EQ(text(switch_state_selective(Part::Serial, 0xAABBCCDD)), "7E5#43DDCCBBAA000000");
  EXPECT_EQ(text(configure_node_id(0x20)), "7E5#1120000000000000");
  EXPECT_EQ(text(configure_node_id(kUnconfiguredNodeId)), "7E5#11FF000000000000");
  EXPECT_EQ(text(configure_bit_timing(0, 2)), "7E5#1300020000000000");
  EXPECT_EQ(text(activate_bit_timing(0x1234)), "7E5#1534120000000000");
  EXPECT_EQ(text(store_configuration()), "7E5#1700000000000000");
  EXPECT_EQ(text(inquire_identity(Part::Vendor)), "7E5#5A00000000000000");
  EXPECT_EQ(text(inquire_identity(Part::Serial)), "7E5#5D00000000000000");
  EXPECT_EQ(text(inquire_node_id()), "7E5#5E00000000000000");
  EXPECT_EQ(text(identify_remote_slave(cs::IdentifySerialHigh, 0x01020304)), "7E5#4B04030201000000");
  EXPECT_EQ(text(identify_non_configured()), "7E5#4C00000000000000");
  EXPECT_EQ(text(fastscan({0x80000000, 31, 1, 1})), "7E5#5100000080" "1F0101");
  EXPECT_EQ(text(fastscan({0, kFastscanReset, 0, 0})), "7E5#5100000000800000");
}

TEST(LssFrames, SlaveAnswersFactsC1) {
  EXPECT_EQ(text(switch_state_selective_response()), "7E4#4400000000000000");
  EXPECT_EQ(text(configure_response(cs::ConfigureNodeId, 0)), "7E4#1100000000000000");
  EXPECT_EQ(text(configure_response(cs::ConfigureNodeId, 1)), "7E4#1101000000000000");
  // The specific byte only with error FFh (manufacturer-specific).
  EXPECT_EQ(text(configure_response(cs::StoreConfiguration, 0xFF, 7)), "7E4#17FF070000000000");
  EXPECT_EQ(text(configure_response(cs::StoreConfiguration, 2, 7)), "7E4#1702000000000000");
  EXPECT_EQ(text(inquire_identity_response(Part::Product, 0x0A0B0C0D)), "7E4#5B0D0C0B0A000000");
  EXPECT_EQ(text(inquire_node_id_response(5)), "7E4#5E05000000000000");
  EXPECT_EQ(text(identify_slave_response()), "7E4#4F00000000000000");
  EXPECT_EQ(text(identify_non_configured_response()), "7E4#5000000000000000");
}

TEST(LssFrames, OnlyWellFormedFramesAreLssFactsC1) {
  EXPECT_TRUE(is_master_frame(parse("7E5#0400000000000000")));
  EXPECT_FALSE(is_master_frame(parse("7E5#04000000000000")));  // DLC 7: CANopenNode's slave ignores it
  EXPECT_FALSE(is_master_frame(parse("7E5#R8")));
  EXPECT_FALSE(is_master_frame(parse("000007E5#0400000000000000")));  // 29-bit id
  EXPECT_FALSE(is_master_frame(parse("7E4#0400000000000000")));
  EXPECT_TRUE(is_slave_frame(parse("7E4#4F00000000000000")));
  EXPECT_FALSE(is_slave_frame(parse("7E4#4F")));
}

TEST(LssFrames, FastscanFieldsRoundTrip) {
  const FastscanFields f{0xDEADBEEF, 5, 2, 3};
  EXPECT_EQ(fastscan_fields(fastscan(f)), f);
  EXPECT_EQ(u32(parse("7E5#4078563412000000")), 0x12345678U);
}

TEST(LssFrames, BitTimingTable0IsCia301Rates) {
  EXPECT_EQ(bit_timing_index(1'000'000), 0);
  EXPECT_EQ(bit_timing_index(500'000), 2);
  EXPECT_EQ(bit_timing_index(125'000), 4);
  EXPECT_EQ(bit_timing_index(10'000), 8);
  EXPECT_FALSE(bit_timing_index(100'000).has_value());  // index 5 is reserved
  EXPECT_FALSE(bit_timing_index(0).has_value());
  EXPECT_EQ(bit_rate_of_index(3), 250'000U);
  EXPECT_FALSE(bit_rate_of_index(5).has_value());
  EXPECT_FALSE(bit_rate_of_index(kBitTimingAuto).has_value());
}

TEST(LssFrames, IdentityOrderIsVendorFirst) {
  const Identity a{1, 9, 9, 9}, b{2, 0, 0, 0};
  EXPECT_LT(a, b);
  Identity c;
  c.set_part(Part::Serial, 42);
  EXPECT_EQ(c.part(Part::Serial), 42U);
  EXPECT_EQ(to_string(Identity{0x123, 1, 2, 3}),
            "vendor 0x00000123 product 0x00000001 revision 0x00000002 serial 0x00000003");
}

TEST(LssFrames, IdentityRangeIsExactVendorProductAndInclusiveRanges) {
  const IdentityRange r{7, 8, 1, 3, 100, 200};
  EXPECT_TRUE(r.contains({7, 8, 1, 100}));
  EXPECT_TRUE(r.contains({7, 8, 3, 200}));
  EXPECT_FALSE(r.contains({7, 8, 4, 150}));
  EXPECT_FALSE(r.contains({7, 9, 2, 150}));
}

}  // namespace
}  // namespace canopen::lss
