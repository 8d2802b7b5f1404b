// RequestCore against a fake core::Networks: no App, no bus, no clock. Each
// rule the core applies once for every front end: identity and rate limit
// for unchecked callers, the address (network, node, bus), the role per
// command with its audit line, the per-caller share of a node's SDO queue,
// SDO typing and limits, audit lines, counters and the latency histogram.
#include "core/request_core.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <deque>
#include <map>

#include "canopen/eds/eds.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/sdo/abort.hpp"
#include "support/core_rig.hpp"
#include "support/fake_networks.hpp"

namespace gateway::core {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

using test_support::FakeNetworks;
using test_support::kDescribed;
using test_support::kOwnNode;

using test_support::checked;
using test_support::problem_of;
using test_support::request;
using test_support::Rig;

TEST(RequestCoreAddress, UnknownNetworkIs404AndOutOfRangeNodes400) {
  Rig rig;
  const auto unknown = rig.run(request(SdoRead{5, 0x1000, 0, {}}, checked(Role::Admin), 3));
  EXPECT_EQ(problem_of(unknown).status, 404);
  EXPECT_EQ(problem_of(unknown).detail, "network 3 is not configured (networks are 1..2)");
  EXPECT_EQ(problem_of(rig.run(request(SdoRead{5, 0x1000, 0, {}}, checked(Role::Admin), 0))).status, 404);
  const auto zero = rig.run(request(SdoRead{0, 0x1000, 0, {}}));
  EXPECT_EQ(problem_of(zero).status, 400);
  EXPECT_EQ(problem_of(zero).detail, "node-ID 0 is out of range 1..127");
  EXPECT_EQ(problem_of(rig.run(request(SdoWrite{128, 0x1000, 0, {}, 1}))).status, 400);
  // NMT to node 0 is all nodes.
  const auto all = rig.run(request(Nmt{0, canopen::NmtCommand::Start}));
  ASSERT_TRUE(std::holds_alternative<NmtSent>(**all));
  ASSERT_EQ(rig.nets.nmt.size(), 1u);
  EXPECT_EQ(rig.nets.nmt[0].node, 0);
  EXPECT_TRUE(rig.nets.pending.empty()) << "nothing reached the bus for the refused ones";
}

TEST(RequestCoreAddress, BusOffOrDownIs503OnlyWhenAsked) {
  Rig rig;
  rig.nets.bus = canopen::can::BusState::BusOff;
  auto r = request(SdoRead{5, 0x1000, 0, canopen::DataType::Unsigned32});
  r.check_bus = true;
  const auto refused = rig.run(r);
  EXPECT_EQ(problem_of(refused).status, 503);
  EXPECT_EQ(problem_of(refused).detail, "network 1 is bus-off");
  r.check_bus = false;  // MQTT: the request waits in the node's queue
  EXPECT_FALSE(rig.run(r)->has_value());
  EXPECT_EQ(rig.nets.pending.size(), 1u);
}

TEST(RequestCoreAddress, AnAddressErrorIsAnsweredAfterTheNetworkCheck) {
  Rig rig;
  auto r = request(Undecodable{Operation::sdo_read, 5, "sub-index must be 0..255", true}, checked(Role::Admin), 9);
  EXPECT_EQ(problem_of(rig.run(r)).status, 404) << "the unknown network first";
  r.network = 1;
  rig.nets.bus = canopen::can::BusState::Down;
  r.check_bus = true;
  const auto bad = rig.run(r);
  EXPECT_EQ(problem_of(bad).status, 400) << "the path before the bus";
  EXPECT_EQ(problem_of(bad).detail, "sub-index must be 0..255");
}

TEST(RequestCoreRoles, EachCommandNeedsItsRoleAndRefusalsAreAudited) {
  Rig rig;
  const auto write = rig.run(request(SdoWrite{5, 0x6060, 0, {}, 3}, checked(Role::Viewer)));
  EXPECT_EQ(problem_of(write).status, 403);
  EXPECT_FALSE(problem_of(write).command_read);
  EXPECT_TRUE(rig.audited("auth failure: op@10.0.0.7: SDO write net 1 node 5: 403"));
  EXPECT_EQ(problem_of(rig.run(request(Nmt{5, canopen::NmtCommand::ResetNode}, checked(Role::Operator)))).status, 403);
  EXPECT_TRUE(rig.audited("auth failure: op@10.0.0.7: NMT reset-node net 1 node 5: 403"));
  EXPECT_EQ(problem_of(rig.run(request(Sync{}, checked(Role::Viewer)))).status, 403);
  EXPECT_EQ(problem_of(rig.run(request(SdoRead{5, 0x1000, 0, {}}, checked(Role::None)))).status, 401);
  EXPECT_EQ(rig.core.counters().auth_failures, 4u);
  // Allowed: an operator starts, a viewer reads.
  EXPECT_TRUE(std::holds_alternative<NmtSent>(**rig.run(request(Nmt{5, canopen::NmtCommand::Start},
                                                                   checked(Role::Operator)))));
  EXPECT_FALSE(rig.run(request(SdoRead{5, 0x1000, 0, {}}, checked(Role::Viewer)))->has_value()) << "queued";
  EXPECT_TRUE(rig.audited("NMT start by op@10.0.0.7: net 1 node 5: sent"));
}

TEST(RequestCoreRoles, AnUndecodableSdoRequestIsRefusedByRoleBeforeItsBodyIsLookedAt) {
  Rig rig;
  const auto r = rig.run(request(Undecodable{Operation::sdo_write, 5, "value is required", false},
                                 checked(Role::Viewer)));
  EXPECT_EQ(problem_of(r).status, 403);
  const auto ok = rig.run(request(Undecodable{Operation::sdo_write, 5, "value is required", false}));
  EXPECT_EQ(problem_of(ok).status, 400);
  EXPECT_EQ(problem_of(ok).detail, "value is required");
  // NMT's role depends on the command: the 400 comes first.
  EXPECT_EQ(problem_of(rig.run(request(Undecodable{Operation::nmt, 5, "command is required", false},
                                       checked(Role::Viewer))))
                .status,
            400);
}

TEST(RequestCoreCallers, UncheckedCallersAreIdentifiedByTokenAndRateLimited) {
  RequestCore::Settings s;
  s.anonymous_role = Role::None;
  s.rate_limit = 1;
  s.rate_burst = 2;
  Rig rig(s, {{"ops", Role::Operator, auth::sha256_hex("secret")}});
  Caller anonymous;
  anonymous.transport = Transport::mqtt;
  const auto no_token = rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}, anonymous));
  EXPECT_EQ(problem_of(no_token).status, 401);
  // Anonymous without a role is not refused as a caller but by the command's role.
  EXPECT_TRUE(rig.audited("auth failure: anonymous: SDO read net 1 node 127: 401"));
  Caller bad = anonymous;
  bad.token = "wrong";
  EXPECT_EQ(problem_of(rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}, bad))).status, 401);
  EXPECT_TRUE(rig.audited("auth failure: anonymous: request to net 1 node 127: 401 the token is not valid"));
  // The third tokenless request in the same instant is over the burst: 429 before any audit.
  const auto audits = rig.audit.size();
  const auto limited = rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}, anonymous));
  EXPECT_EQ(problem_of(limited).status, 429);
  EXPECT_EQ(problem_of(limited).retry_after, 1);
  EXPECT_EQ(problem_of(limited).detail, "too many requests from MQTT requests without a token; slow down (http.rate-limit)");
  EXPECT_EQ(rig.audit.size(), audits);
  EXPECT_EQ(rig.core.counters().requests_rate_limited, 1u);
  // A token holder has its own bucket, and its role.
  Caller ops = anonymous;
  ops.token = "secret";
  const auto read = rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}, ops));
  ASSERT_TRUE(std::holds_alternative<SdoValue>(**read));
  // Time refills the bucket.
  rig.nets.t += 2s;
  EXPECT_EQ(problem_of(rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}, anonymous))).status, 401);
  // Checked callers are not limited here (HTTP's authorizer did that).
  for (int i = 0; i < 5; ++i)
    EXPECT_TRUE(std::holds_alternative<SdoValue>(**rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}))));
}

TEST(RequestCoreSdo, OwnNodeAnswersFromItsDictionaryWithAuditedWrites) {
  Rig rig;
  const auto w = rig.run(request(SdoWrite{kOwnNode, 0x1017, 0, {}, 250}));
  ASSERT_TRUE(std::holds_alternative<SdoValue>(**w));
  EXPECT_TRUE(rig.audited("SDO write by op@10.0.0.7: net 1 node 127 1017h sub 0 = 250: ok"));
  const auto r = rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}));
  ASSERT_TRUE(std::holds_alternative<SdoValue>(**r));
  EXPECT_EQ(canopen::format_value(std::get<SdoValue>(**r).value), "250");
  const auto missing = rig.run(request(SdoRead{kOwnNode, 0x2000, 0, {}}));
  EXPECT_EQ(problem_of(missing).status, 422);
  EXPECT_EQ(problem_of(missing).abort_code, 0x06020000u);
  const auto ro = rig.run(request(SdoWrite{kOwnNode, 0x1018, 1, {}, 1}));
  EXPECT_EQ(problem_of(ro).status, 422);
  EXPECT_TRUE(rig.audited("SDO write by op@10.0.0.7: net 1 node 127 1018h sub 1 = 1: "));
  EXPECT_TRUE(rig.nets.pending.empty()) << "nothing on the bus for the own node";
}

TEST(RequestCoreSdo, ValuesAreTypedAndCheckedBeforeTheBus) {
  Rig rig;
  const auto high = rig.run(request(SdoWrite{kDescribed, 0x6060, 0, {}, 11}));
  EXPECT_EQ(problem_of(high).status, 400);
  EXPECT_THAT(problem_of(high).detail, HasSubstr("6060h sub 0: "));
  const auto not_i8 = rig.run(request(SdoWrite{kDescribed, 0x6060, 0, {}, 300}));
  EXPECT_EQ(problem_of(not_i8).status, 400);
  const auto unknown = rig.run(request(SdoRead{kDescribed, 0x5FFF, 0, {}}));
  EXPECT_EQ(problem_of(unknown).status, 404);
  EXPECT_EQ(problem_of(unknown).detail, "the node's EDS/DCF has no object 5FFFh sub 0 (give ?type= to ask anyway)");
  EXPECT_TRUE(rig.nets.pending.empty());
  // In range: downloaded as INTEGER8, audited when the device answers.
  const auto ok = rig.run(request(SdoWrite{kDescribed, 0x6060, 0, {}, 3}));
  ASSERT_EQ(rig.nets.downloaded.size(), 1u);
  EXPECT_EQ(rig.nets.downloaded[0], canopen::Bytes{3});
  EXPECT_FALSE(ok->has_value());
  rig.nets.answer();
  ASSERT_TRUE(ok->has_value());
  EXPECT_TRUE(rig.audited("SDO write by op@10.0.0.7: net 1 node 5 6060h sub 0 = 3: ok"));
  // Without an EDS and a type: raw bytes (DOMAIN).
  const auto raw = rig.run(request(SdoRead{42, 0x1000, 0, {}}));
  rig.nets.answer({0x91, 0x01});
  ASSERT_TRUE(std::holds_alternative<SdoValue>(**raw));
  EXPECT_EQ(std::get<SdoValue>(**raw).value.type, canopen::DataType::Domain);
  // A typed read the device answers with the wrong size: 502.
  const auto wrong = rig.run(request(SdoRead{42, 0x1000, 0, canopen::DataType::Unsigned32}));
  EXPECT_EQ(rig.nets.pending.back().expected_size, 4u) << "a fixed-size type is the size to expect";
  rig.nets.answer({0x01});
  EXPECT_EQ(problem_of(wrong).status, 502);
  EXPECT_EQ(rig.core.counters().sdo_requests, 3u);
}

TEST(RequestCoreSdo, AbortsAndTimeoutsAreCountedAndTyped) {
  Rig rig;
  const auto aborted = rig.run(request(SdoRead{42, 0x1000, 0, canopen::DataType::Unsigned32}));
  rig.nets.answer({}, make_error_code(canopen::SdoAbort::NoSuchObject));
  EXPECT_EQ(problem_of(aborted).status, 422);
  EXPECT_EQ(problem_of(aborted).title, "SDO abort");
  const auto timed_out = rig.run(request(SdoRead{42, 0x1000, 0, canopen::DataType::Unsigned32}));
  auto r = std::move(rig.nets.pending.front());
  rig.nets.pending.pop_front();
  canopen::sdo::TransferResult res;
  res.error = make_error_code(canopen::SdoAbort::Timeout);
  res.origin = canopen::sdo::Origin::Local;
  r.on_done(std::move(res));
  EXPECT_EQ(problem_of(timed_out).status, 504);
  EXPECT_EQ(rig.core.counters().sdo_aborts, 1u);
  EXPECT_EQ(rig.core.counters().sdo_timeouts, 1u);
}

TEST(RequestCoreLimits, ACallerGetsItsShareOfANodesQueueAndItIsGivenBack) {
  Rig rig;
  const std::size_t share = rig.core.sdo_share();
  ASSERT_EQ(share, 8u);  // max(2, 32 / 4)
  const Command read = SdoRead{42, 0x1000, 0, canopen::DataType::Unsigned32};
  for (std::size_t i = 0; i < share; ++i) EXPECT_FALSE(rig.run(request(read))->has_value());
  const auto over = rig.run(request(read));
  EXPECT_EQ(problem_of(over).status, 429);
  EXPECT_EQ(problem_of(over).retry_after, 1);
  EXPECT_THAT(problem_of(over).detail, HasSubstr("address 10.0.0.7 has 8 SDO requests waiting for node 42 already"));
  EXPECT_EQ(rig.core.counters().sdo_share_refused, 1u);
  // Another caller, and the same caller on another node, still get in.
  EXPECT_FALSE(rig.run(request(read, checked(Role::Viewer, "address 10.0.0.8")))->has_value());
  EXPECT_FALSE(rig.run(request(SdoRead{43, 0x1000, 0, canopen::DataType::Unsigned32}))->has_value());
  // An answer gives the place back.
  rig.nets.answer({1, 0, 0, 0});
  EXPECT_FALSE(rig.run(request(read))->has_value());
  EXPECT_EQ(problem_of(rig.run(request(read))).status, 429);
  // A write refused for the share is audited.
  EXPECT_EQ(problem_of(rig.run(request(SdoWrite{42, 0x1000, 0, canopen::DataType::Unsigned32, 1}))).status, 429);
  EXPECT_TRUE(rig.audited("(address 10.0.0.7 has its share of the node's SDO queue)"));
}

TEST(RequestCoreLimits, AFullNodeQueueIs429AndGivesThePlaceBack) {
  Rig rig;
  rig.nets.queue_full = true;
  const Command read = SdoRead{42, 0x1000, 0, canopen::DataType::Unsigned32};
  for (std::size_t i = 0; i < rig.core.sdo_share() + 2; ++i) {
    const auto r = rig.run(request(read));
    EXPECT_EQ(problem_of(r).status, 429);
    EXPECT_EQ(problem_of(r).detail, "too many SDO requests queued for node 42");
  }
  EXPECT_EQ(rig.core.counters().sdo_share_refused, 0u) << "the places were given back each time";
}

TEST(RequestCoreMetrics, SdoLatencyHistogramFromSubmitToResult) {
  Rig rig;
  const Command read = SdoRead{42, 0x1000, 0, canopen::DataType::Unsigned32};
  rig.run(request(read));
  rig.nets.t += 3ms;  // 0.0025 < 0.003 <= 0.005
  rig.nets.answer({1, 0, 0, 0});
  rig.run(request(read));
  rig.nets.t += 10s;  // slower than the last bound
  rig.nets.answer({1, 0, 0, 0});
  const auto& c = rig.core.counters();
  EXPECT_EQ(c.sdo_latency_count, 2u);
  EXPECT_NEAR(c.sdo_latency_sum, 10.003, 1e-9);
  EXPECT_EQ(c.sdo_latency_counts[3], 1u);  // bound 0.005
  EXPECT_EQ(c.sdo_latency_counts.back(), 1u);
  // The own node's dictionary answers without a transfer: not in the histogram.
  rig.run(request(SdoRead{kOwnNode, 0x1017, 0, {}}));
  EXPECT_EQ(rig.core.counters().sdo_latency_count, 2u);
}

TEST(RequestCoreOther, SyncAndPdoReadAreAuditedAndChecked) {
  Rig rig;
  const auto s = rig.run(request(Sync{7}));
  ASSERT_TRUE(std::holds_alternative<SyncSent>(**s));
  EXPECT_EQ(std::get<SyncSent>(**s).counter, 7);
  ASSERT_EQ(rig.nets.syncs.size(), 1u);
  EXPECT_TRUE(rig.audited("SYNC by op@10.0.0.7: net 1 counter 7: sent"));
  const auto no_eds = rig.run(request(PdoConfigRead{42}));
  EXPECT_EQ(problem_of(no_eds).status, 404);
  EXPECT_EQ(problem_of(no_eds).detail, "node 42 on network 1 has no EDS/DCF, so its PDOs are not decoded");
  const auto rpdo = rig.run(request(RpdoWrite{42, 1, {}, {}, {}}));
  EXPECT_EQ(problem_of(rpdo).detail, "node 42 has no EDS/DCF, so its RPDOs are unknown");
  const auto unused = rig.run(request(RpdoWrite{kDescribed, 1, {}, {}, {}}));
  EXPECT_EQ(problem_of(unused).status, 404);
}

// ---- LSS (contract "LSS master", facts C) ------------------------------------

using S = LssOutcome::Status;
const LssAddress kDev{0x0000ABCD, 0x401, 2, 1001};
const LssAddress kDev2{0x0000ABCD, 0x401, 2, 1002};

// The steps the fake LSS master got, answered ok one by one until none is
// pending; returns them in order.
std::vector<LssStep> answer_all_ok(Rig& rig) {
  std::vector<LssStep> sent;
  while (!rig.nets.lss_pending.empty()) {
    sent.push_back(rig.nets.lss_pending.front().step);
    rig.nets.lss_answer();
  }
  return sent;
}

template <typename T>
const T& step_as(const LssStep& s) {
  static const T none{};
  if (!std::holds_alternative<T>(s)) {
    ADD_FAILURE() << "step " << s.index() << " is not the one expected";
    return none;
  }
  return std::get<T>(s);
}

TEST(RequestCoreLss, EveryLssCommandNeedsAdminAndRefusalsAreAudited) {
  Rig rig;
  for (Command cmd : std::vector<Command>{LssFastscan{}, LssConfigure{kDev, 42, {}, true}, LssAssignAll{},
                                          LssSwitchGlobal{true}, LssStore{}, LssInquire{}, LssDevices{}}) {
    EXPECT_EQ(problem_of(rig.run(request(cmd, checked(Role::Operator)))).status, 403);
  }
  EXPECT_TRUE(rig.audited("auth failure: op@10.0.0.7: LSS net 1 node 0: 403"));
  EXPECT_TRUE(rig.nets.lss_pending.empty()) << "nothing reached the bus";
  EXPECT_EQ(required_role(Command{LssInquire{}}), Role::Admin);
}

TEST(RequestCoreLss, FastscanSwitchesAllToWaitingFirstAndRemembersTheDevice) {
  Rig rig;
  const auto r = rig.run(request(LssFastscan{std::chrono::milliseconds(25)}));
  ASSERT_EQ(rig.nets.lss_pending.size(), 1u) << "one step at a time";
  EXPECT_FALSE(step_as<LssSwitchGlobal>(rig.nets.lss_pending.front().step).configuration);
  rig.nets.lss_answer();
  ASSERT_EQ(rig.nets.lss_pending.size(), 1u);
  EXPECT_EQ(step_as<LssFastscan>(rig.nets.lss_pending.front().step).timeout, std::chrono::milliseconds(25));
  LssOutcome found;
  found.address = kDev;
  rig.nets.lss_answer(found);
  ASSERT_TRUE(std::holds_alternative<LssFound>(**r));
  EXPECT_EQ(std::get<LssFound>(**r).address, kDev);
  EXPECT_TRUE(rig.nets.lss_pending.empty()) << "the device stays selected (contract: leaves it selected)";
  EXPECT_TRUE(rig.audited("LSS fastscan by op@10.0.0.7: net 1: found vendor 0x0000ABCD product 0x00000401"));
  const auto list = rig.run(request(LssDevices{}));
  ASSERT_TRUE(std::holds_alternative<LssDeviceList>(**list));
  ASSERT_EQ(std::get<LssDeviceList>(**list).devices.size(), 1u);
  EXPECT_EQ(std::get<LssDeviceList>(**list).devices[0].address, kDev);
  EXPECT_FALSE(std::get<LssDeviceList>(**list).devices[0].node_id.has_value());
  // The other network has its own list.
  const auto other = rig.run(request(LssDevices{}, checked(Role::Admin), 2));
  EXPECT_TRUE(std::get<LssDeviceList>(**other).devices.empty());
}

TEST(RequestCoreLss, FastscanWithNobodyUnconfiguredIs404AndClearsTheList) {
  Rig rig;
  rig.run(request(LssFastscan{}));
  answer_all_ok(rig);  // found {} (address 0) - a device
  const auto r = rig.run(request(LssFastscan{}));
  rig.nets.lss_answer();  // waiting
  LssOutcome none;
  none.status = S::none_found;
  rig.nets.lss_answer(none);
  // Back to waiting once more, then the answer.
  ASSERT_EQ(rig.nets.lss_pending.size(), 1u);
  EXPECT_FALSE(r->has_value());
  rig.nets.lss_answer();
  EXPECT_EQ(problem_of(r).status, 404);
  EXPECT_THAT(problem_of(r).detail, HasSubstr("no unconfigured device answered"));
  const auto list = rig.run(request(LssDevices{}));
  EXPECT_TRUE(std::get<LssDeviceList>(**list).devices.empty()) << "what the last scan found: nothing";
  EXPECT_EQ(rig.core.counters().lss_none_found, 1u);
}

TEST(RequestCoreLss, ConfigureSelectsSetsIdAndBitTimingStoresAndSwitchesBack) {
  Rig rig;
  rig.run(request(LssFastscan{}));
  LssOutcome found;
  found.address = kDev;
  rig.nets.lss_answer();
  rig.nets.lss_answer(found);
  const auto r = rig.run(request(LssConfigure{kDev, 42, 500000, true}));
  const auto steps = answer_all_ok(rig);
  ASSERT_EQ(steps.size(), 6u);
  EXPECT_FALSE(step_as<LssSwitchGlobal>(steps[0]).configuration) << "nobody else stays selected";
  EXPECT_EQ(step_as<LssSwitchSelective>(steps[1]).address, kDev);
  EXPECT_EQ(step_as<LssSetNodeId>(steps[2]).node_id, 42);
  EXPECT_EQ(step_as<LssSetBitTiming>(steps[3]).table, 0);
  EXPECT_EQ(step_as<LssSetBitTiming>(steps[3]).index, 2) << "500 kbit/s is index 2 of the CiA 301 table (facts B.1)";
  EXPECT_TRUE(std::holds_alternative<LssStore>(steps[4]));
  EXPECT_FALSE(step_as<LssSwitchGlobal>(steps[5]).configuration) << "the device then boots with its new node-ID";
  ASSERT_TRUE(std::holds_alternative<LssAssigned>(**r));
  const auto& a = std::get<LssAssigned>(**r).assignments;
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].node_id, 42);
  EXPECT_TRUE(a[0].stored);
  EXPECT_EQ(a[0].bitrate, 500000u);
  EXPECT_TRUE(rig.audited("LSS configure by op@10.0.0.7: net 1 vendor 0x0000ABCD product 0x00000401 revision "
                          "0x00000002 serial 0x000003E9 -> node-ID 42, 500000 bit/s, store: ok"));
  const auto list = rig.run(request(LssDevices{}));
  EXPECT_EQ(std::get<LssDeviceList>(**list).devices.at(0).node_id, 42) << "the scanned device now has its ID";
  EXPECT_EQ(rig.core.counters().lss_assigned, 1u);
  // Without store and bit rate: no store, no bit timing.
  rig.run(request(LssConfigure{kDev2, 43, {}, false}));
  EXPECT_EQ(answer_all_ok(rig).size(), 4u);
}

TEST(RequestCoreLss, ConfigureOfAnAbsentDeviceIs504AndSetsNothing) {
  Rig rig;
  const auto r = rig.run(request(LssConfigure{kDev, 42, {}, true}));
  rig.nets.lss_answer();  // waiting
  LssOutcome timeout;
  timeout.status = S::timeout;
  rig.nets.lss_answer(timeout);  // selective: nobody has that address
  ASSERT_EQ(rig.nets.lss_pending.size(), 1u);
  EXPECT_FALSE(step_as<LssSwitchGlobal>(rig.nets.lss_pending.front().step).configuration);
  rig.nets.lss_answer();
  EXPECT_EQ(problem_of(r).status, 504);
  EXPECT_THAT(problem_of(r).detail, HasSubstr("no device with vendor 0x0000ABCD"));
  EXPECT_THAT(problem_of(r).detail, HasSubstr("(switch state selective)"));
  EXPECT_TRUE(rig.audited("-> node-ID 42, store: 504 no device with"));
  EXPECT_EQ(rig.core.counters().lss_timeouts, 1u);
  EXPECT_EQ(rig.core.counters().lss_assigned, 0u);
}

// CiA 305 error codes of configure node-ID and store (facts C.1) as 422
// with their meaning, and the network free again afterwards.
// CiA 305: the configuration services address the device in configuration
// state; these put every device there, as `lss_switch_glob 1` does.
void select_all(Rig& rig) {
  auto r = rig.run(request(LssSwitchGlobal{true}));
  rig.nets.lss_answer();
  ASSERT_TRUE(r && r->has_value());
}

TEST(RequestCoreLss, ASlaveErrorIs422WithItsCia305Meaning) {
  Rig rig;
  auto r = rig.run(request(LssConfigure{kDev, 42, {}, true}));
  rig.nets.lss_answer();
  rig.nets.lss_answer();
  rig.nets.lss_answer();  // node-ID set
  LssOutcome refused;
  refused.status = S::refused;
  refused.error = 2;
  rig.nets.lss_answer(refused);  // store
  rig.nets.lss_answer();         // back to waiting
  EXPECT_EQ(problem_of(r).status, 422);
  EXPECT_EQ(problem_of(r).lss_error, LssError::store_media_error);
  EXPECT_EQ(problem_of(r).detail, "the device refused store configuration: storage media access error (error code 2)");
  select_all(rig);
  r = rig.run(request(LssSetNodeId{100}));
  refused.error = 1;
  rig.nets.lss_answer(refused);
  EXPECT_EQ(problem_of(r).lss_error, LssError::node_id_not_supported);
  EXPECT_EQ(problem_of(r).detail, "the device refused configure node-ID: node-ID 100 is out of range (error code 1)");
  EXPECT_TRUE(rig.nets.lss_pending.empty()) << "a single service switches nothing by itself";
  r = rig.run(request(LssSetBitTiming{0, 4}));
  refused.error = 0xFF;
  refused.detail = "specific error 7";
  rig.nets.lss_answer(refused);
  EXPECT_EQ(problem_of(r).lss_error, LssError::manufacturer);
  EXPECT_THAT(problem_of(r).detail, HasSubstr("manufacturer-specific error (error code FFh): specific error 7"));
  EXPECT_EQ(rig.core.counters().lss_refused, 3u);
}

TEST(RequestCoreLss, OneLssOperationPerNetworkAtATime) {
  Rig rig;
  const auto first = rig.run(request(LssFastscan{}));
  const auto second = rig.run(request(LssConfigure{kDev, 42, {}, true}));
  EXPECT_EQ(problem_of(second).status, 409);
  EXPECT_THAT(problem_of(second).detail, HasSubstr("another LSS operation runs on network 1"));
  // Another network is not held; the list can always be read.
  EXPECT_FALSE(rig.run(request(LssFastscan{}, checked(Role::Admin), 2))->has_value());
  EXPECT_TRUE(std::holds_alternative<LssDeviceList>(**rig.run(request(LssDevices{}))));
  answer_all_ok(rig);
  EXPECT_TRUE(first->has_value());
  EXPECT_FALSE(rig.run(request(LssStore{}))->has_value()) << "free again once answered";
  EXPECT_EQ(rig.core.counters().lss_busy, 1u);
}

// Contract: assign-all fastscans until nobody unconfigured answers, giving
// each the next free node-ID (facts C.4 item 1).
TEST(RequestCoreLss, AssignAllGivesEachFoundDeviceTheNextFreeNodeId) {
  Rig rig;
  rig.nets.in_use = {3};
  const auto r = rig.run(request(LssAssignAll{2, true, std::chrono::milliseconds(50)}));
  std::vector<LssStep> steps;
  auto next = [&](LssOutcome o = {}) {
    steps.push_back(rig.nets.lss_pending.front().step);
    rig.nets.lss_answer(o);
  };
  next();  // waiting
  LssOutcome found;
  found.address = kDev;
  next(found);
  next();  // node-ID
  next();  // store
  next();  // waiting
  found.address = kDev2;
  next(found);
  next();
  next();
  next();
  LssOutcome none;
  none.status = S::none_found;
  next(none);
  EXPECT_TRUE(rig.nets.lss_pending.empty());
  ASSERT_EQ(steps.size(), 10u);
  EXPECT_EQ(step_as<LssSetNodeId>(steps[2]).node_id, 2);
  EXPECT_EQ(step_as<LssSetNodeId>(steps[6]).node_id, 4) << "3 is in use on the network";
  EXPECT_EQ(step_as<LssFastscan>(steps[5]).timeout, std::chrono::milliseconds(50));
  ASSERT_TRUE(std::holds_alternative<LssAssigned>(**r));
  const auto& a = std::get<LssAssigned>(**r).assignments;
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].address, kDev);
  EXPECT_EQ(a[1].address, kDev2);
  EXPECT_EQ(a[1].node_id, 4);
  EXPECT_TRUE(a[1].stored);
  const auto list = std::get<LssDeviceList>(**rig.run(request(LssDevices{})));
  ASSERT_EQ(list.devices.size(), 2u);
  EXPECT_EQ(list.devices[1].node_id, 4);
  EXPECT_TRUE(rig.audited("LSS assign-all by op@10.0.0.7: net 1 from node-ID 2, store: 2 assigned"));
  EXPECT_EQ(rig.core.counters().lss_assigned, 2u);
}

TEST(RequestCoreLss, BadArgumentsAre400AndSendNothing) {
  Rig rig;
  EXPECT_EQ(problem_of(rig.run(request(LssConfigure{kDev, 0, {}, true}))).detail, "nodeId must be 1..127, not 0");
  EXPECT_EQ(problem_of(rig.run(request(LssConfigure{kDev, kOwnNode, {}, true}))).detail,
            "node-ID 127 is the gateway's own on this network");
  EXPECT_THAT(problem_of(rig.run(request(LssConfigure{kDev, 5, 300000, true}))).detail,
              HasSubstr("bitrate 300000 is not in the CiA 301 table"));
  EXPECT_EQ(problem_of(rig.run(request(LssAssignAll{0, true, {}}))).status, 400);
  EXPECT_EQ(problem_of(rig.run(request(LssSetNodeId{128}))).status, 400);
  EXPECT_TRUE(rig.nets.lss_pending.empty());
  select_all(rig);
  EXPECT_FALSE(rig.run(request(LssSetNodeId{0xFF}))->has_value()) << "FFh unconfigures (facts C.1)";
}

TEST(RequestCoreLss, InquireWithoutAPartAsksForAllFour) {
  Rig rig;
  select_all(rig);
  const auto r = rig.run(request(LssInquire{}));
  std::vector<LssStep> steps;
  for (std::uint32_t v : {0xABCDu, 0x401u, 2u, 1001u}) {
    steps.push_back(rig.nets.lss_pending.front().step);
    LssOutcome o;
    o.value = v;
    rig.nets.lss_answer(o);
  }
  ASSERT_TRUE(std::holds_alternative<LssInquired>(**r));
  EXPECT_EQ(std::get<LssInquired>(**r).address, kDev);
  EXPECT_EQ(step_as<LssInquiry>(steps[3]), LssInquiry::serial);
  const auto id = rig.run(request(LssInquire{LssInquiry::node_id}));
  LssOutcome o;
  o.value = 42;
  rig.nets.lss_answer(o);
  EXPECT_EQ(std::get<LssInquired>(**id).value, 42u);
}

TEST(RequestCoreLss, BusOffIs503WhenAskedAndAMasterThatCannotSendIs503) {
  Rig rig;
  rig.nets.bus = canopen::can::BusState::BusOff;
  auto req = request(LssFastscan{});
  req.check_bus = true;
  EXPECT_EQ(problem_of(rig.run(req)).status, 503);
  rig.nets.bus = canopen::can::BusState::ErrorActive;
  select_all(rig);
  rig.nets.lss_refuse = std::make_error_code(std::errc::no_buffer_space);
  const auto r = rig.run(request(LssStore{}));
  EXPECT_EQ(problem_of(r).status, 503);
  rig.nets.lss_refuse = {};
  EXPECT_FALSE(rig.run(request(LssStore{}))->has_value()) << "not left held";
}

// Issue 28 item 7: with no device in configuration state, store, configure,
// activate and inquire are refused at once (409; ASCII ERROR:102 as
// CANopenNode) instead of waiting for an answer nobody will send.
TEST(RequestCoreLss, ConfigurationServicesWithNothingSelectedAre409AtOnce) {
  Rig rig;
  const auto refused = [&](Request req) {
    const auto r = rig.run(std::move(req));
    EXPECT_TRUE(rig.nets.lss_pending.empty()) << "nothing reached the bus";
    return problem_of(r).status;
  };
  EXPECT_EQ(refused(request(LssStore{})), 409);
  EXPECT_EQ(refused(request(LssSetNodeId{5})), 409);
  EXPECT_EQ(refused(request(LssSetBitTiming{0, 2})), 409);
  EXPECT_EQ(refused(request(LssActivateBitTiming{100})), 409);
  EXPECT_THAT(problem_of(rig.run(request(LssInquire{}))).detail,
              HasSubstr("no device is in LSS configuration state on network 1"));
  select_all(rig);
  auto r = rig.run(request(LssStore{}));
  ASSERT_EQ(rig.nets.lss_pending.size(), 1u) << "selected: the store goes out";
  rig.nets.lss_answer();
  EXPECT_TRUE(r->has_value());
  r = rig.run(request(LssSwitchGlobal{false}));
  rig.nets.lss_answer();
  EXPECT_EQ(refused(request(LssStore{})), 409) << "all back to waiting";
  // A selective switch that nobody answers selects nothing.
  r = rig.run(request(LssSwitchSelective{kDev}));
  LssOutcome none;
  none.status = S::timeout;
  rig.nets.lss_answer(none);
  EXPECT_EQ(refused(request(LssStore{})), 409);
}

// CiA 309-3 `set sdo_timeout` / `set sdo_block` (the ASCII front end): an
// SDO command may carry its own timeout and say block transfer or not; the
// SDO client's request gets them, and without them the node's defaults hold.
TEST(RequestCoreSdo, TimeoutAndBlockChoiceReachTheSdoClient) {
  Rig rig;
  SdoRead plain{5, 0x1018, 1, canopen::DataType::Unsigned32};
  rig.run(request(plain));
  ASSERT_EQ(rig.nets.pending.size(), 1U);
  EXPECT_FALSE(rig.nets.pending[0].timeout.has_value());
  EXPECT_EQ(rig.nets.pending[0].mode, canopen::sdo::Mode::Auto);
  SdoRead no_block = plain;
  no_block.timeout = std::chrono::milliseconds(50);
  no_block.block = false;
  rig.run(request(no_block));
  EXPECT_EQ(rig.nets.pending[1].timeout, std::chrono::milliseconds(50));
  EXPECT_EQ(rig.nets.pending[1].mode, canopen::sdo::Mode::Segmented) << "a normal (expedited or segmented) upload";
  SdoRead block = plain;
  block.block = true;
  rig.run(request(block));
  EXPECT_EQ(rig.nets.pending[2].mode, canopen::sdo::Mode::Block);

  SdoWrite small{5, 0x1017, 0, canopen::DataType::Unsigned16, 500};
  small.block = false;
  small.timeout = std::chrono::milliseconds(70);
  rig.run(request(small));
  EXPECT_EQ(rig.nets.pending[3].mode, canopen::sdo::Mode::Expedited) << "2 bytes fit an expedited download";
  EXPECT_EQ(rig.nets.pending[3].timeout, std::chrono::milliseconds(70));
  SdoWrite big{5, 0x2000, 0, canopen::DataType::Domain, "00112233445566778899"};
  big.block = false;
  rig.run(request(big));
  EXPECT_EQ(rig.nets.pending[4].mode, canopen::sdo::Mode::Segmented);
  big.block = true;
  rig.run(request(big));
  EXPECT_EQ(rig.nets.pending[5].mode, canopen::sdo::Mode::Block);
}

}  // namespace
}  // namespace gateway::core
