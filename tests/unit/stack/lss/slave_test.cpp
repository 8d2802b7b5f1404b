// Tests for stack/src/lss/slave.cpp: the slave's side of every LSS service
// byte for byte (CiA 305; facts C.1, C.2), pending vs active node-ID (facts
// C.4 item 1, D.8).
#include <gtest/gtest.h>

#include <optional>

#include "canopen/lss/slave.hpp"
#include "unit/stack/lss/lss_test_support.hpp"

namespace canopen::lss {
namespace {

using Strings = std::vector<std::string>;
using test::parse;

constexpr Identity kId{0x00000123, 0x00004567, 0x00010002, 0x0000BEEF};

class SlaveTest : public ::testing::Test {
 protected:
  explicit SlaveTest(std::uint8_t node_id = kUnconfiguredNodeId) : slave(make(node_id)) {}

  LssSlave make(std::uint8_t node_id) {
    SlaveCallbacks cb;
    cb.store = [this](std::uint8_t pending, std::optional<std::uint8_t> bt) {
      stored_node = pending;
      stored_bit_timing = bt;
      return store_answer;
    };
    cb.activate_bit_timing = [this](std::uint16_t d) { activated_delay = d; };
    cb.on_activate = [this](std::uint8_t id) { activated.push_back(id); };
    return LssSlave(kId, node_id, log.sink(), cb);
  }
  Strings rx(const std::string& frame) {
    slave.on_frame(parse(frame));
    return log.take();
  }
  void select() {
    rx("7E5#4023010000000000");
    rx("7E5#4167450000000000");
    rx("7E5#4202000100000000");
    ASSERT_EQ(rx("7E5#43EFBE0000000000"), Strings{"7E4#4400000000000000"});
  }

  test::FrameLog log;
  std::uint8_t store_answer = 0;
  std::optional<std::uint8_t> stored_node;
  std::optional<std::uint8_t> stored_bit_timing;
  std::optional<std::uint16_t> activated_delay;
  std::vector<std::uint8_t> activated;
  LssSlave slave;
};

TEST_F(SlaveTest, SwitchSelectiveNeedsAllFourPartsInOrder) {
  EXPECT_EQ(slave.mode(), Mode::Waiting);
  EXPECT_TRUE(rx("7E5#4023010000000000").empty());
  EXPECT_TRUE(rx("7E5#4167450000000000").empty());
  EXPECT_TRUE(rx("7E5#4202000100000000").empty());
  EXPECT_EQ(rx("7E5#43EFBE0000000000"), Strings{"7E4#4400000000000000"});
  EXPECT_EQ(slave.mode(), Mode::Configuration);
}

TEST_F(SlaveTest, SwitchSelectiveWithAnotherSerialIsSilent) {
  rx("7E5#4023010000000000");
  rx("7E5#4167450000000000");
  rx("7E5#4202000100000000");
  EXPECT_TRUE(rx("7E5#43EEBE0000000000").empty());
  EXPECT_EQ(slave.mode(), Mode::Waiting);
  // Out of order: the product frame without the vendor frame first.
  rx("7E5#4167450000000000");
  rx("7E5#4202000100000000");
  EXPECT_TRUE(rx("7E5#43EFBE0000000000").empty());
}

TEST_F(SlaveTest, ConfigurationServicesOnlyInConfigurationState) {
  EXPECT_TRUE(rx("7E5#1105000000000000").empty());  // waiting: configure node-ID ignored
  EXPECT_TRUE(rx("7E5#5A00000000000000").empty());
  EXPECT_EQ(slave.pending_node_id(), kUnconfiguredNodeId);
}

TEST_F(SlaveTest, ConfigureNodeIdSetsPendingAndAnswersFactsC1) {
  rx("7E5#0401000000000000");  // switch global: configuration
  EXPECT_EQ(rx("7E5#1105000000000000"), Strings{"7E4#1100000000000000"});
  EXPECT_EQ(slave.pending_node_id(), 5);
  EXPECT_EQ(slave.active_node_id(), kUnconfiguredNodeId);
  EXPECT_EQ(rx("7E5#1180000000000000"), Strings{"7E4#1101000000000000"});  // 128: out of range
  EXPECT_EQ(rx("7E5#1100000000000000"), Strings{"7E4#1101000000000000"});  // 0: out of range
  EXPECT_EQ(slave.pending_node_id(), 5);
}

TEST_F(SlaveTest, UnconfiguredDeviceBootsWithItsNodeIdWhenBackToWaitingFactsC4) {
  select();
  rx("7E5#1107000000000000");
  EXPECT_TRUE(activated.empty());
  rx("7E5#0400000000000000");
  EXPECT_EQ(activated, (std::vector<std::uint8_t>{7}));
  EXPECT_EQ(slave.active_node_id(), 7);
  EXPECT_EQ(slave.mode(), Mode::Waiting);
}

TEST_F(SlaveTest, BitTimingStoreAndActivateFactsC1) {
  select();
  EXPECT_EQ(rx("7E5#1300020000000000"), Strings{"7E4#1300000000000000"});  // 500 kbit/s
  EXPECT_EQ(slave.pending_bit_timing(), 2);
  EXPECT_EQ(rx("7E5#1300050000000000"), Strings{"7E4#1301000000000000"});  // 5: reserved
  EXPECT_EQ(rx("7E5#1301020000000000"), Strings{"7E4#1301000000000000"});  // table 1: not supported
  rx("7E5#1109000000000000");
  EXPECT_EQ(rx("7E5#1700000000000000"), Strings{"7E4#1700000000000000"});
  EXPECT_EQ(stored_node, 9);
  EXPECT_EQ(stored_bit_timing, 2);
  store_answer = 2;
  EXPECT_EQ(rx("7E5#1700000000000000"), Strings{"7E4#1702000000000000"});
  EXPECT_TRUE(rx("7E5#15E8030000000000").empty());  // unconfirmed
  EXPECT_EQ(activated_delay, 1000);
}

TEST_F(SlaveTest, InquireAnswersIdentityAndActiveNodeIdFactsC1) {
  select();
  EXPECT_EQ(rx("7E5#5A00000000000000"), Strings{"7E4#5A23010000000000"});
  EXPECT_EQ(rx("7E5#5B00000000000000"), Strings{"7E4#5B67450000000000"});
  EXPECT_EQ(rx("7E5#5C00000000000000"), Strings{"7E4#5C02000100000000"});
  EXPECT_EQ(rx("7E5#5D00000000000000"), Strings{"7E4#5DEFBE0000000000"});
  EXPECT_EQ(rx("7E5#5E00000000000000"), Strings{"7E4#5EFF000000000000"});
}

TEST_F(SlaveTest, IdentifyRemoteSlaveAnswersWhenInRangeFactsC1) {
  auto identify = [this](std::uint32_t rev_lo, std::uint32_t rev_hi, std::uint32_t ser_lo, std::uint32_t ser_hi) {
    rx(can::to_string(identify_remote_slave(cs::IdentifyVendor, kId.vendor_id)));
    rx(can::to_string(identify_remote_slave(cs::IdentifyProduct, kId.product_code)));
    rx(can::to_string(identify_remote_slave(cs::IdentifyRevisionLow, rev_lo)));
    rx(can::to_string(identify_remote_slave(cs::IdentifyRevisionHigh, rev_hi)));
    rx(can::to_string(identify_remote_slave(cs::IdentifySerialLow, ser_lo)));
    return rx(can::to_string(identify_remote_slave(cs::IdentifySerialHigh, ser_hi)));
  };
  EXPECT_EQ(identify(0, 0xFFFFFFFF, 0, 0xFFFFFFFF), Strings{"7E4#4F00000000000000"});
  EXPECT_EQ(identify(0x00010002, 0x00010002, 0xBEEF, 0xBEEF), Strings{"7E4#4F00000000000000"});
  EXPECT_TRUE(identify(0, 0xFFFFFFFF, 0xBEF0, 0xFFFFFFFF).empty());
  EXPECT_TRUE(identify(0x00010003, 0xFFFFFFFF, 0, 0xFFFFFFFF).empty());
}

TEST_F(SlaveTest, IdentifyNonConfiguredOnlyWithoutNodeIdFactsC1) {
  EXPECT_EQ(rx("7E5#4C00000000000000"), Strings{"7E4#5000000000000000"});
  select();
  rx("7E5#1103000000000000");
  EXPECT_TRUE(rx("7E5#4C00000000000000").empty());  // a pending node-ID: configured
}

TEST_F(SlaveTest, FastscanResetBitCheckAndVerifyFactsC2) {
  EXPECT_EQ(rx("7E5#5100000000800000"), Strings{"7E4#4F00000000000000"});  // reset: every unconfigured one
  // Bit 31 of the vendor-ID (123h) is 0: IDNumber 0 matches bits [31..31].
  EXPECT_EQ(rx("7E5#51000000001F0000"), Strings{"7E4#4F00000000000000"});
  // Bits [31..8] against 0x00000100: match; against 0x00000200: no answer.
  EXPECT_EQ(rx("7E5#5100010000080000"), Strings{"7E4#4F00000000000000"});
  EXPECT_TRUE(rx("7E5#5100020000080000").empty());
  // A part it is not at (product): silent.
  EXPECT_TRUE(rx("7E5#5100000000000101").empty());
  // Verify vendor, move to product.
  EXPECT_EQ(rx("7E5#5123010000000001"), Strings{"7E4#4F00000000000000"});
  EXPECT_EQ(rx("7E5#5167450000000102"), Strings{"7E4#4F00000000000000"});
  EXPECT_EQ(rx("7E5#5102000100000203"), Strings{"7E4#4F00000000000000"});
  EXPECT_EQ(slave.mode(), Mode::Waiting);
  // Last verify: LSSNext (0) < LSSSub (3) -> configuration state.
  EXPECT_EQ(rx("7E5#51EFBE0000000300"), Strings{"7E4#4F00000000000000"});
  EXPECT_EQ(slave.mode(), Mode::Configuration);
  // In configuration state fastscan is not served.
  EXPECT_TRUE(rx("7E5#5100000000800000").empty());
}

TEST_F(SlaveTest, FastscanInvalidFieldsAndShortFramesIgnoredFactsC1) {
  EXPECT_TRUE(rx("7E5#5100000000200000").empty());   // BitChecked 32
  EXPECT_TRUE(rx("7E5#5100000000800400").empty());   // LSSSub 4
  EXPECT_TRUE(rx("7E5#51000000008000").empty());     // DLC 7
  EXPECT_FALSE(slave.on_frame(parse("7E5#51000000008000")));
}

class ConfiguredSlaveTest : public SlaveTest {
 protected:
  ConfiguredSlaveTest() : SlaveTest(10) {}
};

TEST_F(ConfiguredSlaveTest, NewNodeIdOnlyAtResetCommunicationFactsD8) {
  EXPECT_TRUE(rx("7E5#5100000000800000").empty());  // configured: no fastscan
  EXPECT_TRUE(rx("7E5#4C00000000000000").empty());
  select();
  EXPECT_EQ(rx("7E5#5E00000000000000"), Strings{"7E4#5E0A000000000000"});
  rx("7E5#110C000000000000");
  rx("7E5#0400000000000000");
  EXPECT_TRUE(activated.empty());  // it has an active node-ID: it waits for reset communication
  EXPECT_EQ(slave.active_node_id(), 10);
  EXPECT_EQ(slave.reset_communication(), 12);
  EXPECT_EQ(slave.active_node_id(), 12);
}

TEST_F(ConfiguredSlaveTest, NodeIdFFhUnconfiguresAtResetCommunication) {
  select();
  EXPECT_EQ(rx("7E5#11FF000000000000"), Strings{"7E4#1100000000000000"});
  rx("7E5#0400000000000000");
  EXPECT_EQ(slave.reset_communication(), kUnconfiguredNodeId);
  EXPECT_TRUE(slave.unconfigured());
  EXPECT_EQ(rx("7E5#5100000000800000"), Strings{"7E4#4F00000000000000"});
}

TEST(LssSlaveDefaults, StoreWithoutCallbackIsNotSupportedFactsC1) {
  test::FrameLog log;
  LssSlave s(kId, 3, log.sink());
  s.on_frame(parse("7E5#0401000000000000"));
  s.on_frame(parse("7E5#1700000000000000"));
  EXPECT_EQ(log.take(), Strings{"7E4#1701000000000000"});
}

}  // namespace
}  // namespace canopen::lss
