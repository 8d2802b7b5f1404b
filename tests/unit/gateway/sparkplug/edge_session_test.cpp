// EdgeSession: the Sparkplug B 3.0 edge node on a fake clock (UTC ms passed
// in) and a fake MQTT connection (the Outgoing list). Payloads are checked
// with the generated parser. Spec references: the facts file
// (../shared/ref/sparkplug-ascii-lss-facts.md) section A and the
// specification's [tck-id-*] assertions it cites.
#include "sparkplug/edge_session.hpp"

#include <gtest/gtest.h>

#include "unit/gateway/sparkplug/sparkplug_support.hpp"

namespace gateway::sparkplug {
namespace {

using sparkplug_test::metric;
using sparkplug_test::parse;
namespace pb = sparkplug_test::pb;
using sparkplug_test::TempDir;
using Kind = Outgoing::Kind;

constexpr std::uint64_t kT0 = 1'767'225'600'000;  // 2026-01-01T00:00:00Z in ms

Metric object(std::string name, std::uint16_t index, std::uint8_t sub, std::uint64_t value) {
  Metric m;
  m.name = std::move(name);
  m.datatype = DataType::UInt16;
  m.value = value;
  m.object = ObjectRef{index, sub};
  return m;
}

std::vector<Metric> drive_metrics() {
  std::vector<Metric> v;
  v.push_back(object("Statusword", 0x6041, 0, 0x0237));
  v.push_back(object("Controlword", 0x6040, 0, 0x000F));
  Metric state;
  state.name = "Node/State";
  state.datatype = DataType::String;
  state.value = std::string("OPERATIONAL");
  v.push_back(state);
  return v;
}

struct Rig {
  explicit Rig(std::filesystem::path dir = {}, std::string host = {})
      : store(std::move(dir)), session({"plant1", "gw1", std::move(host)}, store) {}

  // CONNECT + CONNACK; returns the CONNECT's parameters.
  EdgeSession::ConnectParams connect(std::uint64_t now = kT0) {
    auto c = session.connect_params(now);
    session.connected(out, now);
    return c;
  }
  std::vector<Outgoing> take() { return std::exchange(out, {}); }

  BdSeqStore store;
  EdgeSession session;
  std::vector<Outgoing> out;
};

std::vector<std::string> topics(const std::vector<Outgoing>& out) {
  std::vector<std::string> t;
  for (const auto& o : out)
    t.push_back(o.kind == Kind::Publish ? o.topic : o.kind == Kind::Subscribe ? "SUB " + o.topic : "DISCONNECT");
  return t;
}

std::int64_t bdseq_of(const pb::Payload& p) {
  const auto* m = metric(p, "bdSeq");
  return m ? static_cast<std::int64_t>(m->long_value()) : -1;
}

std::string ncmd_rebirth() {
  pb::Payload p;
  p.set_timestamp(kT0);
  auto* m = p.add_metrics();
  m->set_name("Node Control/Rebirth");
  m->set_datatype(pb::Boolean);
  m->set_boolean_value(true);
  return p.SerializeAsString();
}

std::string state_json(bool online, std::uint64_t ts) {
  return std::string("{\"online\":") + (online ? "true" : "false") + ",\"timestamp\":" + std::to_string(ts) + "}";
}

// Facts A.4.2 / spec ch5 will-message-*: the Will is NDEATH on
// spBv1.0/G/NDEATH/E, QoS 1, not retained, with only bdSeq (Int64) and no
// seq; stamped with the connect time (issue 27 item 7: 0 shows as 1970).
TEST(EdgeSession, TheWillIsNdeathWithTheConnectsBdSeq) {
  Rig r;
  const auto c = r.session.connect_params(kT0);
  EXPECT_EQ(c.will_topic, "spBv1.0/plant1/NDEATH/gw1");
  EXPECT_EQ(c.will_qos, 1);
  EXPECT_FALSE(c.will_retain);
  EXPECT_TRUE(c.clean_start);
  const auto p = parse(c.will_payload);
  ASSERT_EQ(p.metrics_size(), 1);
  EXPECT_EQ(p.metrics(0).name(), "bdSeq");
  EXPECT_EQ(p.metrics(0).datatype(), static_cast<unsigned>(pb::Int64));
  EXPECT_EQ(bdseq_of(p), 0);
  EXPECT_FALSE(p.has_seq()) << "NDEATH must not include seq (spec ch6 payloads-ndeath-seq)";
  EXPECT_EQ(p.timestamp(), kT0) << "the connect time, not 0";
  EXPECT_EQ(p.metrics(0).timestamp(), kT0);
}

// Facts A.4.3/A.4.4, contract: subscribe NCMD (and DCMD) at QoS 1 first,
// then NBIRTH with seq 0, bdSeq as in the Will and Node Control/Rebirth
// false without alias, then every device's DBIRTH, all QoS 0, not retained.
TEST(EdgeSession, BirthsComeInOrderAfterTheSubscriptions) {
  Rig r;
  r.session.device_online(r.out, "net1-node5", drive_metrics(), kT0 - 50);
  r.session.device_online(r.out, "net1-node6", drive_metrics(), kT0 - 40);
  EXPECT_TRUE(r.take().empty()) << "nothing before the connection";
  const auto c = r.connect(kT0);
  const auto out = r.take();
  EXPECT_EQ(topics(out), (std::vector<std::string>{
                             "SUB spBv1.0/plant1/NCMD/gw1", "SUB spBv1.0/plant1/DCMD/gw1/+",
                             "spBv1.0/plant1/NBIRTH/gw1", "spBv1.0/plant1/DBIRTH/gw1/net1-node5",
                             "spBv1.0/plant1/DBIRTH/gw1/net1-node6"}));
  EXPECT_EQ(out[0].qos, 1);
  EXPECT_EQ(out[1].qos, 1);
  for (std::size_t i = 2; i < out.size(); ++i) {
    EXPECT_EQ(out[i].qos, 0);
    EXPECT_FALSE(out[i].retain);
  }
  const auto nbirth = parse(out[2].payload);
  EXPECT_EQ(nbirth.seq(), 0U);
  EXPECT_EQ(nbirth.timestamp(), kT0);
  EXPECT_EQ(bdseq_of(nbirth), c.bd_seq) << "NBIRTH bdSeq = the Will's (spec ch4 bdseq-matching)";
  const auto* rebirth = metric(nbirth, "Node Control/Rebirth");
  ASSERT_TRUE(rebirth);
  EXPECT_EQ(rebirth->datatype(), static_cast<unsigned>(pb::Boolean));
  EXPECT_FALSE(rebirth->boolean_value());
  EXPECT_FALSE(rebirth->has_alias());
  const auto d5 = parse(out[3].payload);
  EXPECT_EQ(d5.seq(), 1U);
  EXPECT_EQ(parse(out[4].payload).seq(), 2U);
  // Every metric with name, datatype, value and timestamp; object metrics
  // with index/subIndex (contract); Device Control/Rebirth false.
  const auto* sw = metric(d5, "Statusword");
  ASSERT_TRUE(sw);
  EXPECT_EQ(sw->datatype(), static_cast<unsigned>(pb::UInt16));
  EXPECT_EQ(sw->int_value(), 0x0237U);
  EXPECT_EQ(sw->timestamp(), kT0 - 50) << "the time the value became known";
  EXPECT_EQ(sw->properties().values(0).int_value(), 0x6041U);
  const auto* drb = metric(d5, "Device Control/Rebirth");
  ASSERT_TRUE(drb);
  EXPECT_FALSE(drb->boolean_value());
  EXPECT_EQ(r.session.state(), EdgeSession::State::Born);
}

// Facts A.4.4 (spec ch6 ndata-order/ddata-order): no DATA before the
// births; values changed meanwhile are in the DBIRTH.
TEST(EdgeSession, DataBeforeTheBirthsOnlyUpdatesTheBirth) {
  Rig r;
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  const Update u[] = {{0, std::uint64_t{0x1237}, kT0 + 5}};
  r.session.device_data(r.out, "d1", u, kT0 + 5);
  EXPECT_TRUE(r.take().empty());
  r.connect(kT0 + 10);
  const auto out = r.take();
  ASSERT_EQ(out.size(), 4U);
  const auto dbirth = parse(out[3].payload);
  const auto* sw = metric(dbirth, "Statusword");
  ASSERT_TRUE(sw);
  EXPECT_EQ(sw->int_value(), 0x1237U);
  EXPECT_EQ(sw->timestamp(), kT0 + 5);
}

// Contract: DDATA with only the changed metrics, each with the frame's
// timestamp; no datatype in DATA (spec ch6 "Metric").
TEST(EdgeSession, DdataCarriesOnlyTheChangedMetrics) {
  Rig r;
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  r.connect(kT0);
  r.take();
  const Update u[] = {{1, std::uint64_t{0x001F}, kT0 + 7}, {99, std::uint64_t{1}, kT0 + 7}};
  r.session.device_data(r.out, "d1", u, kT0 + 8);
  const auto out = r.take();
  ASSERT_EQ(topics(out), std::vector<std::string>{"spBv1.0/plant1/DDATA/gw1/d1"});
  const auto p = parse(out[0].payload);
  EXPECT_EQ(p.seq(), 2U);
  EXPECT_EQ(p.timestamp(), kT0 + 8);
  ASSERT_EQ(p.metrics_size(), 1) << "the unknown position is skipped";
  EXPECT_EQ(p.metrics(0).name(), "Controlword");
  EXPECT_EQ(p.metrics(0).int_value(), 0x001FU);
  EXPECT_EQ(p.metrics(0).timestamp(), kT0 + 7);
  EXPECT_FALSE(p.metrics(0).has_datatype());
}

// Facts A.7 aliases: births carry name and alias, DATA the alias only.
TEST(EdgeSession, WithAliasesDataCarriesTheAliasOnly) {
  Rig r;
  auto metrics = drive_metrics();
  metrics[0].alias = 0x0105'6041'00;
  r.session.device_online(r.out, "d1", metrics, kT0);
  r.connect(kT0);
  const auto births = r.take();
  const auto dbirth = parse(births.back().payload);
  const auto* sw = metric(dbirth, "Statusword");
  ASSERT_TRUE(sw);
  EXPECT_EQ(sw->alias(), 0x0105'6041'00U);
  const Update u[] = {{0, std::uint64_t{1}, kT0 + 1}};
  r.session.device_data(r.out, "d1", u, kT0 + 1);
  const auto p = parse(r.take().at(0).payload);
  ASSERT_EQ(p.metrics_size(), 1);
  EXPECT_FALSE(p.metrics(0).has_name());
  EXPECT_EQ(p.metrics(0).alias(), 0x0105'6041'00U);
}

// Facts A.5 (spec ch6 sequence-num-*): one counter over node and device
// messages, previous + 1, 255 wraps to 0.
TEST(EdgeSession, SeqIsOneCounterThatWrapsAt255) {
  Rig r;
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  r.session.set_node_metrics({object("Network 1/Bus State", 0, 0, 0)}, r.out, kT0);
  r.connect(kT0);
  EXPECT_EQ(r.take().size(), 4U);  // 2 SUBSCRIBEs, NBIRTH seq 0, DBIRTH seq 1
  std::vector<std::uint64_t> seqs;
  for (int i = 0; i < 300; ++i) {
    const auto ms = static_cast<std::uint64_t>(i);
    const Update u[] = {{0, ms, kT0 + ms}};
    if (i % 2)
      r.session.device_data(r.out, "d1", u, kT0 + ms);
    else
      r.session.node_data(r.out, u, kT0 + ms);
  }
  for (const auto& o : r.take()) seqs.push_back(parse(o.payload).seq());
  ASSERT_EQ(seqs.size(), 300U);
  for (std::size_t i = 0; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], (i + 2) % 256) << i;
  EXPECT_EQ(seqs[253], 255U);
  EXPECT_EQ(seqs[254], 0U);
}

// Facts A.6 (spec ch5 rebirth-action-1..3): NCMD Node Control/Rebirth =
// true: NBIRTH with seq 0 and the same bdSeq, then every DBIRTH; no CONNECT.
TEST(EdgeSession, NcmdRebirthRepeatsTheBirthsWithTheSameBdSeq) {
  Rig r;
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  const auto c = r.connect(kT0);
  r.take();
  const Update u[] = {{0, std::uint64_t{7}, kT0 + 1}};
  r.session.device_data(r.out, "d1", u, kT0 + 1);
  r.take();
  const auto cmd = r.session.received(r.out, "spBv1.0/plant1/NCMD/gw1", ncmd_rebirth(), kT0 + 100);
  EXPECT_FALSE(cmd) << "a rebirth is not a write";
  const auto out = r.take();
  ASSERT_EQ(topics(out), (std::vector<std::string>{"spBv1.0/plant1/NBIRTH/gw1", "spBv1.0/plant1/DBIRTH/gw1/d1"}));
  const auto nbirth = parse(out[0].payload);
  EXPECT_EQ(nbirth.seq(), 0U);
  EXPECT_EQ(bdseq_of(nbirth), c.bd_seq);
  const auto dbirth = parse(out[1].payload);
  EXPECT_EQ(dbirth.seq(), 1U);
  ASSERT_TRUE(metric(dbirth, "Statusword"));
  EXPECT_EQ(metric(dbirth, "Statusword")->int_value(), 7U) << "the current value";
  EXPECT_EQ(r.session.last_rebirth(), kT0 + 100);
  EXPECT_EQ(r.store.current(), c.bd_seq) << "no new bdSeq without a CONNECT";
}

// The owner's own rebirth (after it dropped DATA under backpressure, a seq
// gap hosts cannot repair, facts A.6): the same birth sequence as an NCMD
// rebirth, same bdSeq; nothing before the births or when offline.
TEST(EdgeSession, OwnersRebirthRepeatsTheBirthsOnlyWhenBorn) {
  Rig r({}, "scada");
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  r.session.rebirth(r.out, kT0);
  EXPECT_TRUE(r.take().empty()) << "offline";
  const auto c = r.connect(kT0);
  r.take();
  r.session.rebirth(r.out, kT0);
  EXPECT_TRUE(r.take().empty()) << "waiting for the Primary Host";
  r.session.received(r.out, "spBv1.0/STATE/scada", state_json(true, kT0), kT0);
  r.take();
  r.session.rebirth(r.out, kT0 + 5);
  const auto out = r.take();
  ASSERT_EQ(topics(out), (std::vector<std::string>{"spBv1.0/plant1/NBIRTH/gw1", "spBv1.0/plant1/DBIRTH/gw1/d1"}));
  EXPECT_EQ(parse(out[0].payload).seq(), 0U);
  EXPECT_EQ(bdseq_of(parse(out[0].payload)), c.bd_seq);
  EXPECT_EQ(r.session.last_rebirth(), kT0 + 5);
}

TEST(EdgeSession, NcmdRebirthFalseDoesNothing) {
  Rig r;
  r.connect(kT0);
  r.take();
  pb::Payload p;
  auto* m = p.add_metrics();
  m->set_name("Node Control/Rebirth");
  m->set_boolean_value(false);
  r.session.received(r.out, "spBv1.0/plant1/NCMD/gw1", p.SerializeAsString(), kT0);
  EXPECT_TRUE(r.take().empty());
}

// Contract: DCMD Device Control/Rebirth: that DBIRTH.
TEST(EdgeSession, DcmdDeviceRebirthSendsThatDbirth) {
  Rig r;
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  r.session.device_online(r.out, "d2", drive_metrics(), kT0);
  r.connect(kT0);
  r.take();
  pb::Payload p;
  auto* m = p.add_metrics();
  m->set_name("Device Control/Rebirth");
  m->set_boolean_value(true);
  r.session.received(r.out, "spBv1.0/plant1/DCMD/gw1/d2", p.SerializeAsString(), kT0 + 1);
  const auto out = r.take();
  ASSERT_EQ(topics(out), std::vector<std::string>{"spBv1.0/plant1/DBIRTH/gw1/d2"});
  EXPECT_EQ(parse(out[0].payload).seq(), 3U);
}

// Issue 27 item 9: with owner_reads_rebirths, a rebirth's DBIRTHs are the
// owner's (it reads the values again first): NCMD gives the NBIRTH alone,
// no DDATA of a device until its DBIRTH, and the command says rebirth.
TEST(EdgeSession, WithOwnerReadsRebirthsTheOwnerSendsTheDbirths) {
  BdSeqStore store{std::filesystem::path{}};
  EdgeSession session({"plant1", "gw1", "", true}, store);  // as sparkplug::EdgeNode runs it
  std::vector<Outgoing> out;
  session.device_online(out, "d1", drive_metrics(), kT0);
  (void)session.connect_params(kT0);
  session.connected(out, kT0);
  out.clear();
  pb::Payload p;
  auto* m = p.add_metrics();
  m->set_name("Node Control/Rebirth");
  m->set_boolean_value(true);
  const auto cmd = session.received(out, "spBv1.0/plant1/NCMD/gw1", p.SerializeAsString(), kT0 + 1);
  ASSERT_TRUE(cmd);
  EXPECT_TRUE(cmd->rebirth);
  EXPECT_TRUE(cmd->device.empty());
  EXPECT_EQ(topics(out), std::vector<std::string>{"spBv1.0/plant1/NBIRTH/gw1"});
  out.clear();
  const Update u[] = {{0, std::uint64_t{1}, kT0 + 2}};
  session.device_data(out, "d1", u, kT0 + 2);
  EXPECT_TRUE(out.empty()) << "no DDATA before its DBIRTH";
  session.device_online(out, "d1", drive_metrics(), kT0 + 3);
  ASSERT_EQ(topics(out), std::vector<std::string>{"spBv1.0/plant1/DBIRTH/gw1/d1"});
  EXPECT_EQ(parse(out[0].payload).seq(), 1U) << "right after the NBIRTH";
}

// Commands other than rebirth go to the owner, resolved to the device's
// metric (by name or alias) and typed; unknown or ill-typed ones are listed
// as refused and change nothing here.
TEST(EdgeSession, DcmdWritesAreResolvedAndTypedForTheOwner) {
  Rig r;
  auto metrics = drive_metrics();
  metrics[1].alias = 17;
  r.session.device_online(r.out, "d1", metrics, kT0);
  r.connect(kT0);
  r.take();
  pb::Payload p;
  auto* a = p.add_metrics();
  a->set_alias(17);
  a->set_int_value(0x80);
  auto* b = p.add_metrics();
  b->set_name("Statusword");
  b->set_string_value("nope");
  auto* c = p.add_metrics();
  c->set_name("Nonexistent");
  c->set_int_value(1);
  const auto cmd = r.session.received(r.out, "spBv1.0/plant1/DCMD/gw1/d1", p.SerializeAsString(), kT0 + 1);
  ASSERT_TRUE(cmd);
  EXPECT_EQ(cmd->device, "d1");
  ASSERT_EQ(cmd->items.size(), 1U);
  EXPECT_EQ(cmd->items[0].metric, 1U);
  EXPECT_EQ(cmd->items[0].value, Value{std::uint64_t{0x80}});
  EXPECT_EQ(cmd->refused, (std::vector<std::string>{"Statusword", "Nonexistent"}));
  EXPECT_TRUE(r.take().empty()) << "the written value shows in a DDATA once written";
  EXPECT_FALSE(r.session.received(r.out, "spBv1.0/plant1/DCMD/gw1/unknown", p.SerializeAsString(), kT0));
}

// Facts A.4.7 (spec ch5 operational-behavior-device-ddeath), contract:
// DDEATH when the node is lost, DBIRTH when it comes back; nothing for the
// device in between.
TEST(EdgeSession, LostDeviceGetsDdeathAndDbirthWhenBack) {
  Rig r;
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  r.connect(kT0);
  r.take();
  r.session.device_lost(r.out, "d1", kT0 + 10);
  auto out = r.take();
  ASSERT_EQ(topics(out), std::vector<std::string>{"spBv1.0/plant1/DDEATH/gw1/d1"});
  const auto ddeath = parse(out[0].payload);
  EXPECT_EQ(ddeath.seq(), 2U);
  EXPECT_EQ(ddeath.timestamp(), kT0 + 10) << "hosts take it as the time the device went offline";
  r.session.device_lost(r.out, "d1", kT0 + 11);
  const Update u[] = {{0, std::uint64_t{1}, kT0 + 12}};
  r.session.device_data(r.out, "d1", u, kT0 + 12);
  EXPECT_TRUE(r.take().empty()) << "no second DDEATH, no DDATA while lost";
  r.session.device_online(r.out, "d1", drive_metrics(), kT0 + 20);
  out = r.take();
  ASSERT_EQ(topics(out), std::vector<std::string>{"spBv1.0/plant1/DBIRTH/gw1/d1"});
  EXPECT_EQ(parse(out[0].payload).seq(), 3U);
  // A device lost while disconnected is simply not born at the next CONNECT.
  r.session.lost();
  r.session.device_lost(r.out, "d1", kT0 + 30);
  r.connect(kT0 + 40);
  EXPECT_EQ(topics(r.take()).size(), 3U) << "2 SUBSCRIBEs and the NBIRTH";
}

// Facts A.4.6 (spec ch5 intentional-disconnect): NDEATH with the same
// bdSeq before DISCONNECT.
TEST(EdgeSession, CleanStopPublishesNdeathBeforeDisconnect) {
  Rig r;
  const auto c = r.connect(kT0);
  r.take();
  r.session.stop(r.out, kT0 + 1);
  const auto out = r.take();
  ASSERT_EQ(topics(out), (std::vector<std::string>{"spBv1.0/plant1/NDEATH/gw1", "DISCONNECT"}));
  EXPECT_EQ(out[0].qos, 1);
  EXPECT_FALSE(out[0].retain);
  const auto ndeath = parse(out[0].payload);
  EXPECT_EQ(bdseq_of(ndeath), bdseq_of(parse(c.will_payload))) << "the Will's bdSeq";
  EXPECT_FALSE(ndeath.has_seq());
  EXPECT_EQ(ndeath.timestamp(), kT0 + 1) << "the stop time (issue 27 item 7)";
  EXPECT_EQ(ndeath.metrics(0).timestamp(), kT0 + 1);
  r.session.stop(r.out, kT0 + 2);
  EXPECT_TRUE(r.take().empty()) << "once";
}

// Contract/facts A.5: bdSeq goes up with every CONNECT, also across a
// restart of the process (a new store and session on the same state dir).
TEST(EdgeSession, BdSeqGoesUpPerConnectAndAcrossARestart) {
  TempDir dir;
  {
    Rig r(dir.path());
    EXPECT_EQ(r.connect().bd_seq, 0);
    r.take();
    r.session.lost();
    const auto second = r.connect();
    EXPECT_EQ(second.bd_seq, 1);
    EXPECT_EQ(bdseq_of(parse(r.take().at(2).payload)), 1) << "NBIRTH of the second connection";
  }
  Rig after(dir.path());
  const auto c = after.connect();
  EXPECT_EQ(c.bd_seq, 2);
  EXPECT_EQ(bdseq_of(parse(c.will_payload)), 2);
}

// Facts A.4.5 (spec ch5 Primary Host): with a primary host, subscribe to
// spBv1.0/STATE/<host>, no births until online.
TEST(EdgeSession, PrimaryHostBirthsWaitForOnline) {
  Rig r({}, "scada");
  r.session.device_online(r.out, "d1", drive_metrics(), kT0);
  r.connect(kT0);
  auto out = r.take();
  EXPECT_EQ(topics(out), (std::vector<std::string>{"SUB spBv1.0/plant1/NCMD/gw1", "SUB spBv1.0/plant1/DCMD/gw1/+",
                                                   "SUB spBv1.0/STATE/scada"}));
  EXPECT_EQ(out[2].qos, 1);
  EXPECT_EQ(r.session.state(), EdgeSession::State::WaitingForHost);
  const Update u[] = {{0, std::uint64_t{1}, kT0 + 1}};
  r.session.device_data(r.out, "d1", u, kT0 + 1);
  r.session.received(r.out, "spBv1.0/plant1/NCMD/gw1", ncmd_rebirth(), kT0 + 2);
  EXPECT_TRUE(r.take().empty()) << "no DATA and no births while waiting";
  r.session.received(r.out, "spBv1.0/STATE/scada", "not json", kT0 + 3);
  r.session.received(r.out, "spBv1.0/STATE/other", state_json(true, kT0), kT0 + 3);
  EXPECT_TRUE(r.take().empty());
  r.session.received(r.out, "spBv1.0/STATE/scada", state_json(true, kT0 - 1000), kT0 + 4);
  out = r.take();
  EXPECT_EQ(topics(out), (std::vector<std::string>{"spBv1.0/plant1/NBIRTH/gw1", "spBv1.0/plant1/DBIRTH/gw1/d1"}));
  EXPECT_TRUE(r.session.host_online());
}

// Spec ch5 Primary Host: offline with a timestamp >= the last one: NDEATH
// and disconnect; an older (stale) offline is ignored; after a reconnect the
// births wait for a new online no older than the offline.
TEST(EdgeSession, PrimaryHostOfflineEndsTheSessionUnlessStale) {
  Rig r({}, "scada");
  r.connect(kT0);
  r.session.received(r.out, "spBv1.0/STATE/scada", state_json(true, kT0 + 100), kT0 + 1);
  r.take();
  r.session.received(r.out, "spBv1.0/STATE/scada", state_json(false, kT0 + 50), kT0 + 2);
  EXPECT_TRUE(r.take().empty()) << "stale offline ignored";
  EXPECT_EQ(r.session.state(), EdgeSession::State::Born);
  r.session.received(r.out, "spBv1.0/STATE/scada", state_json(false, kT0 + 200), kT0 + 3);
  auto out = r.take();
  ASSERT_EQ(topics(out), (std::vector<std::string>{"spBv1.0/plant1/NDEATH/gw1", "DISCONNECT"}));
  EXPECT_FALSE(r.session.host_online());
  r.session.lost();
  // Next connection (maybe the next server): the retained STATE comes
  // again; a stale online (older than the offline) is not enough.
  const auto c = r.connect(kT0 + 1000);
  EXPECT_EQ(c.bd_seq, 1);
  r.take();
  r.session.received(r.out, "spBv1.0/STATE/scada", state_json(true, kT0 + 150), kT0 + 1001);
  EXPECT_TRUE(r.take().empty()) << "stale online ignored";
  r.session.received(r.out, "spBv1.0/STATE/scada", state_json(true, kT0 + 900), kT0 + 1002);
  out = r.take();
  ASSERT_EQ(topics(out), std::vector<std::string>{"spBv1.0/plant1/NBIRTH/gw1"});
  EXPECT_EQ(bdseq_of(parse(out[0].payload)), 1);
}

// Spec ch4: ids must not contain '+', '/' or '#'.
TEST(EdgeSession, IdsWithTopicCharactersAreRefused) {
  BdSeqStore s({});
  EXPECT_THROW(EdgeSession({"a/b", "gw1", ""}, s), std::invalid_argument);
  EXPECT_THROW(EdgeSession({"g", "gw+1", ""}, s), std::invalid_argument);
  EXPECT_THROW(EdgeSession({"g", "gw1", "h#"}, s), std::invalid_argument);
  EXPECT_THROW(EdgeSession({"", "gw1", ""}, s), std::invalid_argument);
  EdgeSession ok({"g", "gw1", ""}, s);
  std::vector<Outgoing> out;
  EXPECT_FALSE(ok.device_online(out, "net1/node5", drive_metrics(), kT0));
  EXPECT_FALSE(ok.device_online(out, "", drive_metrics(), kT0));
  EXPECT_TRUE(ok.device_online(out, "net1-node5", drive_metrics(), kT0));
}

}  // namespace
}  // namespace gateway::sparkplug
