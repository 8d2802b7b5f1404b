// Issue 11: PDO decoding follows the device. The master (canopen::Network)
// against a Device over the in-memory bus with the fake clock: PDOs the
// gateway remaps by SDO (CiA 301 7.5.2.35-7.5.2.39) are decoded and produced
// with the new configuration, and the configuration the device really has
// can be read at boot-up so it wins over the EDS.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "network_rig.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kNode = test::NetworkRig::kNode;

Bytes u32(std::uint32_t v) {
  return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16),
          static_cast<std::uint8_t>(v >> 24)};
}

// The gateway's network and a CiA 402 drive whose dictionary starts as its
// EDS; `device_od` is what the device really holds.
struct Rig : test::NetworkRig {
  Rig() : NetworkRig("deploy/eds/cia402-drive.eds") {}
  void start_operational() {
    power_on();
    run_for(10ms);
    net.send_nmt(NmtCommand::Start, kNode);
    run_for(10ms);
    ASSERT_EQ(device->state(), NmtState::Operational);
  }
  std::vector<PdoEvent> pdos() const { return bodies<PdoEvent>(); }
  std::vector<BootConfigEvent> boot_steps() const { return bodies<BootConfigEvent>(); }
  // The device sends `f` as if it came from its TPDO producer.
  void inject(const can::Frame& f) {
    dev_ep->send(f);
    run_for(1ms);
  }
};

// 7.5.2.39 (TPDO mapping) with the sequence of 7.5.2.38/7.5.2.39: disable,
// sub 0 = 0, entries, sub 0 = n, enable - each step through the gateway.
TEST(PdoFollow, PdoFollow_7_5_2_39_TpdoRemappedBySdoIsDecodedWithTheNewMapping) {
  Rig rig;
  ASSERT_TRUE(rig.net.add_node(kNode, rig.eds.od).empty());
  rig.start_operational();
  ASSERT_EQ(rig.net.pdo().tpdo(kNode, 1)->entries.size(), 1U);  // EDS: 6041h Statusword

  ASSERT_FALSE(rig.write(0x1800, 1, u32(0x80000185)));  // 1) disable (COB-ID bit 31)
  EXPECT_FALSE(rig.net.pdo().tpdo(kNode, 1)->comm.cob_id.valid());
  // A disabled PDO is not decoded: the same CAN-ID now belongs to nobody.
  rig.inject(can::Frame::standard(0x185, {0x37, 0x06}));
  ASSERT_FALSE(rig.pdos().empty());
  EXPECT_EQ(rig.pdos().back().node, 0);
  EXPECT_TRUE(rig.pdos().back().values.empty());

  ASSERT_FALSE(rig.write(0x1A00, 0, {0x00}));                // 2) no objects mapped
  ASSERT_FALSE(rig.write(0x1A00, 1, u32(0x60640020)));       // 3) Position actual value (i32)
  ASSERT_FALSE(rig.write(0x1A00, 2, u32(0x60410010)));       //    Statusword (u16)
  EXPECT_FALSE(rig.net.pdo().tpdo(kNode, 1)->comm.cob_id.valid()) << "still disabled mid-sequence";
  ASSERT_FALSE(rig.write(0x1A00, 0, {0x02}));                // 4) two objects
  ASSERT_FALSE(rig.write(0x1800, 1, u32(0x40000185)));       // 5) enable
  const pdo::PdoConfig* cfg = rig.net.pdo().tpdo(kNode, 1);
  ASSERT_NE(cfg, nullptr);
  EXPECT_TRUE(cfg->comm.cob_id.valid());
  ASSERT_EQ(cfg->entries.size(), 2U);
  EXPECT_EQ(rig.net.pdo_config().find(kNode, {pdo::Direction::Transmit, 1})->source, pdo::ConfigSource::Written);
  ASSERT_TRUE(rig.device->pdo_errors().empty());

  // The device sends its remapped TPDO1; the gateway decodes the new layout.
  const std::size_t before = rig.pdos().size();
  ASSERT_FALSE(rig.device->set(0x6064, 0, Value::of_signed(DataType::Integer32, -123456), rig.clock.now()));
  rig.run_for(5ms);
  const auto pdos = rig.pdos();
  ASSERT_GT(pdos.size(), before);
  const PdoEvent& ev = pdos.back();
  EXPECT_EQ(ev.node, kNode);
  EXPECT_EQ(ev.number, 1);
  EXPECT_FALSE(ev.error) << *ev.error;
  EXPECT_EQ(ev.raw.size(), 6U);
  ASSERT_EQ(ev.values.size(), 2U);
  EXPECT_EQ(ev.values[0].index, 0x6064);
  EXPECT_EQ(ev.values[0].name, "Position actual value");
  EXPECT_EQ(ev.values[0].value, Value::of_signed(DataType::Integer32, -123456));
  EXPECT_EQ(ev.values[1].index, 0x6041);
  EXPECT_EQ(ev.values[1].name, "Statusword");
  EXPECT_EQ(ev.values[1].value.type, DataType::Unsigned16);
}

// A write the device refuses (SDO abort) changes nothing in the gateway.
TEST(PdoFollow, PdoFollow_7_2_4_3_17_AbortedWriteChangesNothing) {
  Rig rig;
  ASSERT_TRUE(rig.net.add_node(kNode, rig.eds.od).empty());
  rig.device_od.find(0x1A00, 0)->access = od::Access::ReadOnly;  // static mapping on this device
  rig.start_operational();
  EXPECT_TRUE(rig.write(0x1A00, 0, {0x00}));  // refused
  ASSERT_EQ(rig.net.pdo().tpdo(kNode, 1)->entries.size(), 1U);
  EXPECT_EQ(rig.net.pdo_config().find(kNode, {pdo::Direction::Transmit, 1})->source, pdo::ConfigSource::Eds);
}

// A device that lets a mapping be changed while the PDO is valid, to an
// object its EDS does not describe: the gateway cannot type the data, so
// it reports the frames as that node's TPDO with the raw bytes and why,
// never values decoded with a wrong layout.
TEST(PdoFollow, PdoFollow_7_5_2_39_MappingTheEdsCannotTypeIsReportedRawNotDecoded) {
  Rig rig;
  ASSERT_TRUE(rig.net.add_node(kNode, rig.eds.od).empty());
  rig.start_operational();
  ASSERT_FALSE(rig.write(0x1A00, 1, u32(0x20FF0020)));  // no 20FFh in the EDS
  rig.inject(can::Frame::standard(0x185, {1, 2, 3, 4}));
  const auto pdos = rig.pdos();
  ASSERT_FALSE(pdos.empty());
  const PdoEvent& ev = pdos.back();
  EXPECT_EQ(ev.node, kNode);
  EXPECT_EQ(ev.number, 1);
  EXPECT_TRUE(ev.values.empty());
  ASSERT_TRUE(ev.error);
  EXPECT_NE(ev.error->find("20FFh"), std::string::npos) << *ev.error;
  EXPECT_EQ(ev.raw, (Bytes{1, 2, 3, 4}));
}

// 7.5.2.38 (RPDO mapping): after the gateway remapped the device's RPDO1,
// process data written to it goes out with the new layout and lands in the
// device's objects.
TEST(PdoFollow, PdoFollow_7_5_2_38_RpdoWriteAfterRemapUsesTheNewMapping) {
  Rig rig;
  ASSERT_TRUE(rig.net.add_node(kNode, rig.eds.od).empty());
  rig.start_operational();
  ASSERT_FALSE(rig.write(0x1400, 1, u32(0x80000205)));
  ASSERT_FALSE(rig.write(0x1600, 0, {0x00}));
  ASSERT_FALSE(rig.write(0x1600, 1, u32(0x60600008)));  // Modes of operation (i8)
  ASSERT_FALSE(rig.write(0x1600, 2, u32(0x607A0020)));  // Target position (i32)
  ASSERT_FALSE(rig.write(0x1600, 0, {0x02}));
  // While disabled the gateway does not produce it.
  EXPECT_EQ(rig.net.rpdo().payload(kNode, 1), nullptr);
  ASSERT_FALSE(rig.write(0x1400, 1, u32(0x00000205)));
  ASSERT_NE(rig.net.rpdo().payload(kNode, 1), nullptr);
  EXPECT_EQ(rig.net.rpdo().payload(kNode, 1)->size(), 5U);

  const MappedValue values[] = {{0x607A, 0, {}, Value::of_signed(DataType::Integer32, 250000)},
                                {0x6060, 0, {}, Value::of_signed(DataType::Integer8, 1)}};
  ASSERT_FALSE(rig.net.rpdo().set_values(kNode, 1, values, rig.clock.now()));
  rig.run_for(5ms);
  EXPECT_EQ(rig.device_od.get(0x607A, 0).value(), Value::of_signed(DataType::Integer32, 250000));
  EXPECT_EQ(rig.device_od.get(0x6060, 0).value(), Value::of_signed(DataType::Integer8, 1));
  // The old mapping is gone: Controlword is no longer in RPDO1.
  EXPECT_EQ(rig.net.rpdo().set_value(kNode, 1, 0x6040, 0, Value::of_unsigned(DataType::Unsigned16, 15),
                                     rig.clock.now()),
            make_error_code(SdoAbort::NotMappable));
}

// CiA 302-2 boot-up with read-pdo-config: the device was remapped (and its
// parameters stored) by someone else; its EDS says otherwise. The gateway
// reads 1800h-1803h/1A00h-1A03h and 1400h-1403h/1600h-1603h before the NMT
// start, so the first TPDO is already decoded with the device's mapping.
// A PDO the device does not have (abort 06020000h) keeps the EDS's, is
// reported, and does not stop the boot.
TEST(PdoFollow, PdoFollow_7_2_2_ReadPdoConfigAtBootDecodesWithTheDevicesMapping) {
  Rig rig;
  ASSERT_TRUE(rig.net.add_node(kNode, rig.eds.od).empty());
  // The device's truth: TPDO1 maps Velocity actual value + Statusword, on 1C5h.
  ASSERT_FALSE(rig.device_od.set(0x1800, 1, Value::of_unsigned(DataType::Unsigned32, 0x1C5)));
  ASSERT_FALSE(rig.device_od.set(0x1A00, 0, Value::of_unsigned(DataType::Unsigned8, 2)));
  ASSERT_FALSE(rig.device_od.set(0x1A00, 1, Value::of_unsigned(DataType::Unsigned32, 0x606C0020)));
  ASSERT_FALSE(rig.device_od.set(0x1A00, 2, Value::of_unsigned(DataType::Unsigned32, 0x60410010)));
  ASSERT_TRUE(rig.device_od.erase(0x1803));  // this device has only three TPDOs
  master::NodeBootConfig boot;
  boot.start = true;
  ASSERT_TRUE(rig.net.configure_boot(kNode, boot, true));

  rig.power_on();
  rig.run_for(500ms);
  ASSERT_EQ(rig.device->state(), NmtState::Operational);
  const auto steps = rig.boot_steps();
  ASSERT_GE(steps.size(), 3U);
  EXPECT_EQ(steps[steps.size() - 2].step, BootConfigEvent::Step::Start);
  EXPECT_EQ(steps.back().step, BootConfigEvent::Step::Done);
  EXPECT_NE(steps.back().detail.find("7 of 8 PDOs read from the device"), std::string::npos) << steps.back().detail;
  EXPECT_NE(steps.back().detail.find("TPDO4: 1803h sub 1"), std::string::npos) << steps.back().detail;

  const auto* t1 = rig.net.pdo_config().find(kNode, {pdo::Direction::Transmit, 1});
  EXPECT_EQ(t1->source, pdo::ConfigSource::Device);
  const auto* t4 = rig.net.pdo_config().find(kNode, {pdo::Direction::Transmit, 4});
  EXPECT_EQ(t4->source, pdo::ConfigSource::Eds);
  EXPECT_NE(t4->read_error.find("1803h sub 1"), std::string::npos) << t4->read_error;

  // Every TPDO1 the device sent since its start was claimed and decoded
  // with its own mapping (none went out before the read ended).
  for (const auto& p : rig.pdos())
    if (p.cob_id == 0x1C5U) {
      EXPECT_EQ(p.values.size(), 2U);
    }
  ASSERT_FALSE(rig.device->set(0x606C, 0, Value::of_signed(DataType::Integer32, 1500), rig.clock.now()));
  rig.run_for(5ms);
  const auto pdos = rig.pdos();
  ASSERT_FALSE(pdos.empty());
  const PdoEvent& ev = pdos.back();
  EXPECT_EQ(ev.node, kNode);
  EXPECT_EQ(ev.number, 1);
  EXPECT_EQ(ev.cob_id, 0x1C5U);
  ASSERT_EQ(ev.values.size(), 2U);
  EXPECT_EQ(ev.values[0].name, "Velocity actual value");
  EXPECT_EQ(ev.values[0].value, Value::of_signed(DataType::Integer32, 1500));
  EXPECT_EQ(ev.values[1].name, "Statusword");
}

// The same read on demand; a node that stops answering ends it early with
// the timeout instead of waiting once per object.
TEST(PdoFollow, PdoFollow_7_2_4_3_ReadOnDemandAndTimeout) {
  Rig rig;
  ASSERT_TRUE(rig.net.add_node(kNode, rig.eds.od).empty());
  ASSERT_FALSE(rig.device_od.set(0x1600, 1, Value::of_unsigned(DataType::Unsigned32, 0x60400010)));
  ASSERT_FALSE(rig.device_od.set(0x1401, 1, Value::of_unsigned(DataType::Unsigned32, 0x80000305)));
  rig.power_on();
  rig.run_for(10ms);
  std::optional<pdo::PdoReadReport> report;
  ASSERT_FALSE(rig.net.read_pdo_config(kNode, [&](const pdo::PdoReadReport& r) { report = r; }, rig.clock.now()));
  rig.run_for(200ms);
  ASSERT_TRUE(report);
  EXPECT_FALSE(report->stopped);
  EXPECT_EQ(report->read_count(), 8U);
  EXPECT_EQ(rig.net.rpdo().payload(kNode, 2), nullptr) << "RPDO2 is disabled on the device";

  report.reset();
  ASSERT_FALSE(rig.net.read_pdo_config(kNode, [&](const pdo::PdoReadReport& r) { report = r; }, rig.clock.now()));
  rig.dev_ep->set_link_up(false);
  rig.run_for(3s);
  ASSERT_TRUE(report);
  EXPECT_EQ(report->stopped, make_error_code(SdoAbort::Timeout));
  EXPECT_EQ(report->read_count(), 0U);
  EXPECT_EQ(rig.net.pdo_config().find(kNode, {pdo::Direction::Transmit, 1})->source, pdo::ConfigSource::Device)
      << "what an earlier read found stays";
  EXPECT_EQ(rig.net.read_pdo_config(99, {}, rig.clock.now()), make_error_code(SdoAbort::NoSuchObject));
}

}  // namespace
}  // namespace canopen
