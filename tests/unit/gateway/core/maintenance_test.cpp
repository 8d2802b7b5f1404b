// Remote maintenance in the request core (contract "Remote configuration
// and maintenance"), against a fake core::Networks: the roles of DCF read,
// DCF apply, store/restore and program download, one operation per node
// (409), DCF parsing before anything reaches the bus (400 FILE:LINE), the
// CiA 301 store/restore signatures (7.5.2.13/14), the answers and audit
// lines, and the counters /metrics shows.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "canopen/sdo/abort.hpp"
#include "core/request_core.hpp"
#include "support/core_rig.hpp"

namespace gateway::core {
namespace {

using ::testing::HasSubstr;
using test_support::checked;
using test_support::kDescribed;
using test_support::kOwnNode;
using test_support::problem_of;
using test_support::request;
using test_support::Rig;

// A DCF for the fake's described node: 6060h with a ParameterValue.
const char* kDcf =
    "[FileInfo]\nFileName=node5.dcf\n[DeviceInfo]\nVendorName=Test\n[DeviceComissioning]\nNodeID=5\n"
    "[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n"
    "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0\n"
    "[OptionalObjects]\nSupportedObjects=1\n1=0x6060\n"
    "[6060]\nParameterName=Modes of operation\nObjectType=0x7\nDataType=0x0002\nAccessType=rw\n"
    "DefaultValue=0\nParameterValue=3\n";

std::uint64_t count(const Rig& rig, Counters::MaintenanceKind k, Counters::MaintenanceResult r) {
  return rig.core.counters().maintenance[k][r];
}

// Contract: DCF read viewer, store/restore operator, DCF apply and program download admin.
TEST(Maintenance, RolesPerContract) {
  Rig rig;
  EXPECT_FALSE(rig.run(request(DcfRead{kDescribed}, checked(Role::Viewer)))->has_value()) << "viewer reads a DCF";
  rig.nets.transfer_answer();
  EXPECT_EQ(problem_of(rig.run(request(NodeStore{kDescribed, false}, checked(Role::Viewer)))).status, 403);
  EXPECT_EQ(problem_of(rig.run(request(DcfApply{kDescribed, kDcf}, checked(Role::Operator)))).status, 403);
  EXPECT_EQ(problem_of(rig.run(request(ProgramDownload{kDescribed, 1, {1, 2}}, checked(Role::Operator)))).status,
            403);
  EXPECT_TRUE(rig.audited("auth failure: op@10.0.0.7: program download net 1 node 5: 403"));
  EXPECT_TRUE(rig.nets.transfers.empty() && rig.nets.pending.empty()) << "nothing started for the refused ones";
  EXPECT_FALSE(rig.run(request(NodeStore{kDescribed, true}, checked(Role::Operator)))->has_value())
      << "an operator restores (its reset node is part of it)";
}

TEST(Maintenance, DcfReadAnswersTheDocumentWithTheFailedObjects) {
  Rig rig;
  const auto r = rig.run(request(DcfRead{kDescribed}, checked(Role::Viewer, "token viewer", "viewer")));
  ASSERT_EQ(rig.nets.transfers.size(), 1u);
  EXPECT_EQ(rig.nets.transfers[0].kind, "dcf-read");
  TransferOutcome o;
  o.text = "[FileInfo]\n";
  o.read = 7;
  o.objects.push_back({0x2000, 1, make_error_code(canopen::SdoAbort::ReadOfWriteOnly), "write-only"});
  rig.nets.transfer_answer(o);
  ASSERT_TRUE(r->has_value() && std::holds_alternative<DcfDocument>(**r));
  const auto& doc = std::get<DcfDocument>(**r);
  EXPECT_EQ(doc.text, "[FileInfo]\n");
  EXPECT_EQ(doc.objects, 7u);
  ASSERT_EQ(doc.failed.size(), 1u);
  EXPECT_EQ(doc.failed[0].index, 0x2000);
  EXPECT_TRUE(rig.audited("DCF read by viewer: net 1 node 5: 7 objects read, 1 failed"));
  EXPECT_EQ(count(rig, Counters::dcf_read, Counters::ok), 1u);
}

TEST(Maintenance, DcfReadOfANodeWithoutEdsOrOfTheOwnNodeIsRefused) {
  Rig rig;
  const auto none = rig.run(request(DcfRead{9}));
  EXPECT_EQ(problem_of(none).status, 404);
  EXPECT_THAT(problem_of(none).detail, HasSubstr("has no EDS/DCF"));
  EXPECT_EQ(problem_of(rig.run(request(DcfRead{kOwnNode}))).status, 400);
  EXPECT_TRUE(rig.nets.transfers.empty());
}

// CiA 306 file errors as `canopen-eds check` words them; nothing on the bus.
TEST(Maintenance, AMalformedDcfIs400WithFileAndLineAndChangesNothing) {
  Rig rig;
  std::string bad = kDcf;
  // (A value that does not fit is left out with a warning, issue 28 item 8;
  // one entry with two values cannot be read without guessing.)
  bad.replace(bad.find("ParameterValue=3"), 16, "ParameterValue=3\nParameterValue=4");
  const auto r = rig.run(request(DcfApply{kDescribed, bad}));
  EXPECT_EQ(problem_of(r).status, 400);
  EXPECT_THAT(problem_of(r).detail, HasSubstr("node5.dcf:26: key 'ParameterValue'"));
  EXPECT_TRUE(rig.nets.transfers.empty() && rig.nets.pending.empty());
  EXPECT_EQ(count(rig, Counters::dcf_apply, Counters::ok) + count(rig, Counters::dcf_apply, Counters::failed), 0u);
}

TEST(Maintenance, DcfApplyPassesTheParsedDcfAndAnswersPerObject) {
  Rig rig;
  const auto r = rig.run(request(DcfApply{kDescribed, kDcf, true, true}, checked(Role::Admin, "token a", "admin")));
  ASSERT_EQ(rig.nets.transfers.size(), 1u);
  const auto& t = rig.nets.transfers[0];
  ASSERT_TRUE(t.dcf);
  EXPECT_TRUE(t.store && t.reset);
  const auto* e = t.dcf->od.find(0x6060, 0);
  ASSERT_NE(e, nullptr);
  TransferOutcome o;
  o.objects.push_back({0x6060, 0, {}, ""});
  o.objects.push_back({0x1017, 0, make_error_code(canopen::SdoAbort::ValueTooHigh), ""});
  o.stored = true;
  o.reset = true;
  rig.nets.transfer_answer(o);
  ASSERT_TRUE(r->has_value() && std::holds_alternative<DcfApplied>(**r));
  const auto& a = std::get<DcfApplied>(**r);
  ASSERT_EQ(a.objects.size(), 2u);
  EXPECT_FALSE(a.objects[0].error);
  EXPECT_EQ(a.objects[1].error, make_error_code(canopen::SdoAbort::ValueTooHigh));
  EXPECT_TRUE(a.stored && a.reset);
  EXPECT_TRUE(rig.audited("DCF apply by admin: net 1 node 5, then store, then reset node: 1 objects written, 1 failed, "
                          "stored, reset"));
}

// One maintenance operation per node: the second is 409 and counted busy;
// another node is not affected; the first's end frees the node.
TEST(Maintenance, OneTransferPerNodeOthersAre409) {
  Rig rig;
  const auto first = rig.run(request(ProgramDownload{kDescribed, 1, canopen::Bytes(100, 0xAA)}));
  ASSERT_EQ(rig.nets.transfers.size(), 1u);
  EXPECT_EQ(rig.nets.transfers[0].image.size(), 100u);
  const auto second = rig.run(request(DcfRead{kDescribed}));
  EXPECT_EQ(problem_of(second).status, 409);
  const auto store = rig.run(request(NodeStore{kDescribed, false}));
  EXPECT_EQ(problem_of(store).status, 409);
  EXPECT_EQ(count(rig, Counters::dcf_read, Counters::busy), 1u);
  EXPECT_TRUE(rig.audited("DCF read by op@10.0.0.7: net 1 node 5: 409"));
  EXPECT_FALSE(rig.run(request(ProgramDownload{6, 1, {1}}))->has_value()) << "another node runs in parallel";
  TransferOutcome done;
  done.bytes = 100;
  done.identification = 0x12345678;
  rig.nets.transfer_answer(done);
  ASSERT_TRUE(first->has_value() && std::holds_alternative<ProgramDownloaded>(**first));
  EXPECT_EQ(std::get<ProgramDownloaded>(**first).identification, 0x12345678u);
  EXPECT_FALSE(rig.run(request(DcfRead{kDescribed}))->has_value()) << "free again";
}

// The network's own busy check (e.g. a transfer started elsewhere) is 409 too.
TEST(Maintenance, NetworkBusyIs409) {
  Rig rig;
  rig.nets.transfer_refuse = std::make_error_code(std::errc::device_or_resource_busy);
  EXPECT_EQ(problem_of(rig.run(request(ProgramDownload{kDescribed, 1, {1}}))).status, 409);
  EXPECT_EQ(count(rig, Counters::program_download, Counters::busy), 1u);
  rig.nets.transfer_refuse = {};
  EXPECT_FALSE(rig.run(request(ProgramDownload{kDescribed, 1, {1}}))->has_value()) << "the node was freed";
}

// CiA 302-3: a failed step is answered with the step and the abort code.
TEST(Maintenance, AFailedProgramDownloadStepIsAProblemWithStepAndAbortCode) {
  Rig rig;
  const auto r = rig.run(request(ProgramDownload{kDescribed, 1, canopen::Bytes(64, 1)}));
  TransferOutcome o;
  o.error = make_error_code(canopen::SdoAbort::LengthTooHigh);
  o.remote = true;
  o.step = "download (1F50h sub 1)";
  rig.nets.transfer_answer(o);
  const auto& p = problem_of(r);
  EXPECT_EQ(p.status, 422);
  EXPECT_EQ(p.abort_code, 0x06070012u);
  EXPECT_THAT(p.detail, HasSubstr("download (1F50h sub 1)"));
  EXPECT_EQ(count(rig, Counters::program_download, Counters::failed), 1u);
  EXPECT_TRUE(rig.audited("program download by op@10.0.0.7: net 1 node 5 program 1, 64 bytes: 422"));
}

TEST(Maintenance, ProgramNumberAndEmptyImageAre400) {
  Rig rig;
  EXPECT_EQ(problem_of(rig.run(request(ProgramDownload{kDescribed, 0, {1}}))).status, 400);
  EXPECT_EQ(problem_of(rig.run(request(ProgramDownload{kDescribed, 255, {1}}))).status, 400);
  EXPECT_EQ(problem_of(rig.run(request(ProgramDownload{kDescribed, 1, {}}))).status, 400);
  EXPECT_TRUE(rig.nets.transfers.empty());
}

// CiA 301 7.5.2.13: "save" (65766173h) to 1010h sub 1.
TEST(Maintenance, StoreWritesSaveTo1010Sub1) {
  Rig rig;
  const auto r = rig.run(request(NodeStore{kDescribed, false}, checked(Role::Operator)));
  ASSERT_EQ(rig.nets.pending.size(), 1u);
  EXPECT_EQ(rig.nets.pending[0].index, 0x1010);
  EXPECT_EQ(rig.nets.pending[0].sub, 1);
  EXPECT_EQ(rig.nets.downloaded.back(), (canopen::Bytes{'s', 'a', 'v', 'e'}));
  rig.nets.answer();
  ASSERT_TRUE(r->has_value() && std::holds_alternative<NodeStored>(**r));
  EXPECT_FALSE(std::get<NodeStored>(**r).restore);
  EXPECT_TRUE(rig.nets.nmt.empty()) << "store resets nothing";
  EXPECT_TRUE(rig.audited("store by op@10.0.0.7: net 1 node 5 1010h sub 1 = \"save\": ok"));
  EXPECT_EQ(count(rig, Counters::store, Counters::ok), 1u);
}

// CiA 301 7.5.2.14: "load" (64616F6Ch) to 1011h sub 1; the defaults take
// effect after a reset, which the restore sends.
TEST(Maintenance, RestoreWritesLoadTo1011Sub1ThenResetsTheNode) {
  Rig rig;
  const auto r = rig.run(request(NodeStore{kDescribed, true}, checked(Role::Operator)));
  ASSERT_EQ(rig.nets.pending.size(), 1u);
  EXPECT_EQ(rig.nets.pending[0].index, 0x1011);
  EXPECT_EQ(rig.nets.downloaded.back(), (canopen::Bytes{'l', 'o', 'a', 'd'}));
  EXPECT_TRUE(rig.nets.nmt.empty()) << "no reset before the device confirmed";
  rig.nets.answer();
  ASSERT_EQ(rig.nets.nmt.size(), 1u);
  EXPECT_EQ(rig.nets.nmt[0].command, canopen::NmtCommand::ResetNode);
  EXPECT_EQ(rig.nets.nmt[0].node, kDescribed);
  ASSERT_TRUE(r->has_value() && std::holds_alternative<NodeStored>(**r));
  EXPECT_TRUE(rig.audited("then NMT reset node (part of the restore): ok"));
}

TEST(Maintenance, ARefusedStoreIs422WithTheAbortAndNoReset) {
  Rig rig;
  const auto r = rig.run(request(NodeStore{kDescribed, true}, checked(Role::Operator)));
  rig.nets.answer({}, make_error_code(canopen::SdoAbort::CannotStore));
  EXPECT_EQ(problem_of(r).status, 422);
  EXPECT_EQ(problem_of(r).abort_code, 0x08000020u);
  EXPECT_TRUE(rig.nets.nmt.empty());
  EXPECT_EQ(count(rig, Counters::restore, Counters::failed), 1u);
}

// The gateway's own node: its own dictionary stores (as an SDO download would).
TEST(Maintenance, StoreOnTheOwnNodeWritesItsDictionary) {
  Rig rig;
  const auto r = rig.run(request(NodeStore{kOwnNode, false}));
  ASSERT_TRUE(r->has_value());
  EXPECT_TRUE(std::holds_alternative<NodeStored>(**r)) << (std::holds_alternative<Problem>(**r) ? problem_of(r).detail : "");
  EXPECT_TRUE(rig.nets.pending.empty());
}

// Each operation holds one place of the caller's share of the node's SDO
// queue while it runs, and gives it back at its end.
TEST(Maintenance, HoldsOnePlaceOfTheCallersShare) {
  Rig rig;  // share: auth::caller_share(the queue limit)
  const auto dl = rig.run(request(ProgramDownload{kDescribed, 1, {1}}));
  for (std::size_t i = 1; i < rig.core.sdo_share(); ++i)
    EXPECT_FALSE(rig.run(request(SdoRead{kDescribed, 0x1000, 0, {}}))->has_value());
  const auto over = rig.run(request(SdoRead{kDescribed, 0x1000, 0, {}}));
  EXPECT_EQ(problem_of(over).status, 429) << "the download holds one of the caller's places";
  rig.nets.transfer_answer();
  EXPECT_FALSE(rig.run(request(SdoRead{kDescribed, 0x1000, 0, {}}))->has_value()) << "given back at its end";
}

}  // namespace
}  // namespace gateway::core
