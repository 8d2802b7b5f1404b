// The CiA 302-3 program download objects of the simulated devices
// (gateway/sim/device_objects), on the demo I/O module's dictionary through
// SDO-style access (ObjectDictionary::read/write, as the SDO server calls it).
#include "sim/device_objects.hpp"

#include <gtest/gtest.h>

#include <string_view>

#include "canopen/device.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/sdo/abort.hpp"

namespace canopen::sim {
namespace {

constexpr std::uint8_t kNode = 5;

od::ObjectDictionary io_module() {
  auto od = eds::load_device_description(std::string(CANOPEN_SOURCE_DIR) + "/deploy/eds/cia401-io-module.eds", kNode).od;
  EXPECT_TRUE(install_program_objects(od));
  return od;
}

std::uint64_t state(const od::ObjectDictionary& od) { return od.read(0x1F51, 1).value().at(0); }
std::uint32_t identification(const od::ObjectDictionary& od) {
  return static_cast<std::uint32_t>(std::get<std::uint64_t>(decode(DataType::Unsigned32, od.read(0x1F56, 1).value())->data));
}
std::error_code control(od::ObjectDictionary& od, std::uint8_t cmd) { return od.write(0x1F51, 1, Bytes{cmd}); }

TEST(ProgramObjects, Identification_IsTheCrc32OfTheImage_StandardCheckValue) {
  constexpr std::string_view kCheck = "123456789";  // CRC-32 (IEEE 802.3) check value CBF43926h
  EXPECT_EQ(program_identification(Bytes(kCheck.begin(), kCheck.end())), 0xCBF43926U);
  EXPECT_EQ(program_identification({}), 0U);
}

TEST(ProgramObjects, CiA302_3_ControlStates_StartNeedsAProgram_ClearAndDownloadNeedItStopped) {
  auto od = io_module();
  EXPECT_EQ(state(od), 3U) << "no program";
  EXPECT_EQ(identification(od), 0U);
  EXPECT_EQ(control(od, 1), SdoAbort::CannotStoreDeviceState) << "start without a program";
  EXPECT_EQ(control(od, 2), SdoAbort::CannotStoreDeviceState) << "reset without a program";
  const Bytes image{0x10, 0x20, 0x30};
  ASSERT_FALSE(od.write(0x1F50, 1, image));
  EXPECT_EQ(state(od), 0U) << "downloaded, stopped";
  EXPECT_EQ(identification(od), program_identification(image));
  ASSERT_FALSE(control(od, 1));
  EXPECT_EQ(state(od), 1U) << "running";
  EXPECT_EQ(od.write(0x1F50, 1, Bytes{1}), SdoAbort::CannotStoreDeviceState) << "download into a running program";
  EXPECT_EQ(control(od, 3), SdoAbort::CannotStoreDeviceState) << "clear a running program";
  ASSERT_FALSE(control(od, 2));
  EXPECT_EQ(state(od), 1U) << "reset: running again";
  ASSERT_FALSE(control(od, 0));
  EXPECT_EQ(state(od), 0U);
  ASSERT_FALSE(control(od, 3));
  EXPECT_EQ(state(od), 3U);
  EXPECT_EQ(identification(od), 0U) << "cleared";
  EXPECT_EQ(control(od, 4), SdoAbort::InvalidValue);
  EXPECT_EQ(od.read(0x1F57, 1).value(), (Bytes{0, 0, 0, 0})) << "flash status: no error";
}

TEST(ProgramObjects, ImageAbove4MiB_AbortsOutOfMemory_NothingStored) {
  auto od = io_module();
  EXPECT_EQ(od.write(0x1F50, 1, Bytes(kMaxProgramSize + 1)), SdoAbort::OutOfMemory);
  EXPECT_EQ(state(od), 3U);
  EXPECT_FALSE(od.write(0x1F50, 1, Bytes(kMaxProgramSize, 0x5A)));
  EXPECT_EQ(state(od), 0U);
}

// The program is not a parameter: NMT reset node (7.3.2.2.1) keeps it.
TEST(ProgramObjects, ResetNodeKeepsTheProgramAndItsState) {
  auto od = io_module();
  DeviceConfig cfg;
  cfg.node_id = kNode;
  Device device(od, cfg, [](const can::Frame&) {});
  FakeClock clock;
  device.start(clock.now());
  const Bytes image{9, 8, 7};
  ASSERT_FALSE(od.write(0x1F50, 1, image));
  ASSERT_FALSE(control(od, 1));
  device.command(NmtCommand::ResetNode, clock.now());
  EXPECT_EQ(identification(od), program_identification(image));
  EXPECT_EQ(state(od), 1U);
}

TEST(ProgramObjects, DictionaryWithoutProgramControl_NothingInstalled) {
  auto od = eds::load_device_description(std::string(CANOPEN_SOURCE_DIR) + "/deploy/eds/cia402-drive.eds", kNode).od;
  EXPECT_FALSE(install_program_objects(od));
}

}  // namespace
}  // namespace canopen::sim
