// The example EDS/DCF files shipped in deploy/eds and the DCF test variant.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "eds_test_util.hpp"

namespace canopen::eds::test {
namespace {

using od::Access;
using od::ObjectCode;

const od::SubEntry& entry(const DeviceDescription& d, std::uint16_t index, std::uint8_t sub) {
  const auto* e = d.od.find(index, sub);
  if (e == nullptr) {
    ADD_FAILURE() << "no entry " << std::hex << index << " sub " << unsigned{sub};
    static const od::SubEntry none;
    return none;
  }
  return *e;
}

std::uint64_t value_u(const DeviceDescription& d, std::uint16_t index, std::uint8_t sub) {
  return u(entry(d, index, sub).value);
}

// ---- cia401-io-module.eds ----------------------------------------------------

TEST(EdsIoModule, LoadsWithoutWarnings) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_FALSE(d.is_dcf);
  EXPECT_EQ(d.node_id, 5);
  EXPECT_FALSE(d.commissioning.has_value());
  EXPECT_EQ(d.file.file_name, "cia401-io-module.eds");
  EXPECT_EQ(d.file.eds_version, "4.0");
  EXPECT_EQ(d.file.file_version, "1");
  EXPECT_EQ(d.file.created_by, "canopen-gateway project");
  EXPECT_EQ(d.device.vendor_number, 0x5A1u);
  EXPECT_EQ(d.device.product_number, 0x8822u);
  EXPECT_EQ(d.device.revision_number, 0x00010003u);
  EXPECT_EQ(d.device.order_code, "IO-8822-A");
  EXPECT_EQ(d.device.baud_rates_kbit, (std::vector<unsigned>{10, 20, 50, 125, 250, 500, 1000}));
  EXPECT_EQ(d.device.nr_of_rx_pdo, 4);
  EXPECT_EQ(d.device.nr_of_tx_pdo, 4);
  EXPECT_EQ(d.device.granularity, 8);
  EXPECT_TRUE(d.device.simple_boot_up_slave);
  EXPECT_FALSE(d.device.simple_boot_up_master);
  EXPECT_TRUE(d.device.lss_supported);
  EXPECT_EQ(d.dummy_usage, (std::vector<std::uint16_t>{2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(d.comments.size(), 3u);
  EXPECT_EQ(d.mandatory_objects, (std::vector<std::uint16_t>{0x1000, 0x1001, 0x1018}));
  EXPECT_EQ(d.optional_objects.size(), 49u);  // with the CiA 302-3 program objects 1F50h/1F51h/1F56h/1F57h
  EXPECT_EQ(d.manufacturer_objects.size(), 6u);
  EXPECT_EQ(d.od.objects().size(), 3u + 49u + 6u);
}

TEST(EdsIoModule, CommunicationObjects) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  const auto& dt = entry(d, 0x1000, 0);
  EXPECT_EQ(dt.type, DataType::Unsigned32);
  EXPECT_EQ(dt.access, Access::ReadOnly);
  EXPECT_EQ(u(dt.value), 0x000F0191u);
  EXPECT_EQ(dt.default_value, dt.value);
  EXPECT_TRUE(entry(d, 0x1001, 0).pdo_mappable);
  EXPECT_EQ(entry(d, 0x1008, 0).access, Access::Const);
  EXPECT_EQ(entry(d, 0x1008, 0).value, Value::of_string("IO-8822"));
  EXPECT_EQ(value_u(d, 0x1017, 0), 1000u);
  EXPECT_EQ(entry(d, 0x1017, 0).type, DataType::Unsigned16);

  const auto* id = d.od.find(0x1018);
  ASSERT_NE(id, nullptr);
  EXPECT_EQ(id->code, ObjectCode::Record);
  EXPECT_EQ(id->name, "Identity object");
  EXPECT_EQ(id->subs.size(), 5u);
  EXPECT_EQ(value_u(d, 0x1018, 0), 4u);
  EXPECT_EQ(value_u(d, 0x1018, 1), 0x5A1u);
  EXPECT_EQ(value_u(d, 0x1018, 2), 0x8822u);
  EXPECT_EQ(entry(d, 0x1018, 1).name, "Vendor-ID");

  // 1003h: sub 0 writable with 0 only (LowLimit=HighLimit=0).
  const auto& errors = entry(d, 0x1003, 0);
  EXPECT_EQ(errors.access, Access::ReadWrite);
  EXPECT_EQ(errors.high, Value::of_unsigned(DataType::Unsigned8, 0));
  EXPECT_EQ(d.od.find(0x1003)->code, ObjectCode::Array);
  EXPECT_EQ(d.od.find(0x1003)->subs.size(), 5u);
}

TEST(EdsIoModule, NodeIdResolvedForNode5) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  EXPECT_EQ(value_u(d, 0x1014, 0), 0x85u);
  EXPECT_EQ(u(*entry(d, 0x1014, 0).default_value), 0x85u);
  EXPECT_EQ(value_u(d, 0x1200, 1), 0x605u);
  EXPECT_EQ(value_u(d, 0x1200, 2), 0x585u);
  EXPECT_EQ(value_u(d, 0x1400, 1), 0x205u);
  EXPECT_EQ(value_u(d, 0x1401, 1), 0x305u);
  EXPECT_EQ(value_u(d, 0x1402, 1), 0x80000405u);
  EXPECT_EQ(value_u(d, 0x1403, 1), 0x80000505u);
  EXPECT_EQ(value_u(d, 0x1800, 1), 0x185u);
  EXPECT_EQ(value_u(d, 0x1801, 1), 0x285u);
  EXPECT_EQ(value_u(d, 0x1802, 1), 0xC0000385u);
  EXPECT_EQ(value_u(d, 0x1803, 1), 0xC0000485u);
}

TEST(EdsIoModule, NodeIdResolvedForNode127) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 127);
  EXPECT_EQ(d.node_id, 127);
  EXPECT_EQ(value_u(d, 0x1014, 0), 0xFFu);
  EXPECT_EQ(value_u(d, 0x1200, 1), 0x67Fu);
  EXPECT_EQ(value_u(d, 0x1200, 2), 0x5FFu);
  EXPECT_EQ(value_u(d, 0x1400, 1), 0x27Fu);
  EXPECT_EQ(value_u(d, 0x1403, 1), 0x8000057Fu);
  EXPECT_EQ(value_u(d, 0x1800, 1), 0x1FFu);
  EXPECT_EQ(value_u(d, 0x1803, 1), 0xC00004FFu);
}

TEST(EdsIoModule, WithoutNodeIdNamesTheFirstNodeIdValue) {
  const auto path = deploy_eds("cia401-io-module.eds");
  const auto text = read_text(path);
  try {
    (void)load_device_description(path);
    FAIL() << "expected an EdsError";
  } catch (const EdsError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_EQ(e.line(), line_of(text, "DefaultValue=$NODEID+0x80", "[1014]"));
    EXPECT_NE(e.reason().find("$NODEID"), std::string::npos) << e.what();
    EXPECT_NE(e.reason().find("no node-ID"), std::string::npos) << e.what();
  }
}

TEST(EdsIoModule, PdoParameters) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  // RPDO communication records skip sub 4 (reserved).
  const auto* rpdo1 = d.od.find(0x1400);
  ASSERT_NE(rpdo1, nullptr);
  EXPECT_EQ(rpdo1->code, ObjectCode::Record);
  EXPECT_EQ(rpdo1->subs.size(), 5u);
  EXPECT_FALSE(rpdo1->subs.contains(4));
  EXPECT_EQ(value_u(d, 0x1400, 0), 5u);
  EXPECT_EQ(value_u(d, 0x1400, 2), 0xFFu);
  EXPECT_EQ(value_u(d, 0x1801, 3), 50u);
  EXPECT_EQ(value_u(d, 0x1801, 5), 100u);

  EXPECT_EQ(value_u(d, 0x1600, 0), 1u);
  EXPECT_EQ(value_u(d, 0x1600, 1), 0x62000108u);
  EXPECT_EQ(value_u(d, 0x1601, 0), 2u);
  EXPECT_EQ(value_u(d, 0x1601, 2), 0x64110210u);
  EXPECT_EQ(value_u(d, 0x1602, 0), 0u);
  EXPECT_EQ(value_u(d, 0x1A00, 1), 0x60000108u);
  EXPECT_EQ(value_u(d, 0x1A01, 0), 4u);
  for (std::uint8_t s = 1; s <= 4; ++s) {
    EXPECT_EQ(value_u(d, 0x1A01, s), 0x64010010u + (std::uint64_t{s} << 8)) << unsigned{s};
  }
  EXPECT_EQ(entry(d, 0x1A01, 0).access, Access::ReadWrite);
  EXPECT_EQ(entry(d, 0x1A01, 0).high, Value::of_unsigned(DataType::Unsigned8, 4));
}

TEST(EdsIoModule, ApplicationObjects) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  const auto& di = entry(d, 0x6000, 1);
  EXPECT_EQ(di.type, DataType::Unsigned8);
  EXPECT_EQ(di.access, Access::ReadOnly);
  EXPECT_TRUE(di.pdo_mappable);
  const auto& dout = entry(d, 0x6200, 1);
  EXPECT_EQ(dout.access, Access::ReadWriteWrite);
  EXPECT_TRUE(dout.pdo_mappable);
  EXPECT_EQ(value_u(d, 0x6206, 1), 0xFFu);
  EXPECT_EQ(entry(d, 0x6423, 0).value, Value::of_bool(false));
  EXPECT_EQ(i(entry(d, 0x6424, 4).value), 32767);
  EXPECT_EQ(i(entry(d, 0x6425, 1).value), -32768);
  EXPECT_EQ(entry(d, 0x6425, 1).type, DataType::Integer32);
}

TEST(EdsIoModule, CompactObjectsExpand) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  const auto* ai = d.od.find(0x6401);
  ASSERT_NE(ai, nullptr);
  EXPECT_EQ(ai->code, ObjectCode::Array);
  EXPECT_EQ(ai->subs.size(), 5u);
  const auto& sub0 = entry(d, 0x6401, 0);
  EXPECT_EQ(sub0.type, DataType::Unsigned8);
  EXPECT_EQ(sub0.access, Access::ReadOnly);
  EXPECT_FALSE(sub0.pdo_mappable);
  EXPECT_EQ(u(sub0.value), 4u);
  for (std::uint8_t s = 1; s <= 4; ++s) {
    const auto& e = entry(d, 0x6401, s);
    EXPECT_EQ(e.type, DataType::Integer16);
    EXPECT_EQ(e.access, Access::ReadOnly);
    EXPECT_TRUE(e.pdo_mappable);
    EXPECT_EQ(e.name, "Analogue input " + std::to_string(s));
    EXPECT_EQ(e.value, Value::of_signed(DataType::Integer16, 0));
  }
  EXPECT_EQ(entry(d, 0x6411, 2).access, Access::ReadWriteWrite);
  EXPECT_EQ(entry(d, 0x6411, 2).name, "Analogue output 2");
  EXPECT_EQ(entry(d, 0x1010, 2).name, "Save communication parameters");
  EXPECT_EQ(value_u(d, 0x1010, 4), 1u);
  // No [1016Name]: ParameterName followed by the sub-index.
  EXPECT_EQ(entry(d, 0x1016, 2).name, "Consumer heartbeat time2");
  EXPECT_EQ(d.object_links.at(0x6401), (std::vector<std::uint16_t>{0x6423, 0x6424, 0x6425}));
}

TEST(EdsIoModule, ManufacturerObjects) {
  const auto d = load_device_description(deploy_eds("cia401-io-module.eds"), 5);
  const auto* fw = d.od.find(0x2000);
  ASSERT_NE(fw, nullptr);
  EXPECT_EQ(fw->code, ObjectCode::Domain);
  EXPECT_EQ(entry(d, 0x2000, 0).type, DataType::Domain);
  EXPECT_EQ(entry(d, 0x2000, 0).access, Access::WriteOnly);
  EXPECT_EQ(entry(d, 0x2000, 0).value, Value::of_bytes(DataType::Domain, {}));
  EXPECT_EQ(entry(d, 0x2001, 0).value, Value::of_string("Cabinet A, slot 3"));

  const auto& filter = entry(d, 0x2002, 0);
  EXPECT_EQ(filter.low, Value::of_unsigned(DataType::Unsigned16, 0));
  EXPECT_EQ(filter.high, Value::of_unsigned(DataType::Unsigned16, 1000));
  EXPECT_EQ(u(filter.value), 10u);

  EXPECT_EQ(d.od.find(0x2003)->code, ObjectCode::Record);
  const auto& temp = entry(d, 0x2003, 2);
  EXPECT_EQ(temp.type, DataType::Integer16);
  EXPECT_EQ(temp.low, Value::of_signed(DataType::Integer16, -400));
  EXPECT_EQ(temp.high, Value::of_signed(DataType::Integer16, 1250));
  EXPECT_EQ(i(temp.value), 250);
  EXPECT_EQ(entry(d, 0x2003, 3).value, Value::of_real32(24.0f));
  EXPECT_EQ(entry(d, 0x2004, 0).value,
            Value::of_bytes(DataType::OctetString, {0x00, 0x00, 0x80, 0x3F, 0x00, 0x00, 0x00, 0x00}));
}

// ---- cia402-drive.eds ----------------------------------------------------------

TEST(EdsDrive, LoadsWithoutWarnings) {
  const auto d = load_device_description(deploy_eds("cia402-drive.eds"), 5);
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_FALSE(d.is_dcf);
  EXPECT_EQ(value_u(d, 0x1000, 0), 0x00020192u);
  EXPECT_EQ(d.device.product_name, "SD-402 Servo Drive");
  EXPECT_EQ(d.device.baud_rates_kbit, (std::vector<unsigned>{125, 250, 500, 1000}));
}

TEST(EdsDrive, DriveObjectsTypesAndLimits) {
  const auto d = load_device_description(deploy_eds("cia402-drive.eds"), 5);
  const auto& cw = entry(d, 0x6040, 0);
  EXPECT_EQ(cw.type, DataType::Unsigned16);
  EXPECT_EQ(cw.access, Access::ReadWriteWrite);
  EXPECT_TRUE(cw.pdo_mappable);
  const auto& sw = entry(d, 0x6041, 0);
  EXPECT_EQ(sw.type, DataType::Unsigned16);
  EXPECT_EQ(sw.access, Access::ReadOnly);
  EXPECT_TRUE(sw.pdo_mappable);

  const auto& mode = entry(d, 0x6060, 0);
  EXPECT_EQ(mode.type, DataType::Integer8);
  EXPECT_EQ(mode.low, Value::of_signed(DataType::Integer8, 0));
  EXPECT_EQ(mode.high, Value::of_signed(DataType::Integer8, 10));
  EXPECT_EQ(entry(d, 0x6061, 0).type, DataType::Integer8);

  EXPECT_EQ(entry(d, 0x6064, 0).type, DataType::Integer32);
  EXPECT_EQ(entry(d, 0x6064, 0).access, Access::ReadOnly);
  EXPECT_EQ(entry(d, 0x606C, 0).type, DataType::Integer32);
  const auto& target = entry(d, 0x607A, 0);
  EXPECT_EQ(target.type, DataType::Integer32);
  EXPECT_EQ(target.low, Value::of_signed(DataType::Integer32, -1000000000));
  EXPECT_EQ(target.high, Value::of_signed(DataType::Integer32, 1000000000));
  const auto& pv = entry(d, 0x6081, 0);
  EXPECT_EQ(pv.type, DataType::Unsigned32);
  EXPECT_EQ(u(pv.value), 10000u);
  EXPECT_EQ(pv.high, Value::of_unsigned(DataType::Unsigned32, 100000));
  EXPECT_EQ(u(*entry(d, 0x6083, 0).low), 1u);
  EXPECT_EQ(u(*entry(d, 0x6084, 0).high), 1000000u);
  EXPECT_EQ(i(*entry(d, 0x60FF, 0).low), -100000);
  EXPECT_EQ(i(*entry(d, 0x6098, 0).low), -128);
  EXPECT_EQ(value_u(d, 0x6502, 0), 0x3ADu);

  const auto* limits = d.od.find(0x607D);
  ASSERT_NE(limits, nullptr);
  EXPECT_EQ(limits->subs.size(), 3u);
  EXPECT_EQ(entry(d, 0x607D, 1).name, "Min position limit");
  EXPECT_EQ(entry(d, 0x607D, 2).type, DataType::Integer32);
}

TEST(EdsDrive, ErrorHistoryAndIdentity) {
  const auto d = load_device_description(deploy_eds("cia402-drive.eds"), 5);
  const auto* history = d.od.find(0x1003);
  ASSERT_NE(history, nullptr);
  EXPECT_EQ(history->code, ObjectCode::Array);
  EXPECT_EQ(history->subs.size(), 9u);
  EXPECT_EQ(entry(d, 0x1003, 0).access, Access::ReadWrite);
  EXPECT_EQ(entry(d, 0x1003, 8).type, DataType::Unsigned32);
  EXPECT_EQ(entry(d, 0x1003, 8).access, Access::ReadOnly);
  EXPECT_EQ(d.od.find(0x1016)->code, ObjectCode::Array);
  EXPECT_EQ(entry(d, 0x1016, 1).access, Access::ReadWrite);
  EXPECT_EQ(d.od.find(0x1018)->code, ObjectCode::Record);
  EXPECT_EQ(value_u(d, 0x1018, 2), 0x402u);
}

TEST(EdsDrive, DefaultPdoMappings) {
  const auto d = load_device_description(deploy_eds("cia402-drive.eds"), 5);
  EXPECT_EQ(value_u(d, 0x1600, 1), 0x60400010u);
  EXPECT_EQ(value_u(d, 0x1601, 2), 0x60600008u);
  EXPECT_EQ(value_u(d, 0x1602, 2), 0x607A0020u);
  EXPECT_EQ(value_u(d, 0x1603, 2), 0x60FF0020u);
  EXPECT_EQ(value_u(d, 0x1A00, 1), 0x60410010u);
  EXPECT_EQ(value_u(d, 0x1A01, 2), 0x60610008u);
  EXPECT_EQ(value_u(d, 0x1A02, 2), 0x60640020u);
  EXPECT_EQ(value_u(d, 0x1A03, 2), 0x606C0020u);
  EXPECT_EQ(value_u(d, 0x1802, 2), 1u);
  for (std::uint16_t n = 0; n < 4; ++n) {
    EXPECT_EQ(value_u(d, static_cast<std::uint16_t>(0x1400 + n), 1), 0x205u + 0x100u * n);
    EXPECT_EQ(value_u(d, static_cast<std::uint16_t>(0x1800 + n), 1), 0x185u + 0x100u * n);
  }
}

// ---- cia402-drive-node5.dcf ----------------------------------------------------

TEST(EdsDcf, TakesNodeIdFromDeviceComissioning) {
  const auto d = load_device_description(test_data("cia402-drive-node5.dcf"));
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  EXPECT_TRUE(d.is_dcf);
  EXPECT_EQ(d.node_id, 5);
  ASSERT_TRUE(d.commissioning.has_value());
  EXPECT_EQ(d.commissioning->node_id, 5);
  EXPECT_EQ(d.commissioning->node_name, "Axis X");
  EXPECT_EQ(d.commissioning->baud_rate_kbit, 500);
  EXPECT_EQ(d.commissioning->net_number, 1u);
  EXPECT_EQ(d.commissioning->network_name, "Machine line 1");
  EXPECT_FALSE(d.commissioning->canopen_manager);
  EXPECT_EQ(d.commissioning->lss_serial_number, 0x12345u);
  EXPECT_EQ(d.file.last_eds, "cia402-drive.eds");
  EXPECT_EQ(value_u(d, 0x1014, 0), 0x85u);  // DefaultValue $NODEID+0x80 with the DCF's node-ID
}

TEST(EdsDcf, ParameterValueWinsOverDefaultValue) {
  const auto d = load_device_description(test_data("cia402-drive-node5.dcf"));
  const auto& hb = entry(d, 0x1017, 0);
  EXPECT_EQ(u(hb.value), 100u);
  EXPECT_EQ(u(*hb.default_value), 0u);
  EXPECT_EQ(value_u(d, 0x6081, 0), 20000u);
  EXPECT_EQ(u(*entry(d, 0x6081, 0).default_value), 10000u);
  EXPECT_EQ(value_u(d, 0x6083, 0), 50000u);
  EXPECT_EQ(i(entry(d, 0x6060, 0).value), 1);
  EXPECT_EQ(value_u(d, 0x1800, 1), 0x185u);
  EXPECT_EQ(value_u(d, 0x1800, 5), 50u);
  EXPECT_EQ(value_u(d, 0x1803, 2), 0xFFu);
  EXPECT_EQ(value_u(d, 0x1A01, 2), 0x60770010u);
  EXPECT_EQ(u(*entry(d, 0x1A01, 2).default_value), 0x60610008u);
  EXPECT_EQ(value_u(d, 0x1016, 1), 0x007F01F4u);
  EXPECT_EQ(value_u(d, 0x1018, 4), 0x12345u);
  EXPECT_EQ(value_u(d, 0x2000, 0), 3200u);
  // [607DValue] sets the compact sub-objects' values; DefaultValue stays.
  EXPECT_EQ(i(entry(d, 0x607D, 1).value), -500000);
  EXPECT_EQ(i(entry(d, 0x607D, 2).value), 500000);
  EXPECT_EQ(i(*entry(d, 0x607D, 2).default_value), 0);
  // Untouched entries keep their default.
  EXPECT_EQ(value_u(d, 0x1A00, 1), 0x60410010u);
}

TEST(EdsDcf, NodeIdArgumentOverridesWithWarning) {
  const auto path = test_data("cia402-drive-node5.dcf");
  const auto d = load_device_description(path, 7);
  EXPECT_EQ(d.node_id, 7);
  EXPECT_EQ(d.commissioning->node_id, 5);
  EXPECT_EQ(value_u(d, 0x1014, 0), 0x87u);
  EXPECT_EQ(value_u(d, 0x1800, 1), 0x185u);  // a ParameterValue is taken as written
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_EQ(d.warnings[0], path.string() + ":" + std::to_string(line_of(read_text(path), "NodeID=5")) +
                               ": node-ID 7 given overrides NodeID=5");
}

TEST(EdsDcf, DescribesTheSameObjectsAsTheEds) {
  const auto eds = load_device_description(deploy_eds("cia402-drive.eds"), 5);
  const auto dcf = load_device_description(test_data("cia402-drive-node5.dcf"));
  ASSERT_EQ(eds.od.objects().size(), dcf.od.objects().size());
  for (const auto& [index, obj] : eds.od.objects()) {
    const auto* other = dcf.od.find(index);
    ASSERT_NE(other, nullptr) << std::hex << index;
    ASSERT_EQ(obj.subs.size(), other->subs.size()) << std::hex << index;
    for (const auto& [sub, e] : obj.subs) {
      const auto& o = other->subs.at(sub);
      EXPECT_EQ(e.type, o.type) << std::hex << index << " " << unsigned{sub};
      EXPECT_EQ(e.access, o.access) << std::hex << index << " " << unsigned{sub};
      EXPECT_EQ(e.default_value, o.default_value) << std::hex << index << " " << unsigned{sub};
    }
  }
}

TEST(EdsFiles, MissingFileIsAnErrorWithoutLine) {
  const auto path = test_data("no-such-file.eds");
  try {
    (void)load_device_description(path, 5);
    FAIL() << "expected an EdsError";
  } catch (const EdsError& e) {
    EXPECT_EQ(e.line(), 0u);
    EXPECT_EQ(std::string(e.what()), path.string() + ": cannot open the file");
  }
}

// ---- the public vendor corpus (../shared/eds-corpus beside the checkout) -----

// 219 public EDS/DCF files from ~35 vendors and projects. Every file whose
// meaning is unambiguous loads; the few refused are refused for a reason
// that would need a guess (two different values for one key, a value its
// type cannot hold, template prose as a default), and say file:line.
TEST(EdsCorpus, AcceptsEveryUnambiguousVendorFile) {
  const auto corpus = source_dir() / ".." / "shared" / "eds-corpus";
  if (!std::filesystem::is_directory(corpus)) GTEST_SKIP() << corpus << " not found";
  std::size_t accepted = 0;
  std::vector<std::string> refused;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(corpus)) {
    const auto ext = entry.path().extension().string();
    if (!entry.is_regular_file() || (ext != ".eds" && ext != ".dcf" && ext != ".EDS" && ext != ".DCF")) continue;
    try {
      (void)load_device_description(entry.path(), 5);
      ++accepted;
    } catch (const EdsError& e) {
      EXPECT_GT(e.line(), 0u) << e.what();
      const bool needs_a_guess = e.reason().find("repeated with a different value") != std::string::npos ||
                                 e.reason().find("is not a valid") != std::string::npos;
      EXPECT_TRUE(needs_a_guess) << "refused for a reason that is not ambiguity: " << e.what();
      refused.push_back(e.what());
    }
  }
  EXPECT_GE(accepted + refused.size(), 219u);
  // 214 of 219 today (209 before issue 28 left unreadable values out instead
  // of refusing the file; python-canopen loads 86%); the refusals are listed
  // so a change in either direction is seen: four keys repeated with another
  // value outside the object lists (two names for one object) and one
  // DataType that is a comment.
  EXPECT_GE(accepted, 214u);
  EXPECT_LE(refused.size(), 5u) << [&] {
    std::string all;
    for (const auto& r : refused) all += r + "\n";
    return all;
  }();
}

}  // namespace
}  // namespace canopen::eds::test
