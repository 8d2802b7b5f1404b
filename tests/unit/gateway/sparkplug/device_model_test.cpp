// A CANopen node as a Sparkplug device (api-contract.md "Sparkplug B"):
// its metrics from the EDS and the PDOs in use, names unique and stable
// with the quirks of vendor files, values by exception, and NCMD/DCMD
// writes as request-core commands in the format the core reads.
#include "sparkplug/device_model.hpp"

#include <gtest/gtest.h>

#include <boost/json/parse.hpp>
#include <filesystem>
#include <set>

#include "canopen/od/object_dictionary.hpp"
#include "core/rpdo_values.hpp"
#include "support/write_json.hpp"

namespace gateway::sparkplug {
namespace {

using CT = canopen::DataType;

// Every quirk the model handles, in one small file: TPDO1 maps an array
// sub named with a '/', a VAR named with a '/', a VAR with an empty name;
// TPDO2 is disabled (COB-ID bit 31); TPDO3 maps an object the file lacks;
// RPDO1 maps an output and a dummy entry; "Speed" and "speed" collide
// (case only); record "Node" sub "State" collides with the fixed
// `Node/State`.
const char* kEds = R"([FileInfo]
FileName=quirks.eds
[DeviceInfo]
VendorName=Test
[DummyUsage]
Dummy0005=1
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
SupportedObjects=8
1=0x1400
2=0x1600
3=0x1800
4=0x1801
5=0x1802
6=0x1A00
7=0x1A01
8=0x1A02
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
DefaultValue=0x00050008
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
[1801]
ParameterName=TPDO2 communication
ObjectType=0x9
SubNumber=2
[1801sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[1801sub1]
ParameterName=COB-ID
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x80000280
[1802]
ParameterName=TPDO3 communication
ObjectType=0x9
SubNumber=2
[1802sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[1802sub1]
ParameterName=COB-ID
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=$NODEID+0x380
[1A00]
ParameterName=TPDO1 mapping
ObjectType=0x9
SubNumber=4
[1A00sub0]
ParameterName=Number of mapped objects
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=3
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
[1A00sub3]
ParameterName=Mapped object 3
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0x21000020
[1A01]
ParameterName=TPDO2 mapping
ObjectType=0x9
SubNumber=2
[1A01sub0]
ParameterName=Number of mapped objects
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=1
[1A01sub1]
ParameterName=Mapped object 1
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0x20020010
[1A02]
ParameterName=TPDO3 mapping
ObjectType=0x9
SubNumber=2
[1A02sub0]
ParameterName=Number of mapped objects
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=1
[1A02sub1]
ParameterName=Mapped object 1
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=0x30000108
[ManufacturerObjects]
SupportedObjects=7
1=0x2001
2=0x2002
3=0x2100
4=0x2200
5=0x2201
6=0x2300
7=0x2400
[2001]
ParameterName=Temp/Humidity
ObjectType=0x7
DataType=0x0003
AccessType=ro
PDOMapping=1
DefaultValue=0
[2002]
ParameterName=Pressure
ObjectType=0x7
DataType=0x0003
AccessType=ro
PDOMapping=1
DefaultValue=0
[2100]
ParameterName=
ObjectType=0x7
DataType=0x0007
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
[2201]
ParameterName=speed
ObjectType=0x7
DataType=0x000D
AccessType=rw
DefaultValue=0 0
[2300]
ParameterName=Node
ObjectType=0x9
SubNumber=2
[2300sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[2300sub1]
ParameterName=State
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=0
[2400]
ParameterName=Clock
ObjectType=0x7
DataType=0x000C
AccessType=rw
DefaultValue=0 0
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
ParameterName=Input/1
ObjectType=0x7
DataType=0x0005
AccessType=ro
PDOMapping=1
DefaultValue=0
[6200]
ParameterName=Write outputs
ObjectType=0x8
SubNumber=2
[6200sub0]
ParameterName=Number of outputs
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[6200sub1]
ParameterName=Output 1
ObjectType=0x7
DataType=0x0005
AccessType=rww
PDOMapping=1
DefaultValue=0
)";

constexpr std::uint8_t kNode = 5;

struct Fixture {
  Fixture() : desc(canopen::eds::parse_device_description(kEds, "quirks.eds", kNode)) {
    (void)pdos.add_node(kNode, desc.od);
  }
  DeviceModel build(bool aliases = false, bool with_pdos = true) const {
    DeviceModel::Input in;
    in.network = 2;
    in.node = kNode;
    in.device_id = "pump";
    in.description = &desc;
    in.pdos = with_pdos ? &pdos : nullptr;
    in.listed = listed;
    in.aliases = aliases;
    return DeviceModel::build(in);
  }
  canopen::eds::DeviceDescription desc;
  canopen::pdo::RemotePdoTable pdos;
  // sparkplug-metrics: [2200h, "2201h:0", 2300h (a record: every sub), 2400h, 5000h (not in the EDS)]
  std::vector<SparkplugObject> listed = {{0x2200, {}}, {0x2201, 0}, {0x2300, {}}, {0x2400, {}}, {0x5000, {}}};
};

core::SdoWrite sdo_of(const std::variant<core::Command, std::string>& r);

std::vector<std::string> names(const DeviceModel& m) {
  std::vector<std::string> out;
  for (const auto& metric : m.metrics()) out.push_back(metric.name);
  return out;
}

bool noted(const DeviceModel& m, std::string_view part) {
  for (const auto& n : m.notes())
    if (n.find(part) != std::string::npos) return true;
  return false;
}

// Contract "Sparkplug B": TPDO- and RPDO-mapped objects, then the
// sparkplug-metrics objects, then Node/State and the EMCY metrics; names
// `<object>` / `<object>/<sub>`, unique per device.
TEST(SparkplugDeviceModel, MetricsArePdoMappedThenListedThenFixedWithUniqueNames) {
  Fixture f;
  const auto m = f.build();
  EXPECT_EQ(names(m), (std::vector<std::string>{
                          "Read inputs/Input-1",     // TPDO1; '/' in a name is no folder level
                          "Temp-Humidity",           // TPDO1
                          "2100h",                   // TPDO1; the EDS name is empty
                          "Write outputs/Output 1",  // RPDO1 (its dummy entry maps nothing)
                          "Speed 2200h",             // "Speed" and "speed" differ only in case (spec ch5)
                          "speed 2201h",
                          "Node/Highest sub-index supported",
                          "Node/State 2300h sub 1",  // not the fixed Node/State
                          "Clock",
                          "5000h",                   // listed, not in the EDS
                          "Node/State", "EMCY/Error Code", "EMCY/Error Register", "EMCY/Description",
                      }));
  // TPDO2 is disabled: its object is no metric. TPDO3 maps what the EDS lacks.
  EXPECT_FALSE(m.find({0x2002, 0}));
  EXPECT_TRUE(noted(m, "TPDO3")) << "the unusable PDO is said";
  EXPECT_TRUE(noted(m, "3000h sub 1")) << "the missing object is said";
  EXPECT_TRUE(noted(m, "5000h"));
  // Every object metric names its object (the index/subIndex properties).
  EXPECT_EQ(m.metrics()[0].object, (ObjectRef{0x6000, 1}));
  EXPECT_EQ(m.metrics()[3].object, (ObjectRef{0x6200, 1}));
  EXPECT_EQ(m.metrics()[9].object, (ObjectRef{0x5000, 0}));
  for (std::size_t i = 10; i < m.metrics().size(); ++i) EXPECT_FALSE(m.metrics()[i].object) << m.metrics()[i].name;
  // The PDO each object travels in.
  EXPECT_EQ(m.sources()[0].tpdo, 1);
  EXPECT_EQ(m.sources()[3].rpdo, 1);
  EXPECT_EQ(m.sources()[4].tpdo + m.sources()[4].rpdo, 0);
  EXPECT_TRUE(m.sources()[4].listed);
}

// A node without EDS: no PDO is decoded, so only its listed objects (as
// bytes, named by address) and the fixed metrics.
TEST(SparkplugDeviceModel, ANodeWithoutEdsHasListedObjectsAsBytesAndTheFixedMetrics) {
  const std::vector<SparkplugObject> listed = {{0x2000, 1}, {0x2001, {}}};
  DeviceModel::Input in;
  in.network = 1;
  in.node = 9;
  in.device_id = "net1-node9";
  in.listed = listed;
  const auto m = DeviceModel::build(in);
  EXPECT_EQ(names(m), (std::vector<std::string>{"2000h/sub 1", "2001h", "Node/State", "EMCY/Error Code",
                                                "EMCY/Error Register", "EMCY/Description"}));
  EXPECT_EQ(m.metrics()[0].datatype, DataType::Bytes);
  EXPECT_EQ(sdo_of(m.command_for({0, Value{canopen::Bytes{1}}})).type, CT::Domain);
}

// Contract: types map to the nearest Sparkplug type; Node/State String,
// EMCY/Error Code UInt16, EMCY/Error Register UInt8, EMCY/Description String.
TEST(SparkplugDeviceModel, TypesFollowTheContractsMapping) {
  Fixture f;
  const auto m = f.build();
  const std::vector<DataType> want = {DataType::UInt8,  DataType::Int16,    DataType::UInt32, DataType::UInt8,
                                      DataType::UInt16, DataType::Int64,    DataType::UInt8,  DataType::UInt8,
                                      DataType::DateTime, DataType::Bytes,  DataType::String, DataType::UInt16,
                                      DataType::UInt8,  DataType::String};
  ASSERT_EQ(m.metrics().size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(m.metrics()[i].datatype, want[i]) << m.metrics()[i].name;
  for (const auto& metric : m.metrics()) EXPECT_TRUE(std::holds_alternative<std::monostate>(metric.value));
}

// A name depends on the EDS only: the same file gives the same names, with
// or without the PDOs that map some of its objects.
TEST(SparkplugDeviceModel, NamesAreStableAcrossBuildsAndPdoChanges) {
  Fixture f;
  EXPECT_EQ(names(f.build()), names(f.build()));
  const auto without = f.build(false, false);
  EXPECT_EQ(without.metrics()[0].name, "Speed 2200h");
  EXPECT_FALSE(without.find({0x6000, 1}));
}

// Aliases (facts A.7: unique over the edge node): network << 32 | node << 24
// | index << 8 | sub; fixed metrics index 0, sub 1..4.
TEST(SparkplugDeviceModel, AliasesAreUniqueAndDerivedFromTheAddress) {
  Fixture f;
  const auto m = f.build(true);
  std::set<std::uint64_t> seen;
  for (const auto& metric : m.metrics()) {
    ASSERT_TRUE(metric.alias) << metric.name;
    EXPECT_TRUE(seen.insert(*metric.alias).second) << metric.name;
  }
  EXPECT_EQ(m.metrics()[0].alias, (std::uint64_t{2} << 32 | 5u << 24 | 0x6000u << 8 | 1u));
  EXPECT_EQ(m.metrics()[m.fixed(DeviceModel::Kind::NodeState)].alias, (std::uint64_t{2} << 32 | 5u << 24 | 1u));
  EXPECT_FALSE(seen.contains(bus_state_alias(2)));
  EXPECT_FALSE(f.build(false).metrics()[0].alias) << "no aliases unless sparkplug.aliases";
}

// Contract: device id = name, else net<N>-node<M>; spec ch4: no '+', '/',
// '#', unique under the edge node.
TEST(SparkplugDeviceIds, NameElseNetNodeAndFallbackForBadOrSharedNames) {
  const std::vector<NodeName> nodes = {
      {1, 5, ""}, {1, 6, "pump"}, {1, 7, "a/b"}, {1, 8, "x"}, {2, 8, "x"}, {2, 9, "net1-node5"}, {2, 10, "valve#1"}};
  const auto ids = device_ids(nodes);
  EXPECT_EQ(ids.ids, (std::vector<std::string>{"net1-node5", "pump", "net1-node7", "net1-node8", "net2-node8",
                                               "net2-node9", "net2-node10"}));
  EXPECT_EQ(ids.notes.size(), 5u);
}

// Contract: DDATA on every TPDO with only the metrics that changed; the
// first value always counts; the frame's timestamp.
TEST(SparkplugDeviceModel, PdoValuesGiveUpdatesOnlyWhenChanged) {
  Fixture f;
  auto m = f.build();
  const std::vector<canopen::MappedValue> first = {
      {0x6000, 1, "Input/1", canopen::Value::of_unsigned(CT::Unsigned8, 3)},
      {0x2001, 0, "Temp/Humidity", canopen::Value::of_signed(CT::Integer16, -4)},
      {0x7777, 0, "not a metric", canopen::Value::of_unsigned(CT::Unsigned8, 1)}};
  const auto u1 = m.on_values(first, 1000);
  ASSERT_EQ(u1.size(), 2u);
  EXPECT_EQ(u1[0].metric, 0u);
  EXPECT_EQ(u1[0].value, Value{std::uint64_t{3}});
  EXPECT_EQ(u1[1].value, Value{std::int64_t{-4}});
  EXPECT_EQ(u1[1].timestamp, 1000u);
  auto second = first;
  second[1].value = canopen::Value::of_signed(CT::Integer16, 7);
  const auto u2 = m.on_values(second, 2000);
  ASSERT_EQ(u2.size(), 1u) << "the unchanged input is not repeated";
  EXPECT_EQ(u2[0].metric, 1u);
  EXPECT_EQ(m.metrics()[1].value, Value{std::int64_t{7}});
  EXPECT_EQ(m.metrics()[1].timestamp, 2000u);
}

// Node/State: canopen::to_string's names; EMCY: all three every time.
TEST(SparkplugDeviceModel, StateAndEmcyUpdates) {
  Fixture f;
  auto m = f.build();
  const auto s = m.on_state(canopen::NmtState::Operational, 5);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].value, Value{std::string("operational")});
  EXPECT_TRUE(m.on_state(canopen::NmtState::Operational, 6).empty());
  canopen::EmcyEvent e;
  e.node = kNode;
  e.error_code = 0x8130;
  e.error_register = 0x11;
  e.description = "Life guard error or heartbeat error";
  for (int round = 0; round < 2; ++round) {
    const auto u = m.on_emcy(e, 9);
    ASSERT_EQ(u.size(), 3u) << "a repeated EMCY is still reported";
    EXPECT_EQ(m.metrics()[u[0].metric].name, "EMCY/Error Code");
    EXPECT_EQ(u[0].value, Value{std::uint64_t{0x8130}});
    EXPECT_EQ(u[1].value, Value{std::uint64_t{0x11}});
    EXPECT_EQ(u[2].value, Value{e.description});
  }
}

// Contract mapping of values: us -> UTF-8 String, td -> Int64 ms,
// t -> DateTime ms, os/d -> Bytes, vs that is not UTF-8 as Latin-1.
TEST(SparkplugValues, StackValuesConvertToSparkplugValues) {
  EXPECT_EQ(to_sparkplug(canopen::Value{CT::UnicodeString, std::u16string(u"Grüße")}), Value{std::string("Grüße")});
  EXPECT_EQ(to_sparkplug(canopen::Value{CT::TimeDifference, canopen::TimeOfDay{1500, 2}}),
            Value{std::int64_t{2 * 86'400'000 + 1500}});
  EXPECT_EQ(to_sparkplug(canopen::Value{CT::TimeOfDay, canopen::TimeOfDay{0, 1}}),
            Value{std::uint64_t{441'763'200'000 + 86'400'000}});
  EXPECT_EQ(to_sparkplug(canopen::Value::of_bytes(CT::OctetString, canopen::Bytes{1, 2})), (Value{canopen::Bytes{1, 2}}));
  EXPECT_EQ(to_sparkplug(canopen::Value::of_string("\xE4")), Value{std::string("ä")});
  EXPECT_EQ(to_sparkplug(canopen::Value::of_real32(1.5F)), Value{1.5F});
}

core::RpdoWrite rpdo_of(const std::variant<core::Command, std::string>& r) {
  if (const auto* c = std::get_if<core::Command>(&r))
    if (const auto* w = std::get_if<core::RpdoWrite>(c)) return *w;
  ADD_FAILURE() << "not an RpdoWrite: " << (std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : "");
  return {};
}
core::SdoWrite sdo_of(const std::variant<core::Command, std::string>& r) {
  if (const auto* c = std::get_if<core::Command>(&r))
    if (const auto* w = std::get_if<core::SdoWrite>(c)) return *w;
  ADD_FAILURE() << "not an SdoWrite: " << (std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : "");
  return {};
}
std::string refusal(const std::variant<core::Command, std::string>& r) {
  if (const auto* s = std::get_if<std::string>(&r)) return *s;
  ADD_FAILURE() << "not refused";
  return {};
}

// Contract: a DCMD on an RPDO-mapped object goes out as that RPDO; the body
// is what the core reads (core::typed_rpdo_values accepts it, as for REST).
TEST(SparkplugDeviceModel, DcmdToAnRpdoObjectIsThatRpdosWriteInTheRestFormat) {
  Fixture f;
  const auto m = f.build();
  const auto w = rpdo_of(m.command_for({3, Value{std::uint64_t{200}}}));
  EXPECT_EQ(w.node, kNode);
  EXPECT_EQ(w.number, 1);
  const auto cfg = f.pdos.resolve(kNode, {canopen::pdo::Direction::Receive, 1});
  ASSERT_TRUE(cfg);
  std::string error;
  const auto body = core::typed_rpdo_values(w, *cfg, f.desc.od, "node 5 RPDO1", error);
  ASSERT_TRUE(body) << error << " in " << test::rpdo_json(w);
  ASSERT_EQ(body->values.size(), 1u);
  EXPECT_EQ(body->values[0].index, 0x6200);
  EXPECT_EQ(body->values[0].sub, 1);
  EXPECT_EQ(body->values[0].value, canopen::Value::of_unsigned(CT::Unsigned8, 200));
}

// Contract: any other object by SDO download, typed from the EDS; values
// that do not fit (type range, EDS limits) are refused before anything is sent.
TEST(SparkplugDeviceModel, DcmdToAnotherObjectIsAnSdoWriteTypedFromTheEds) {
  Fixture f;
  const auto m = f.build();
  const auto w = sdo_of(m.command_for({4, Value{std::uint64_t{500}}}));
  EXPECT_EQ(w.node, kNode);
  EXPECT_EQ(w.index, 0x2200);
  EXPECT_EQ(w.sub, 0);
  EXPECT_EQ(w.type, CT::Unsigned16);
  EXPECT_EQ(test::json_of(w.value), boost::json::value(500));
  EXPECT_NE(refusal(m.command_for({4, Value{std::uint64_t{1001}}})).find("1000"), std::string::npos)
      << "the EDS HighLimit";
  EXPECT_NE(refusal(m.command_for({4, Value{std::uint64_t{70000}}})).find("above 65535"), std::string::npos);
  // td from Int64 ms; t from DateTime ms as the contract's RFC 3339 text.
  EXPECT_EQ(test::json_of(sdo_of(m.command_for({5, Value{std::int64_t{90'000'000}}})).value), boost::json::value(90'000'000));
  EXPECT_EQ(test::json_of(sdo_of(m.command_for({8, Value{std::uint64_t{1'795'000'000'000}}})).value),
            boost::json::value("2026-11-18T11:06:40.000Z"));  // date -u -d @1795000000
  EXPECT_NE(refusal(m.command_for({8, Value{std::uint64_t{1000}}})).find("TIME_OF_DAY"), std::string::npos)
      << "before 1984 does not fit";
  // Not in the EDS: written as bytes.
  const auto raw = sdo_of(m.command_for({9, Value{canopen::Bytes{0xAB, 0x01}}}));
  EXPECT_EQ(raw.type, CT::Domain);
  EXPECT_EQ(test::json_of(raw.value), boost::json::value("ab01"));
}

// One DCMD: the values for one RPDO become one write (one frame), SDO
// objects one write each, refusals one reason each.
TEST(SparkplugDeviceModel, WritesOfOneCommandGroupTheRpdoValues) {
  Fixture f;
  const auto m = f.build();
  const std::vector<WriteCommand::Item> items = {{3, Value{std::uint64_t{1}}},
                                                 {4, Value{std::uint64_t{5}}},
                                                 {3, Value{std::uint64_t{2}}},
                                                 {m.fixed(DeviceModel::Kind::NodeState), Value{std::string("x")}}};
  const auto plan = m.writes_for(items);
  ASSERT_EQ(plan.writes.size(), 2u);
  EXPECT_EQ(plan.refused.size(), 1u);
  const auto& rpdo = std::get<core::RpdoWrite>(plan.writes[0].command);
  EXPECT_EQ(test::rpdo_json(rpdo), boost::json::parse(R"({"values":[{"index":25088,"subIndex":1,"value":2}]})"))
      << "the object given twice: its last value";
  EXPECT_EQ(plan.writes[0].objects, (std::vector<ObjectRef>{{0x6200, 1}}));
  EXPECT_TRUE(std::holds_alternative<core::SdoWrite>(plan.writes[1].command));
}

TEST(SparkplugDeviceModel, ReportedReadOnlyAndUnknownMetricsAreRefused) {
  Fixture f;
  const auto m = f.build();
  EXPECT_NE(refusal(m.command_for({m.fixed(DeviceModel::Kind::NodeState), Value{std::string("stopped")}}))
                .find("cannot be written"),
            std::string::npos);
  EXPECT_NE(refusal(m.command_for({m.fixed(DeviceModel::Kind::EmcyErrorCode), Value{std::uint64_t{0}}}))
                .find("cannot be written"),
            std::string::npos);
  EXPECT_NE(refusal(m.command_for({1, Value{std::int64_t{3}}})).find("read-only"), std::string::npos);
  EXPECT_FALSE(refusal(m.command_for({99, Value{true}})).empty());
  EXPECT_NE(refusal(m.command_for({4, Value{}})).find("null"), std::string::npos);
}

// A rebirth after a rebuild shows the values known before.
TEST(SparkplugDeviceModel, CarriedValuesSurviveARebuild) {
  Fixture f;
  auto old = f.build();
  (void)old.on_state(canopen::NmtState::Stopped, 3);
  (void)old.on_value({0x2200, 0}, canopen::Value::of_unsigned(CT::Unsigned16, 9), 4);
  auto fresh = f.build();
  fresh.carry_values(old);
  EXPECT_EQ(fresh.metrics()[fresh.fixed(DeviceModel::Kind::NodeState)].value, Value{std::string("stopped")});
  EXPECT_EQ(fresh.metrics()[*fresh.find({0x2200, 0})].value, Value{std::uint64_t{9}});
  EXPECT_EQ(fresh.metrics()[*fresh.find({0x2200, 0})].timestamp, 4u);
}

// Every public vendor file (../shared/eds-corpus): a model with every PDO
// in use and every object listed builds without a crash; names unique
// (ignoring case), non-empty, one folder level per record sub; types mapped.
TEST(SparkplugDeviceModelCorpus, EveryVendorFileGivesUniqueNamedTypedMetrics) {
  const auto corpus = std::filesystem::path(CANOPEN_SOURCE_DIR) / ".." / "shared" / "eds-corpus";
  if (!std::filesystem::is_directory(corpus)) GTEST_SKIP() << corpus << " not found";
  std::size_t models = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(corpus)) {
    auto ext = entry.path().extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!entry.is_regular_file() || (ext != ".eds" && ext != ".dcf")) continue;
    canopen::eds::DeviceDescription desc;
    try {
      desc = canopen::eds::load_device_description(entry.path(), kNode);
    } catch (const canopen::eds::EdsError&) {
      continue;  // refused files are the EDS reader's test
    }
    canopen::pdo::RemotePdoTable pdos;
    (void)pdos.add_node(kNode, desc.od);
    std::vector<SparkplugObject> all;
    for (const auto& [index, obj] : desc.od.objects()) all.push_back({index, {}});
    DeviceModel::Input in;
    in.network = 1;
    in.node = kNode;
    in.device_id = "d";
    in.description = &desc;
    in.pdos = &pdos;
    in.listed = all;
    in.aliases = true;
    const auto m = DeviceModel::build(in);
    ++models;
    std::set<std::string> seen;
    std::set<std::uint64_t> aliases;
    for (std::size_t i = 0; i < m.metrics().size(); ++i) {
      const auto& metric = m.metrics()[i];
      std::string folded = metric.name;
      for (char& c : folded) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      EXPECT_FALSE(metric.name.empty()) << entry.path();
      EXPECT_TRUE(seen.insert(folded).second) << entry.path() << ": " << metric.name;
      EXPECT_TRUE(aliases.insert(*metric.alias).second) << entry.path() << ": " << metric.name;
      EXPECT_NE(metric.datatype, DataType::Unknown) << entry.path() << ": " << metric.name;
      EXPECT_TRUE(canopen::is_utf8(metric.name)) << entry.path();
      if (metric.object) {
        const auto* obj = desc.od.find(metric.object->index);
        ASSERT_NE(obj, nullptr);
        const bool var = obj->code == canopen::od::ObjectCode::Var || obj->code == canopen::od::ObjectCode::Domain;
        EXPECT_EQ(std::count(metric.name.begin(), metric.name.end(), '/'), var ? 0 : 1)
            << entry.path() << ": " << metric.name;
      }
    }
    EXPECT_EQ(m.metrics().size(), seen.size());
  }
  EXPECT_GE(models, 200u);
}

}  // namespace
}  // namespace gateway::sparkplug
