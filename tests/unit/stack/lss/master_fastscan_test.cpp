// Tests for stack/src/lss/master_fastscan.cpp: fastscan and assign-all
// against 1..4 LssSlaves on an in-memory bus with a fake clock (facts C.2,
// C.4 item 1): the lowest identity first, 133 exchanges for a full scan,
// an empty bus costs one step window, a lost answer in the middle of a scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <optional>

#include "canopen/lss/master.hpp"
#include "unit/stack/lss/lss_test_support.hpp"

namespace canopen::lss {
namespace {

using namespace std::chrono_literals;
using test::LssBus;

// Identities that differ in every part, listed in no particular order.
const std::vector<Identity> kDevices{
    {0x00000123, 0x00004567, 0x00010002, 0x0000BEEF},
    {0x00000123, 0x00004567, 0x00010002, 0x0000BEE0},  // same but the serial's low bits
    {0x00000100, 0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF},  // lowest vendor
    {0x80000000, 0x00000001, 0x00000000, 0x00000000},  // vendor bit 31 set
};

std::optional<FastscanResult> scan(LssBus& b, const FastscanRequest& r = {}) {
  std::optional<FastscanResult> got;
  EXPECT_FALSE(b.master.fastscan(r, [&](const FastscanResult& res) { got = res; }, b.clock.now()));
  b.run();
  return got;
}

TEST(LssFastscan, EmptyBusCostsOneStepWindowFactsC2) {
  LssBus b;
  const TimePoint start = b.clock.now();
  const auto r = scan(b);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->error, make_error_code(LssError::NoUnconfiguredSlave));
  EXPECT_EQ(r->exchanges, 1U);  // only the reset (BitChecked 80h), not 133
  EXPECT_EQ(b.clock.now() - start, 100ms);
}

TEST(LssFastscan, StepTimeoutIsConfigurablePerScan) {
  LssBus b;
  const TimePoint start = b.clock.now();
  FastscanRequest req;
  req.step_timeout = 25ms;
  const auto r = scan(b, req);
  EXPECT_EQ(b.clock.now() - start, 25ms);
  EXPECT_EQ(r->error, make_error_code(LssError::NoUnconfiguredSlave));
}

TEST(LssFastscan, FullScanOfOneDeviceIs133ExchangesFactsC2) {
  LssBus b;
  auto& node = b.add_slave(kDevices[0]);
  const TimePoint start = b.clock.now();
  const auto r = scan(b);
  ASSERT_TRUE(r);
  ASSERT_FALSE(r->error) << r->error.message();
  EXPECT_EQ(r->identity, kDevices[0]);
  EXPECT_EQ(r->exchanges, 133U);  // 1 + 4 x 32 + 4
  EXPECT_EQ(r->restarts, 0U);
  EXPECT_EQ(b.clock.now() - start, 133 * 100ms);  // every step waits its window
  EXPECT_EQ(node.slave->mode(), Mode::Configuration);  // found and selected
}

TEST(LssFastscan, ConfiguredDevicesDoNotAnswerFactsD7) {
  LssBus b;
  b.add_slave(kDevices[0], 5);
  const auto r = scan(b);
  EXPECT_EQ(r->error, make_error_code(LssError::NoUnconfiguredSlave));
}

TEST(LssFastscan, MatchAndSkipPartsSaveSteps) {
  LssBus b;
  b.add_slave(kDevices[0]);
  FastscanRequest req;
  req.parts = {PartScan::Match, PartScan::Scan, PartScan::Skip, PartScan::Scan};
  req.known.vendor_id = kDevices[0].vendor_id;
  const auto r = scan(b, req);
  ASSERT_FALSE(r->error) << r->error.message();
  EXPECT_EQ(r->exchanges, 1U + 1 + 33 + 33);  // reset, vendor verify, product, serial
  EXPECT_EQ(r->identity, (Identity{kDevices[0].vendor_id, kDevices[0].product_code, 0, kDevices[0].serial}));
}

TEST(LssFastscan, MatchOfAnAbsentValueFailsAfterRestarts) {
  LssBus b({.timeout = 1s, .scan_step_timeout = 100ms, .queue_limit = 16, .fastscan_restarts = 1});
  b.add_slave(kDevices[0]);
  FastscanRequest req;
  req.parts[0] = PartScan::Match;
  req.known.vendor_id = 0x999;
  const auto r = scan(b, req);
  EXPECT_EQ(r->error, make_error_code(LssError::ScanFailed));
  EXPECT_EQ(r->restarts, 1U);
  EXPECT_EQ(r->exchanges, 4U);  // (reset + verify) twice
}

TEST(LssFastscan, SkipsTheProtocolCannotDoAreRejected) {
  LssBus b;
  FastscanRequest vendor_skipped;
  vendor_skipped.parts[0] = PartScan::Skip;
  EXPECT_EQ(b.master.fastscan(vendor_skipped, nullptr, b.clock.now()), std::errc::invalid_argument);
  FastscanRequest only_vendor;
  only_vendor.parts = {PartScan::Scan, PartScan::Skip, PartScan::Skip, PartScan::Skip};
  EXPECT_EQ(b.master.fastscan(only_vendor, nullptr, b.clock.now()), std::errc::invalid_argument);
  EXPECT_FALSE(b.master.busy());
}

// Fastscan and assign-all with 1, 2, 3 and 4 unconfigured devices.
class LssFastscanDevices : public ::testing::TestWithParam<std::size_t> {};

TEST_P(LssFastscanDevices, FindsTheLowestIdentityFirstFactsC2) {
  LssBus b;
  const std::size_t n = GetParam();
  for (std::size_t i = 0; i < n; ++i) b.add_slave(kDevices[i]);
  const auto r = scan(b);
  ASSERT_FALSE(r->error) << r->error.message();
  EXPECT_EQ(r->identity, *std::min_element(kDevices.begin(), kDevices.begin() + static_cast<long>(n)));
  EXPECT_EQ(r->exchanges, 133U);
  // Exactly that one is in configuration state.
  for (const auto& node : b.nodes)
    EXPECT_EQ(node->slave->mode() == Mode::Configuration, node->slave->identity() == r->identity);
}

TEST_P(LssFastscanDevices, AssignAllGivesEachANodeIdInIdentityOrderFactsC4) {
  LssBus b;
  const std::size_t n = GetParam();
  for (std::size_t i = 0; i < n; ++i) b.add_slave(kDevices[i]);
  std::optional<AssignAllResult> got;
  AssignAllRequest req;
  req.first_node_id = 10;
  req.in_use = {11};  // already on the bus: skipped
  const TimePoint start = b.clock.now();
  ASSERT_FALSE(b.master.assign_all(req, [&](const AssignAllResult& r) { got = r; }, b.clock.now()));
  const std::size_t windows = b.run();
  ASSERT_TRUE(got);
  EXPECT_FALSE(got->error) << got->error.message();
  ASSERT_EQ(got->assigned.size(), n);
  std::vector<Identity> sorted(kDevices.begin(), kDevices.begin() + static_cast<long>(n));
  std::sort(sorted.begin(), sorted.end());
  const std::vector<std::uint8_t> ids{10, 12, 13, 14};
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(got->assigned[i].identity, sorted[i]);
    EXPECT_EQ(got->assigned[i].node_id, ids[i]);
    EXPECT_TRUE(got->assigned[i].stored);
  }
  // Each device took its node-ID when switched back to waiting (booted with it), and stored it.
  for (const auto& node : b.nodes) {
    const auto it = std::find_if(got->assigned.begin(), got->assigned.end(),
                                 [&](const Assignment& a) { return a.identity == node->slave->identity(); });
    ASSERT_NE(it, got->assigned.end());
    EXPECT_EQ(node->activated, std::vector<std::uint8_t>{it->node_id});
    EXPECT_EQ(node->stored, it->node_id);
    EXPECT_EQ(node->slave->mode(), Mode::Waiting);
  }
  // Frames: the first switch to waiting, per device a full fastscan (133) +
  // configure + store + switch to waiting, and the last scan's reset.
  EXPECT_EQ(got->exchanges, 2 + 136 * n);
  // Time: 133 step windows per device plus the last, unanswered reset.
  EXPECT_EQ(windows, 133 * n + 1);
  EXPECT_EQ(b.clock.now() - start, (133 * static_cast<long>(n) + 1) * 100ms);
}

INSTANTIATE_TEST_SUITE_P(OneToFour, LssFastscanDevices, ::testing::Values(1, 2, 3, 4));

TEST(LssAssignAll, EmptyBusAssignsNothingInOneWindow) {
  LssBus b;
  std::optional<AssignAllResult> got;
  ASSERT_FALSE(b.master.assign_all({}, [&](const AssignAllResult& r) { got = r; }, b.clock.now()));
  EXPECT_EQ(b.run(), 1U);
  EXPECT_FALSE(got->error);
  EXPECT_TRUE(got->assigned.empty());
}

TEST(LssAssignAll, StopsWithNoFreeNodeIdAndLeavesTheRestWaiting) {
  LssBus b;
  b.add_slave(kDevices[0]);
  b.add_slave(kDevices[1]);
  std::optional<AssignAllResult> got;
  AssignAllRequest req;
  req.node_ids = {42};
  req.store = false;
  ASSERT_FALSE(b.master.assign_all(req, [&](const AssignAllResult& r) { got = r; }, b.clock.now()));
  b.run();
  EXPECT_EQ(got->error, make_error_code(LssError::NoFreeNodeId));
  ASSERT_EQ(got->assigned.size(), 1U);
  EXPECT_EQ(got->assigned[0].node_id, 42);
  EXPECT_FALSE(got->assigned[0].stored);
  for (const auto& node : b.nodes) EXPECT_EQ(node->slave->mode(), Mode::Waiting);
}

TEST(LssAssignAll, InvalidNodeIdsAreRejected) {
  LssBus b;
  AssignAllRequest req;
  req.node_ids = {5, 128};
  EXPECT_EQ(b.master.assign_all(req, nullptr, b.clock.now()), std::errc::invalid_argument);
  AssignAllRequest first;
  first.first_node_id = 0;
  EXPECT_EQ(b.master.assign_all(first, nullptr, b.clock.now()), std::errc::invalid_argument);
}

// A lost answer: in a bit step it reads as bit 1, the verify step gets no
// answer and the scan restarts from the reset (documented in master.hpp).
TEST(LssFastscanLoss, LostBitAnswerRestartsAndStillFindsTheDeviceFactsC2) {
  LssBus b;
  b.add_slave(kDevices[0]);  // vendor 0x123: bits 31..9 are 0, so answered
  std::uint64_t slave_answers = 0;
  can::BusFaults faults;
  faults.verdict = [&](const can::Frame& f, std::uint64_t) {
    // Answer 1 is the reset's; answer 10 is the one to the bit-23 step.
    if (f.id == kSlaveCobId && ++slave_answers == 10) return can::FrameVerdict::Drop;
    return can::FrameVerdict::Deliver;
  };
  b.bus.set_faults(faults);
  const auto r = scan(b);
  ASSERT_FALSE(r->error) << r->error.message();
  EXPECT_EQ(r->identity, kDevices[0]);
  EXPECT_EQ(r->restarts, 1U);
  // The vendor part failed at its verify: reset + 32 bits + verify, then a full scan.
  EXPECT_EQ(r->exchanges, 34U + 133U);
  EXPECT_EQ(b.bus.frames_lost(), 1U);
}

TEST(LssFastscanLoss, LostLastVerifyAnswerSwitchesBackToWaitingAndRescans) {
  LssBus b;
  auto& node = b.add_slave(kDevices[0]);
  std::optional<FastscanFields> last_request;
  bool dropped = false;
  can::BusFaults faults;
  faults.verdict = [&](const can::Frame& f, std::uint64_t) {
    if (f.id == kMasterCobId && command(f) == cs::Fastscan) last_request = fastscan_fields(f);
    // The answer to the serial's verify (LSSSub 3, LSSNext 0): the slave is
    // already in configuration state, the master does not know it.
    if (f.id == kSlaveCobId && !dropped && last_request && last_request->bit_checked == 0 &&
        last_request->sub == 3) {
      dropped = true;
      return can::FrameVerdict::Drop;
    }
    return can::FrameVerdict::Deliver;
  };
  b.bus.set_faults(faults);
  const auto r = scan(b);
  ASSERT_FALSE(r->error) << r->error.message();
  EXPECT_EQ(r->identity, kDevices[0]);
  EXPECT_EQ(r->restarts, 1U);
  EXPECT_EQ(r->exchanges, 266U);
  EXPECT_EQ(node.slave->mode(), Mode::Configuration);
}

TEST(LssFastscanLoss, WithoutRestartsALostAnswerIsAClearFailure) {
  LssBus b({.timeout = 1s, .scan_step_timeout = 100ms, .queue_limit = 16, .fastscan_restarts = 0});
  b.add_slave(kDevices[0]);
  std::uint64_t slave_answers = 0;
  can::BusFaults faults;
  faults.verdict = [&](const can::Frame& f, std::uint64_t) {
    if (f.id == kSlaveCobId && ++slave_answers == 10) return can::FrameVerdict::Drop;
    return can::FrameVerdict::Deliver;
  };
  b.bus.set_faults(faults);
  const auto r = scan(b);
  EXPECT_EQ(r->error, make_error_code(LssError::ScanFailed));
  EXPECT_EQ(r->exchanges, 34U);
  EXPECT_EQ(r->error.message(), "LSS fastscan failed: no slave answered a verify step");
}

TEST(LssFastscanLoss, CancelledScanReportsItsSteps) {
  LssBus b;
  b.add_slave(kDevices[0]);
  std::optional<FastscanResult> got;
  ASSERT_FALSE(b.master.fastscan({}, [&](const FastscanResult& r) { got = r; }, b.clock.now()));
  b.bus.deliver();
  b.clock.advance(100ms);
  b.master.on_time(b.clock.now());  // the reset's window: first bit step sent
  b.master.cancel_all(b.clock.now());
  ASSERT_TRUE(got);
  EXPECT_EQ(got->error, make_error_code(LssError::Cancelled));
  EXPECT_EQ(got->exchanges, 2U);
}

}  // namespace
}  // namespace canopen::lss
