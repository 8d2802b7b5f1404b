// SparkplugOutput: stack events -> the EdgeSession's births, deaths and
// data, and NCMD/DCMD writes -> the request core (api-contract.md
// "Sparkplug B"; facts A.3, A.4.7). A real EdgeSession (bdSeq not kept),
// no broker: what it publishes is decoded with the generated parser. The
// request core is a fake that records requests and answers as told, and
// once the real RequestCore over the fake networks, for roles and audit.
#include "sparkplug/sparkplug_output.hpp"

#include <gtest/gtest.h>

#include <boost/json/parse.hpp>

#include "support/fake_networks.hpp"
#include "support/memory_log.hpp"
#include "support/write_json.hpp"
#include "unit/gateway/sparkplug/sparkplug_support.hpp"

namespace gateway {
namespace {

namespace pb = sparkplug_test::pb;
using sparkplug_test::metric;
using sparkplug_test::parse;
using CT = canopen::DataType;

constexpr std::uint64_t kT0 = 1'767'225'600'000;  // 2026-01-01T00:00:00Z
constexpr std::uint8_t kNode = 5;

// TPDO1: 6000h sub 1 (u8), 2001h (i16). RPDO1: 6200h sub 1 and sub 2 (u8).
// 2200h (u16, 0..1000) and 2300h (u32) are listed in sparkplug-metrics.
const char* kEds = R"([FileInfo]
FileName=io.eds
[DeviceInfo]
VendorName=Test
[MandatoryObjects]
SupportedObjects=1
1=0x1000
[1000]
ParameterName=Device type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0
[OptionalObjects]
SupportedObjects=4
1=0x1400
2=0x1600
3=0x1800
4=0x1A00
[1400]
ParameterName=RPDO1 communication
ObjectType=0x9
SubNumber=3
[1400sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=2
[1400sub1]
ParameterName=COB-ID
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x200
[1400sub2]
ParameterName=Transmission type
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=255
[1600]
ParameterName=RPDO1 mapping
ObjectType=0x9
SubNumber=3
[1600sub0]
ParameterName=Number of mapped objects
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=2
[1600sub1]
ParameterName=Mapped object 1
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0x62000108
[1600sub2]
ParameterName=Mapped object 2
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0x62000208
[1800]
ParameterName=TPDO1 communication
ObjectType=0x9
SubNumber=3
[1800sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=2
[1800sub1]
ParameterName=COB-ID
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x180
[1800sub2]
ParameterName=Transmission type
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=255
[1A00]
ParameterName=TPDO1 mapping
ObjectType=0x9
SubNumber=3
[1A00sub0]
ParameterName=Number of mapped objects
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=2
[1A00sub1]
ParameterName=Mapped object 1
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0x60000108
[1A00sub2]
ParameterName=Mapped object 2
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0x20010010
[ManufacturerObjects]
SupportedObjects=3
1=0x2001
2=0x2200
3=0x2300
[2001]
ParameterName=Temperature
ObjectType=0x7
DataType=0x0003
AccessType=ro
PDOMapping=1
DefaultValue=0
[2200]
ParameterName=Speed
ObjectType=0x7
DataType=0x0006
AccessType=rw
LowLimit=0
HighLimit=1000
DefaultValue=0
[2300]
ParameterName=Serial
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0
[6000]
ParameterName=Read inputs
ObjectType=0x8
SubNumber=2
[6000sub0]
ParameterName=Number of inputs
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[6000sub1]
ParameterName=Input 1
ObjectType=0x7
DataType=0x0005
AccessType=ro
PDOMapping=1
DefaultValue=0
[6200]
ParameterName=Write outputs
ObjectType=0x8
SubNumber=3
[6200sub0]
ParameterName=Number of outputs
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=2
[6200sub1]
ParameterName=Output 1
ObjectType=0x7
DataType=0x0005
AccessType=rww
PDOMapping=1
DefaultValue=0
[6200sub2]
ParameterName=Output 2
ObjectType=0x7
DataType=0x0005
AccessType=rww
PDOMapping=1
DefaultValue=0
)";

const std::string kDevice = "spBv1.0/plant/DBIRTH/gw/io";

// A fake request core: records each request; the test answers.
struct FakeCore {
  std::vector<core::Request> requests;
  std::vector<core::RequestCore::Done> done;
  void answer(std::size_t i, core::Result r) { done.at(i)(std::move(r)); }
};

struct Rig {
  explicit Rig(Role commands_role = Role::Operator, bool real_core = false)
      : desc(canopen::eds::parse_device_description(kEds, "io.eds", kNode)),
        store(""),
        session({"plant", "gw", "", true}, store),  // the DBIRTHs of a rebirth are ours, as in EdgeNode
        log(LogLevel::Info, mlog.file),
        fake_nets(kEds, kNode),
        real(fake_nets, tokens, {}, [this](const std::string& line) { audit.push_back(line); }) {
    (void)pdos.add_node(kNode, desc.od);
    NodeConfig node;
    node.id = kNode;
    node.name = "io";
    node.sparkplug_metrics = {{0x2200, {}}, {0x2300, {}}};
    SparkplugOutput::Sources src;
    src.description = [this](std::uint32_t net, std::uint8_t n) {
      return net == 1 && n == kNode ? &desc : nullptr;
    };
    src.pdo_table = [this](std::uint32_t net) { return net == 1 ? &pdos : nullptr; };
    src.bus_state = [](std::uint32_t) { return canopen::can::BusState::ErrorActive; };
    src.now_ms = [this] { return now; };
    SparkplugOutput::Execute exec;
    if (real_core) {
      exec = [this](core::Request r, core::RequestCore::Done d) { real.execute(std::move(r), std::move(d)); };
    } else {
      exec = [this](core::Request r, core::RequestCore::Done d) {
        // The birth's reads of objects without a value (issue 27 item 8)
        // get no answer unless a test answers them itself: the others
        // are then not read and the requests are those of the listed
        // objects and the test's own.
        const auto* read = std::get_if<core::SdoRead>(&r.command);
        if (read != nullptr && read->index != 0x2200 && read->index != 0x2300 && !answer_unheard) {
          unheard.push_back(*read);
          d(core::Problem{504, "SDO timeout", {}, {}, 0x05040000, 0, true, {}});
          return;
        }
        fake.requests.push_back(std::move(r));
        fake.done.push_back(std::move(d));
      };
    }
    output.emplace(
        session, [this](std::vector<sparkplug::Outgoing>& o) { sent.insert(sent.end(), o.begin(), o.end()); },
        exec, std::vector<SparkplugOutput::Network>{{1, {node}}}, src, SparkplugOutput::Options{false, commands_role},
        log);
    output->start();
    session.connect_params(now);
    session.connected(sent, now);
  }

  void event(canopen::EventBody body, std::uint64_t ms = 0) {
    canopen::Event ev;
    ev.timestamp = canopen::can::Frame::Clock::time_point(std::chrono::milliseconds(ms));
    ev.body = std::move(body);
    output->on_event(1, ev);
  }
  void boot_up() {
    event(canopen::NodeStateEvent{kNode, canopen::NmtState::Initialising, std::nullopt,
                                  canopen::NodeStateEvent::Cause::BootUp},
          kT0 + 5);
  }
  // The two listed reads, answered in turn (2200h = 42, 2300h = 7).
  void answer_reads() {
    ASSERT_EQ(fake.requests.size(), 1u) << "one read at a time";
    fake.answer(0, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned16, 42)});
    ASSERT_EQ(fake.requests.size(), 2u);
    fake.answer(1, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 7)});
  }
  // A DCMD as a host sends it, through the session as the EdgeClient does.
  void dcmd(std::string_view name, pb::DataType type, std::uint64_t value) {
    pb::Payload p;
    p.set_timestamp(now);
    auto* m = p.add_metrics();
    m->set_name(std::string(name));
    m->set_datatype(static_cast<std::uint32_t>(type));
    if (type == pb::Int64 || type == pb::UInt64)
      m->set_long_value(value);
    else
      m->set_int_value(static_cast<std::uint32_t>(value));
    std::vector<sparkplug::Outgoing> out;
    auto cmd = session.received(out, "spBv1.0/plant/DCMD/gw/io", p.SerializeAsString(), now);
    ASSERT_TRUE(cmd);
    output->on_command(*cmd);
  }
  // NCMD Node Control/Rebirth (device "") or DCMD Device Control/Rebirth.
  void rebirth(std::string_view device) {
    pb::Payload p;
    p.set_timestamp(now);
    auto* m = p.add_metrics();
    m->set_name(device.empty() ? "Node Control/Rebirth" : "Device Control/Rebirth");
    m->set_datatype(pb::Boolean);
    m->set_boolean_value(true);
    std::vector<sparkplug::Outgoing> out;
    auto cmd = session.received(
        out, device.empty() ? std::string("spBv1.0/plant/NCMD/gw") : "spBv1.0/plant/DCMD/gw/" + std::string(device),
        p.SerializeAsString(), now);
    sent.insert(sent.end(), out.begin(), out.end());
    ASSERT_TRUE(cmd);
    EXPECT_TRUE(cmd->rebirth);
    output->on_command(*cmd);
  }
  // A DCMD with several metrics (UInt8 values).
  void dcmd_u8(const std::vector<std::pair<std::string, std::uint32_t>>& items) {
    pb::Payload p;
    p.set_timestamp(now);
    for (const auto& [name, value] : items) {
      auto* m = p.add_metrics();
      m->set_name(name);
      m->set_datatype(pb::UInt8);
      m->set_int_value(value);
    }
    std::vector<sparkplug::Outgoing> out;
    auto cmd = session.received(out, "spBv1.0/plant/DCMD/gw/io", p.SerializeAsString(), now);
    ASSERT_TRUE(cmd);
    output->on_command(*cmd);
  }
  std::string logged() {
    log.flush();  // info lines wait for the loop's flush
    return mlog.text();
  }
  std::vector<const sparkplug::Outgoing*> published(std::string_view type) const {
    std::vector<const sparkplug::Outgoing*> v;
    for (const auto& o : sent)
      if (o.kind == sparkplug::Outgoing::Kind::Publish && o.topic.find(std::string("/") + std::string(type) + "/") !=
                                                              std::string::npos)
        v.push_back(&o);
    return v;
  }

  std::uint64_t now = kT0;
  bool answer_unheard = false;         // true: those reads wait in `fake` like the others
  std::vector<core::SdoRead> unheard;  // the reads answered with a time-out
  canopen::eds::DeviceDescription desc;
  canopen::pdo::RemotePdoTable pdos;
  sparkplug::BdSeqStore store;
  sparkplug::EdgeSession session;
  MemoryLog mlog;
  Logger log;
  FakeCore fake;
  core::test_support::FakeNetworks fake_nets;
  auth::TokenStore tokens;
  std::vector<std::string> audit;
  core::RequestCore real;
  std::vector<sparkplug::Outgoing> sent;
  std::optional<SparkplugOutput> output;
};

// One metric of a payload, by value (an empty one, and a failure, if absent).
pb::Payload::Metric one(const std::string& payload, std::string_view name) {
  const auto p = parse(payload);
  if (const auto* m = metric(p, name)) return *m;
  ADD_FAILURE() << "no metric " << name;
  return {};
}

std::uint64_t prop(const pb::Payload::Metric& m, std::string_view key) {
  const auto& ps = m.properties();
  for (int i = 0; i < ps.keys_size(); ++i)
    if (ps.keys(i) == key) return ps.values(i).has_int_value() ? ps.values(i).int_value() : ps.values(i).long_value();
  return 0xFFFFFFFF;
}

// Contract: NBIRTH carries `Network <N>/Bus State`; DBIRTH when a node is
// heard (boot-up), with the PDO-mapped objects and the sparkplug-metrics
// objects read by SDO through the core (as viewer), each object metric with
// the index/subIndex properties.
TEST(SparkplugOutput, BootUpGivesADbirthWithPdoAndListedMetrics) {
  Rig rig;
  const auto nbirth = rig.published("NBIRTH");
  ASSERT_EQ(nbirth.size(), 1u);
  const auto nb = parse(nbirth[0]->payload);
  const auto* bus = metric(nb, "Network 1/Bus State");
  ASSERT_NE(bus, nullptr);
  EXPECT_EQ(bus->string_value(), "error-active");

  rig.boot_up();
  EXPECT_TRUE(rig.published("DBIRTH").empty()) << "not before the listed objects are read";
  ASSERT_EQ(rig.fake.requests.size(), 1u);
  const auto& read = rig.fake.requests[0];
  EXPECT_EQ(read.caller.transport, core::Transport::sparkplug);
  EXPECT_EQ(read.caller.role, Role::Viewer);
  EXPECT_TRUE(read.caller.authenticated);
  const auto* sdo = std::get_if<core::SdoRead>(&read.command);
  ASSERT_NE(sdo, nullptr);
  EXPECT_EQ(sdo->node, kNode);
  EXPECT_EQ(sdo->index, 0x2200);
  rig.answer_reads();

  const auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 1u);
  EXPECT_EQ(dbirth[0]->topic, kDevice);
  const auto p = parse(dbirth[0]->payload);
  const auto* input = metric(p, "Read inputs/Input 1");
  ASSERT_NE(input, nullptr);
  EXPECT_EQ(input->datatype(), pb::UInt8);
  EXPECT_EQ(prop(*input, "index"), 0x6000u);
  EXPECT_EQ(prop(*input, "subIndex"), 1u);
  ASSERT_NE(metric(p, "Temperature"), nullptr);
  ASSERT_NE(metric(p, "Write outputs/Output 2"), nullptr);
  const auto* speed = metric(p, "Speed");
  ASSERT_NE(speed, nullptr);
  EXPECT_EQ(speed->int_value(), 42u);
  EXPECT_EQ(metric(p, "Serial")->long_value(), 7u) << "UInt32 in long_value (contract, issue 27 item 6)";
  EXPECT_EQ(metric(p, "Node/State")->string_value(), "initialising");
  EXPECT_TRUE(metric(p, "EMCY/Error Code")->is_null());
  ASSERT_NE(metric(p, "Device Control/Rebirth"), nullptr);
  EXPECT_TRUE(metric(p, "Read inputs/Input 1")->is_null()) << "no TPDO yet";
}

// A failed read leaves that metric null, is logged, and the birth goes on.
TEST(SparkplugOutput, AFailedListedReadIsNullAndLogged) {
  Rig rig;
  rig.boot_up();
  rig.fake.answer(0, core::Problem{504, "SDO timeout", {}, {}, 0x05040000, 0, true, {}});
  rig.fake.answer(1, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 7)});
  const auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 1u);
  EXPECT_TRUE(one(dbirth[0]->payload, "Speed").is_null());
  EXPECT_NE(rig.logged().find("reading 2200h sub 0 for the DBIRTH failed (504 SDO timeout)"), std::string::npos);
}

// Contract / facts A.4.7: DDEATH when the node is lost, DBIRTH again when it
// comes back, with the values known.
TEST(SparkplugOutput, LostGivesDdeathAndBackGivesDbirth) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  rig.event(canopen::PdoEvent{kNode, 1, 0x185, {}, {{0x6000, 1, "Input 1", canopen::Value::of_unsigned(CT::Unsigned8, 9)}}, {}, {}},
            kT0 + 10);
  rig.event(canopen::NodeStateEvent{kNode, std::nullopt, canopen::NmtState::Operational,
                                    canopen::NodeStateEvent::Cause::Lost},
            kT0 + 20);
  const auto ddeath = rig.published("DDEATH");
  ASSERT_EQ(ddeath.size(), 1u);
  EXPECT_EQ(ddeath[0]->topic, "spBv1.0/plant/DDEATH/gw/io");
  EXPECT_EQ(parse(ddeath[0]->payload).timestamp(), kT0 + 20);
  // A TPDO while lost sends nothing.
  const auto before = rig.sent.size();
  rig.event(canopen::PdoEvent{kNode, 1, 0x185, {}, {{0x6000, 1, "Input 1", canopen::Value::of_unsigned(CT::Unsigned8, 1)}}, {}, {}},
            kT0 + 25);
  EXPECT_EQ(rig.sent.size(), before);

  rig.event(canopen::NodeStateEvent{kNode, canopen::NmtState::Operational, canopen::NmtState::Operational,
                                    canopen::NodeStateEvent::Cause::Recovered},
            kT0 + 30);
  ASSERT_EQ(rig.fake.requests.size(), 3u) << "the listed objects are read again";
  rig.fake.answer(2, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned16, 43)});
  rig.fake.answer(3, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 7)});
  const auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 2u);
  const auto p = parse(dbirth[1]->payload);
  EXPECT_EQ(metric(p, "Node/State")->string_value(), "operational");
  EXPECT_EQ(metric(p, "Speed")->int_value(), 43u);
  EXPECT_EQ(metric(p, "Read inputs/Input 1")->int_value(), 1u) << "the last value heard";
}

// Contract: DDATA on every TPDO with only the changed metrics, each with the
// frame's timestamp; NMT state changes and EMCYs too.
TEST(SparkplugOutput, TpdoStateAndEmcyGiveDdataWithTheFramesTime) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  const std::vector<canopen::MappedValue> values = {
      {0x6000, 1, "Input 1", canopen::Value::of_unsigned(CT::Unsigned8, 3)},
      {0x2001, 0, "Temperature", canopen::Value::of_signed(CT::Integer16, -12)}};
  rig.event(canopen::PdoEvent{kNode, 1, 0x185, {}, values, {}, {}}, kT0 + 100);
  auto ddata = rig.published("DDATA");
  ASSERT_EQ(ddata.size(), 1u);
  auto p = parse(ddata[0]->payload);
  ASSERT_EQ(p.metrics_size(), 2);
  EXPECT_EQ(p.metrics(0).name(), "Read inputs/Input 1");
  EXPECT_EQ(p.metrics(0).int_value(), 3u);
  EXPECT_EQ(p.metrics(0).timestamp(), kT0 + 100);
  EXPECT_EQ(static_cast<std::int16_t>(p.metrics(1).int_value()), -12);

  rig.event(canopen::PdoEvent{kNode, 1, 0x185, {}, values, {}, {}}, kT0 + 200);
  EXPECT_EQ(rig.published("DDATA").size(), 1u) << "nothing changed: no DDATA";
  auto changed = values;
  changed[1].value = canopen::Value::of_signed(CT::Integer16, -11);
  rig.event(canopen::PdoEvent{kNode, 1, 0x185, {}, changed, {}, {}}, kT0 + 300);
  ddata = rig.published("DDATA");
  ASSERT_EQ(ddata.size(), 2u);
  p = parse(ddata[1]->payload);
  ASSERT_EQ(p.metrics_size(), 1);
  EXPECT_EQ(p.metrics(0).name(), "Temperature");
  EXPECT_EQ(p.metrics(0).timestamp(), kT0 + 300);

  rig.event(canopen::NodeStateEvent{kNode, canopen::NmtState::Operational, canopen::NmtState::PreOperational,
                                    canopen::NodeStateEvent::Cause::Heartbeat},
            kT0 + 400);
  p = parse(rig.published("DDATA").back()->payload);
  ASSERT_EQ(p.metrics_size(), 1);
  EXPECT_EQ(p.metrics(0).name(), "Node/State");
  EXPECT_EQ(p.metrics(0).string_value(), "operational");
  EXPECT_EQ(p.metrics(0).timestamp(), kT0 + 400);

  canopen::EmcyEvent emcy;
  emcy.node = kNode;
  emcy.error_code = 0x4210;
  emcy.error_register = 0x09;
  emcy.description = "Temperature device";
  rig.event(emcy, kT0 + 500);
  p = parse(rig.published("DDATA").back()->payload);
  ASSERT_EQ(p.metrics_size(), 3);
  EXPECT_EQ(metric(p, "EMCY/Error Code")->int_value(), 0x4210u);
  EXPECT_EQ(metric(p, "EMCY/Error Register")->int_value(), 0x09u);
  EXPECT_EQ(metric(p, "EMCY/Description")->string_value(), "Temperature device");
  EXPECT_EQ(metric(p, "EMCY/Error Code")->timestamp(), kT0 + 500);
}

// A PDO configuration read from the device at boot-up (BootConfigEvent
// Done) that changes the metric set gives a new DBIRTH with the new set;
// one that changes nothing gives none.
TEST(SparkplugOutput, ANewPdoConfigurationIsANewBirth) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  canopen::BootConfigEvent done;
  done.node = kNode;
  done.step = canopen::BootConfigEvent::Step::Done;
  rig.event(done, kT0 + 50);
  EXPECT_EQ(rig.fake.requests.size(), 2u) << "the same set: no new birth";
  // The device maps only 6000h sub 1 into TPDO1.
  canopen::pdo::PdoParameters tpdo1;
  tpdo1.comm.cob_id.raw = 0x185;
  tpdo1.count = 1;
  tpdo1.entries = {{1, 0x60000108}};
  ASSERT_TRUE(rig.pdos.apply_read(kNode, {canopen::pdo::Direction::Transmit, 1}, tpdo1));
  rig.event(done, kT0 + 60);
  ASSERT_EQ(rig.fake.requests.size(), 3u);
  rig.fake.answer(2, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned16, 42)});
  rig.fake.answer(3, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 7)});
  const auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 2u);
  const auto p = parse(dbirth[1]->payload);
  EXPECT_EQ(metric(p, "Temperature"), nullptr) << "no longer mapped";
  EXPECT_NE(metric(p, "Read inputs/Input 1"), nullptr);
}

// Issue 17 item 1: a node's settings or EDS changed at run time rebirth an
// online device at once (Sparkplug B 3.0: a DBIRTH states the device's
// whole metric set) with the new `sparkplug-metrics`; an offline one waits
// for its next boot-up.
TEST(SparkplugOutput, AChangedNodeConfigurationIsANewBirthWhileOnline) {
  Rig rig;
  rig.output->node_changed(1, kNode, {{0x2300, {}}});
  EXPECT_TRUE(rig.fake.requests.empty()) << "offline: nothing to send yet";
  rig.boot_up();
  ASSERT_EQ(rig.fake.requests.size(), 1u) << "only the one listed object now";
  rig.fake.answer(0, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 7)});
  ASSERT_EQ(rig.published("DBIRTH").size(), 1u);
  const auto first = parse(rig.published("DBIRTH")[0]->payload);
  EXPECT_EQ(metric(first, "Speed"), nullptr);

  rig.output->node_changed(1, kNode, {{0x2200, {}}, {0x2300, {}}});
  ASSERT_EQ(rig.fake.requests.size(), 2u) << "reborn at once: the listed objects read again";
  rig.fake.answer(1, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned16, 42)});
  rig.fake.answer(2, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 7)});
  const auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 2u);
  EXPECT_EQ(dbirth[1]->topic, kDevice) << "the same device id";
  const auto second = parse(dbirth[1]->payload);
  const auto* speed = metric(second, "Speed");
  ASSERT_NE(speed, nullptr);
  EXPECT_EQ(speed->int_value(), 42u);
}

// A bus state change is NDATA of `Network <N>/Bus State`.
TEST(SparkplugOutput, BusStateChangeIsNdata) {
  Rig rig;
  canopen::can::BusEvent b;
  b.previous = canopen::can::BusState::ErrorActive;
  b.state = canopen::can::BusState::BusOff;
  b.cause = canopen::can::BusEventCause::ErrorFrame;
  rig.event(b, kT0 + 1);
  ASSERT_EQ(rig.published("NDATA").size(), 1u);
  ASSERT_EQ(rig.sent.back().topic, "spBv1.0/plant/NDATA/gw");
  const auto p = parse(rig.sent.back().payload);
  ASSERT_EQ(p.metrics_size(), 1);
  EXPECT_EQ(p.metrics(0).name(), "Network 1/Bus State");
  EXPECT_EQ(p.metrics(0).string_value(), "bus-off");
}

// Contract: a DCMD on an RPDO-mapped object goes out as that RPDO (the
// others as last sent) through the core with sparkplug.commands-role; the
// written values then appear in a DDATA.
TEST(SparkplugOutput, DcmdToAnRpdoObjectIsAnRpdoWriteAndItsValuesADdata) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  rig.dcmd("Write outputs/Output 1", pb::UInt8, 200);
  ASSERT_EQ(rig.fake.requests.size(), 3u);
  const auto& r = rig.fake.requests[2];
  EXPECT_EQ(r.caller.transport, core::Transport::sparkplug);
  EXPECT_EQ(r.caller.role, Role::Operator);
  EXPECT_EQ(r.caller.who, "sparkplug:dcmd");
  EXPECT_EQ(r.network, 1u);
  const auto* w = std::get_if<core::RpdoWrite>(&r.command);
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(w->node, kNode);
  EXPECT_EQ(w->number, 1);
  EXPECT_EQ(test::rpdo_json(*w), boost::json::parse(R"({"values":[{"index":25088,"subIndex":1,"value":200}]})"));
  EXPECT_TRUE(rig.published("DDATA").empty()) << "nothing before the core answered";
  rig.now = kT0 + 700;
  rig.fake.answer(2, core::RpdoSent{1, kNode, 1, 0x205, 255, canopen::Bytes{200, 4}});
  const auto ddata = rig.published("DDATA");
  ASSERT_EQ(ddata.size(), 1u);
  const auto p = parse(ddata[0]->payload);
  EXPECT_EQ(metric(p, "Write outputs/Output 1")->int_value(), 200u);
  EXPECT_EQ(metric(p, "Write outputs/Output 2")->int_value(), 4u) << "the other mapped value as sent";
  EXPECT_EQ(metric(p, "Write outputs/Output 1")->timestamp(), kT0 + 700);
}

// Several values for one RPDO in one DCMD go out as one RPDO write (one frame).
TEST(SparkplugOutput, OneDcmdWithValuesForOneRpdoIsOneWrite) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  rig.dcmd_u8({{"Write outputs/Output 1", 1}, {"Write outputs/Output 2", 2}});
  ASSERT_EQ(rig.fake.requests.size(), 3u);
  const auto* w = std::get_if<core::RpdoWrite>(&rig.fake.requests[2].command);
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(test::rpdo_json(*w),
            boost::json::parse(R"({"values":[{"index":25088,"subIndex":1,"value":1},{"index":25088,"subIndex":2,"value":2}]})"));
}

// Contract: any other object by SDO download, typed from the EDS.
TEST(SparkplugOutput, DcmdToAnSdoObjectIsAnSdoWriteTypedFromTheEds) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  rig.dcmd("Speed", pb::UInt16, 500);
  ASSERT_EQ(rig.fake.requests.size(), 3u);
  const auto* w = std::get_if<core::SdoWrite>(&rig.fake.requests[2].command);
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(w->index, 0x2200);
  EXPECT_EQ(w->sub, 0);
  EXPECT_EQ(w->type, CT::Unsigned16);
  EXPECT_EQ(test::json_of(w->value), boost::json::value(500));
  rig.fake.answer(2, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned16, 500)});
  const auto ddata = rig.published("DDATA");
  ASSERT_EQ(ddata.size(), 1u);
  EXPECT_EQ(one(ddata[0]->payload, "Speed").int_value(), 500u);
}

// Contract: a refused write changes nothing and is logged; one that does not
// fit the EDS limits never reaches the core.
TEST(SparkplugOutput, ARefusedWriteChangesNothingAndIsLogged) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  rig.dcmd("Speed", pb::UInt16, 500);
  rig.fake.answer(2, core::Problem{422, "SDO abort: value too high", {}, {}, 0x06090031, 0, true, {}});
  EXPECT_TRUE(rig.published("DDATA").empty());
  EXPECT_NE(rig.logged().find("write of \"Speed\" (2200h sub 0) refused (422 SDO abort: value too high)"), std::string::npos);
  rig.dcmd("Speed", pb::UInt16, 1001);
  EXPECT_EQ(rig.fake.requests.size(), 3u) << "above HighLimit: refused before the core";
  EXPECT_NE(rig.logged().find("write refused"), std::string::npos);
  rig.dcmd("Node/State", pb::String, 0);  // not even a string: the session refuses it
  EXPECT_EQ(rig.fake.requests.size(), 3u);
}

// Contract: sparkplug.commands-role none ignores NCMD/DCMD writes.
TEST(SparkplugOutput, CommandsRoleNoneExecutesNothing) {
  Rig rig(Role::None);
  rig.boot_up();
  rig.answer_reads();
  rig.dcmd("Speed", pb::UInt16, 500);
  EXPECT_EQ(rig.fake.requests.size(), 2u) << "only the birth's reads";
  EXPECT_NE(rig.logged().find("ignored (sparkplug.commands-role is none)"), std::string::npos);
}

// With the real RequestCore: the birth's reads and a DCMD's write pass its
// role check and audit; a commands-role below operator is refused there.
TEST(SparkplugOutput, TheRealCoreAppliesRoleAndAudit) {
  for (const Role role : {Role::Viewer, Role::Operator}) {
    Rig rig(role, true);
    rig.boot_up();
    ASSERT_EQ(rig.fake_nets.pending.size(), 1u) << "the read of 2200h reached the bus";
    rig.fake_nets.answer(canopen::Bytes{42, 0});
    rig.fake_nets.answer(canopen::Bytes{7, 0, 0, 0});
    // Then the objects without a value, one at a time (issue 27 item 8);
    // an abort leaves one null and the next is read.
    std::size_t unheard = 0;
    while (!rig.fake_nets.pending.empty() && unheard < 100) {
      ASSERT_EQ(rig.fake_nets.pending.size(), 1u);
      rig.fake_nets.answer({}, make_error_code(canopen::SdoAbort::NoSuchObject));
      ++unheard;
    }
    EXPECT_GT(unheard, 0u);
    ASSERT_EQ(rig.published("DBIRTH").size(), 1u);
    EXPECT_EQ(one(rig.published("DBIRTH")[0]->payload, "Speed").int_value(), 42u);
    rig.dcmd("Speed", pb::UInt16, 300);
    if (role == Role::Viewer) {
      EXPECT_TRUE(rig.fake_nets.pending.empty()) << "refused by role";
      EXPECT_TRUE(rig.published("DDATA").empty());
      EXPECT_NE(rig.logged().find("refused (403"), std::string::npos);
      EXPECT_FALSE(rig.audit.empty()) << "the refusal by role is audited";
    } else {
      ASSERT_EQ(rig.fake_nets.pending.size(), 1u);
      EXPECT_EQ(rig.fake_nets.downloaded.back(), (canopen::Bytes{0x2C, 0x01}));
      rig.fake_nets.answer();
      const auto ddata = rig.published("DDATA");
      ASSERT_EQ(ddata.size(), 1u);
      EXPECT_EQ(one(ddata[0]->payload, "Speed").int_value(), 300u);
      ASSERT_FALSE(rig.audit.empty());
      EXPECT_NE(rig.audit.back().find("sparkplug:dcmd"), std::string::npos) << rig.audit.back();
    }
  }
}

// Issue 27 item 8 (contract "Sparkplug B"): the DBIRTH declares values, not
// nulls: after the sparkplug-metrics objects, the PDO-mapped objects that
// have no value yet are read by SDO (a TPDO not heard since, an RPDO
// output), one at a time; one heard meanwhile is not read again.
TEST(SparkplugOutput, TheDbirthReadsTheObjectsItDeclaresWithoutAValue) {
  Rig rig;
  rig.answer_unheard = true;
  rig.boot_up();
  rig.answer_reads();
  EXPECT_TRUE(rig.published("DBIRTH").empty()) << "not before those reads";
  const auto read_of = [&](std::size_t i) { return std::get_if<core::SdoRead>(&rig.fake.requests.at(i).command); };
  ASSERT_EQ(rig.fake.requests.size(), 3u) << "one read at a time";
  ASSERT_NE(read_of(2), nullptr);
  EXPECT_EQ(std::pair(read_of(2)->index, read_of(2)->sub), std::pair(std::uint16_t{0x6000}, std::uint8_t{1}));
  EXPECT_EQ(rig.fake.requests[2].caller.role, Role::Viewer);
  // Temperature's TPDO arrives meanwhile: it is not read.
  rig.event(canopen::PdoEvent{kNode, 1, 0x185, {}, {{0x2001, 0, "Temperature", canopen::Value::of_signed(CT::Integer16, -1234)}}, {}, {}},
            kT0 + 7);
  rig.fake.answer(2, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned8, 9)});
  ASSERT_EQ(rig.fake.requests.size(), 4u);
  EXPECT_EQ(std::pair(read_of(3)->index, read_of(3)->sub), std::pair(std::uint16_t{0x6200}, std::uint8_t{1}))
      << "the RPDO outputs after the TPDO inputs; 2001h was heard";
  rig.fake.answer(3, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned8, 3)});
  ASSERT_EQ(rig.fake.requests.size(), 5u);
  EXPECT_EQ(std::pair(read_of(4)->index, read_of(4)->sub), std::pair(std::uint16_t{0x6200}, std::uint8_t{2}));
  rig.fake.answer(4, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned8, 4)});
  EXPECT_EQ(rig.fake.requests.size(), 5u) << "nothing else without a value";
  const auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 1u);
  const auto p = parse(dbirth[0]->payload);
  EXPECT_EQ(metric(p, "Read inputs/Input 1")->int_value(), 9u);
  EXPECT_EQ(static_cast<std::int32_t>(metric(p, "Temperature")->int_value()), -1234) << "sign-extended (item 5)";
  EXPECT_EQ(metric(p, "Write outputs/Output 1")->int_value(), 3u);
  EXPECT_EQ(metric(p, "Write outputs/Output 2")->int_value(), 4u);
  for (const auto& m : p.metrics()) {
    if (m.properties().keys_size() > 0) {
      EXPECT_FALSE(m.is_null()) << m.name();
    }
  }
}

// A device that does not answer holds its birth for one SDO time-out, not
// one per object: after an unanswered read the others stay null until heard.
TEST(SparkplugOutput, AnUnansweredReadEndsTheReadsOfObjectsWithoutAValue) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  EXPECT_EQ(rig.unheard.size(), 1u);
  const auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 1u);
  EXPECT_TRUE(one(dbirth[0]->payload, "Read inputs/Input 1").is_null());
  EXPECT_EQ(rig.logged().find("reading 6000h sub 1 for the DBIRTH failed"), std::string::npos)
      << "not worth a warning: the value comes with its TPDO";
}

// Issue 27 item 9 (contract "Sparkplug B"): a rebirth (DCMD Device
// Control/Rebirth, NCMD Node Control/Rebirth) reads the sparkplug-metrics
// objects again for its DBIRTH instead of repeating the values of the last.
TEST(SparkplugOutput, ARebirthReadsTheListedObjectsAgain) {
  Rig rig;
  rig.boot_up();
  rig.answer_reads();
  ASSERT_EQ(rig.published("DBIRTH").size(), 1u);
  rig.rebirth("io");
  EXPECT_EQ(rig.published("DBIRTH").size(), 1u) << "not before the reads";
  ASSERT_EQ(rig.fake.requests.size(), 3u);
  rig.fake.answer(2, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned16, 43)});
  ASSERT_EQ(rig.fake.requests.size(), 4u);
  rig.fake.answer(3, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 8)});
  auto dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 2u);
  EXPECT_EQ(one(dbirth[1]->payload, "Speed").int_value(), 43u) << "read again";
  EXPECT_EQ(one(dbirth[1]->payload, "Serial").long_value(), 8u);

  const auto nbirths = rig.published("NBIRTH").size();
  rig.rebirth("");
  EXPECT_EQ(rig.published("NBIRTH").size(), nbirths + 1) << "the NBIRTH at once";
  EXPECT_EQ(rig.published("DBIRTH").size(), 2u) << "the DBIRTH after its reads";
  ASSERT_EQ(rig.fake.requests.size(), 5u);
  rig.fake.answer(4, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned16, 44)});
  rig.fake.answer(5, core::SdoValue{canopen::Value::of_unsigned(CT::Unsigned32, 8)});
  dbirth = rig.published("DBIRTH");
  ASSERT_EQ(dbirth.size(), 3u);
  EXPECT_EQ(one(dbirth[2]->payload, "Speed").int_value(), 44u);
  EXPECT_EQ(parse(dbirth[2]->payload).seq(), parse(rig.published("NBIRTH").back()->payload).seq() + 1u)
      << "right after the NBIRTH: no DDATA between";
}

}  // namespace
}  // namespace gateway
