// Issue 17: maintenance transfers on canopen::Network (DCF read-back, DCF
// apply, CiA 302-3 program download) against a simulated I/O module over
// the in-memory bus with the fake clock: TransferEvents in the network's
// own numbered stream, one transfer per node, and PDO parameters written by
// an apply followed by the decoder (CiA 301 7.5.2.35-7.5.2.39).
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "network_rig.hpp"
#include "sim/device_objects.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kNode = test::NetworkRig::kNode;

// The gateway's network and a CiA 401 I/O module with the simulator's
// CiA 302-3 program objects, powered on.
struct Rig : test::NetworkRig {
  Rig() : NetworkRig("deploy/eds/cia401-io-module.eds") {
    sim::install_program_objects(device_od);
    power_on();
    run_for(10ms);
  }
  std::vector<std::pair<std::uint64_t, TransferEvent>> transfers() const { return events_of<TransferEvent>(); }
};

TEST(NetworkTransfer, ReadDcf_TransferEventsInTheNetworksNumberedStream_ThenTheDcfText) {
  Rig rig;
  std::optional<master::DcfReadReport> report;
  ASSERT_FALSE(rig.net.read_dcf(kNode, rig.eds, [&](const master::DcfReadReport& r) { report = r; },
                                rig.clock.now()));
  EXPECT_TRUE(rig.net.transfer_busy(kNode));
  rig.run_for(5s);
  ASSERT_TRUE(report.has_value());
  EXPECT_FALSE(rig.net.transfer_busy(kNode));
  const auto t = rig.transfers();
  ASSERT_GE(t.size(), 2U);
  for (std::size_t i = 1; i < t.size(); ++i) EXPECT_GT(t[i].first, t[i - 1].first) << "seq goes up";
  EXPECT_EQ(t.front().second.status, TransferEvent::Status::Running);
  EXPECT_EQ(t.front().second.operation, TransferEvent::Operation::DcfRead);
  EXPECT_EQ(t.front().second.node, kNode);
  EXPECT_EQ(t.back().second.status, TransferEvent::Status::Done);
  EXPECT_EQ(rig.events.back().seq, rig.net.last_seq());
  const auto dcf = eds::parse_device_description(master::write_dcf(rig.eds, kNode, report->values), "node5.dcf");
  EXPECT_EQ(dcf.od.get_unsigned(0x1800, 1), rig.device_od.get_unsigned(0x1800, 1));
}

TEST(NetworkTransfer, OneTransferPerNode_BusyWhateverTheKind_OtherNodesFree) {
  Rig rig;
  ASSERT_FALSE(rig.net.read_dcf(kNode, rig.eds, nullptr, rig.clock.now()));
  EXPECT_EQ(rig.net.download_program(kNode, {}, Bytes{1, 2, 3}, nullptr, rig.clock.now()),
            master::TransferError::Busy);
  EXPECT_EQ(rig.net.apply_dcf(kNode, rig.eds, {}, nullptr, rig.clock.now()), master::TransferError::Busy);
  EXPECT_EQ(rig.net.read_dcf(kNode, rig.eds, nullptr, rig.clock.now()), master::TransferError::Busy);
  EXPECT_EQ(rig.net.read_dcf(0, rig.eds, nullptr, rig.clock.now()), master::TransferError::BadNode);
  EXPECT_EQ(rig.net.read_dcf(128, rig.eds, nullptr, rig.clock.now()), master::TransferError::BadNode);
  // Another node may run its own (it times out: nobody answers there).
  EXPECT_FALSE(rig.net.download_program(6, {}, Bytes{1, 2, 3}, nullptr, rig.clock.now()));
  EXPECT_TRUE(rig.net.cancel_transfer(kNode, rig.clock.now()));
  EXPECT_FALSE(rig.net.transfer_busy(kNode));
  EXPECT_EQ(rig.transfers().back().second.status, TransferEvent::Status::Failed);
}

// 7.5.2.35/7.5.2.39: a DCF apply that remaps TPDO1 changes what the gateway
// decodes, as any SDO download to 1A00h does.
TEST(NetworkTransfer, ApplyDcfRemappingATpdo_TheDecoderFollows) {
  Rig rig;
  ASSERT_TRUE(rig.net.add_node(kNode, rig.eds.od).empty());
  ASSERT_EQ(rig.net.pdo().tpdo(kNode, 1)->entries.size(), 1U);
  std::map<master::ObjectAddress, Value> values;
  for (const auto& a : master::configurable_objects(rig.eds)) values.emplace(a, rig.eds.od.find(a.index, a.sub)->value);
  values[{0x1A00, 0}] = Value::of_unsigned(DataType::Unsigned8, 2);
  values[{0x1A00, 2}] = Value::of_unsigned(DataType::Unsigned32, 0x64010110);  // analogue input 1 (i16)
  const auto dcf = eds::parse_device_description(master::write_dcf(rig.eds, kNode, values), "node5.dcf");
  std::optional<master::DcfApplyReport> report;
  ASSERT_FALSE(rig.net.apply_dcf(kNode, dcf, {}, [&](const master::DcfApplyReport& r) { report = r; },
                                 rig.clock.now()));
  rig.run_for(5s);
  ASSERT_TRUE(report.has_value());
  EXPECT_EQ(report->failed, 0U);
  const pdo::PdoConfig* tpdo1 = rig.net.pdo().tpdo(kNode, 1);
  ASSERT_NE(tpdo1, nullptr);
  ASSERT_EQ(tpdo1->entries.size(), 2U);
  EXPECT_EQ(tpdo1->entries[1].index, 0x6401);
  EXPECT_TRUE(tpdo1->comm.cob_id.valid()) << "enabled again at the end";
  EXPECT_EQ(rig.transfers().back().second.operation, TransferEvent::Operation::DcfApply);
  EXPECT_EQ(rig.transfers().back().second.status, TransferEvent::Status::Done);
}

TEST(NetworkTransfer, DownloadProgram_ProgressAndDoneInTheStream_DeviceRunsTheImage) {
  Rig rig;
  Bytes image(10000);
  for (std::size_t i = 0; i < image.size(); ++i) image[i] = static_cast<std::uint8_t>(i % 251);
  std::optional<master::ProgramDownloadReport> report;
  ASSERT_FALSE(rig.net.download_program(kNode, {}, image, [&](const master::ProgramDownloadReport& r) { report = r; },
                                        rig.clock.now()));
  rig.run_for(5s);
  ASSERT_TRUE(report.has_value());
  EXPECT_TRUE(report->ok()) << report->detail;
  EXPECT_EQ(report->identification, sim::program_identification(image));
  const auto t = rig.transfers();
  ASSERT_GE(t.size(), 3U);
  EXPECT_EQ(t.back().second.status, TransferEvent::Status::Done);
  EXPECT_EQ(t.back().second.done, image.size());
  EXPECT_EQ(t.back().second.total, image.size());
  EXPECT_EQ(rig.device_od.read(0x1F51, 1).value(), Bytes{1}) << "running";
}

}  // namespace
}  // namespace canopen
