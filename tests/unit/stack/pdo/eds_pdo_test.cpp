// TPDOs and RPDOs of the shipped CiA 401 / CiA 402 device descriptions.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "canopen/clock.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/pdo/receiver.hpp"
#include "canopen/pdo/transmitter.hpp"

namespace canopen::pdo {
namespace {

std::filesystem::path source(const std::string& rel) { return std::filesystem::path(CANOPEN_SOURCE_DIR) / rel; }

struct Fixture {
  FakeClock clock;
  std::vector<PdoEvent> events;
  PdoReceiver rx{[](const can::Frame&) {}, [this](PdoEvent e) { events.push_back(std::move(e)); }};

  const PdoEvent& feed(const char* text) {
    EXPECT_TRUE(rx.on_frame(*can::parse_frame(text), clock.now())) << text;
    return events.back();
  }
};

TEST(PdoEds, Pdo_Cia401TpdosDecodedByNameAndType) {
  Fixture t;
  auto dev = eds::load_device_description(source("deploy/eds/cia401-io-module.eds"), 2);
  EXPECT_TRUE(t.rx.add_node(2, std::move(dev.od)).empty());

  const PdoEvent& e1 = t.feed("182#A5");
  EXPECT_EQ(e1.node, 2);
  EXPECT_EQ(e1.number, 1);
  ASSERT_EQ(e1.values.size(), 1U);
  EXPECT_EQ(e1.values[0].index, 0x6000);
  EXPECT_EQ(e1.values[0].sub, 1);
  EXPECT_EQ(e1.values[0].name, "Read input 1h to 8h");
  EXPECT_EQ(e1.values[0].value, Value::of_unsigned(DataType::Unsigned8, 0xA5));

  const PdoEvent& e2 = t.feed("282#0100FFFF0080FF7F");
  EXPECT_EQ(e2.number, 2);
  ASSERT_EQ(e2.values.size(), 4U);
  EXPECT_EQ(e2.values[0].name, "Analogue input 1");
  EXPECT_EQ(e2.values[3].name, "Analogue input 4");
  EXPECT_EQ(e2.values[0].value, Value::of_signed(DataType::Integer16, 1));
  EXPECT_EQ(e2.values[1].value, Value::of_signed(DataType::Integer16, -1));
  EXPECT_EQ(e2.values[2].value, Value::of_signed(DataType::Integer16, -32768));
  EXPECT_EQ(e2.values[3].value, Value::of_signed(DataType::Integer16, 32767));

  // TPDO3's COB-ID has bit 31 set (not valid): nobody claims 382h.
  EXPECT_EQ(t.feed("382#00").node, 0);
}

TEST(PdoEds, Pdo_Cia402TpdosDecodedByNameAndType) {
  Fixture t;
  auto dev = eds::load_device_description(source("deploy/eds/cia402-drive.eds"), 5);
  EXPECT_TRUE(t.rx.add_node(5, std::move(dev.od)).empty());
  const PdoEvent& e2 = t.feed("285#3716FD");
  ASSERT_EQ(e2.values.size(), 2U);
  EXPECT_EQ(e2.values[0].name, "Statusword");
  EXPECT_EQ(e2.values[0].value, Value::of_unsigned(DataType::Unsigned16, 0x1637));
  EXPECT_EQ(e2.values[1].name, "Modes of operation display");
  EXPECT_EQ(e2.values[1].value, Value::of_signed(DataType::Integer8, -3));
  const PdoEvent& e3 = t.feed("385#3706A0860100");
  ASSERT_EQ(e3.values.size(), 2U);
  EXPECT_EQ(e3.values[1].name, "Position actual value");
  EXPECT_EQ(e3.values[1].value, Value::of_signed(DataType::Integer32, 100000));
  ASSERT_NE(t.rx.tpdo(5, 3), nullptr);
  EXPECT_EQ(t.rx.tpdo(5, 3)->comm.transmission_type, 1);  // synchronous
}

TEST(PdoEds, Pdo_Cia402DcfParameterValuesOverrideMapping) {
  Fixture t;
  auto dev = eds::load_device_description(source("tests/support/eds/cia402-drive-node5.dcf"));
  EXPECT_TRUE(t.rx.add_node(5, std::move(dev.od)).empty());
  const PdoEvent& e = t.feed("285#3706F6FF");
  ASSERT_EQ(e.values.size(), 2U);
  EXPECT_EQ(e.values[1].index, 0x6077);
  EXPECT_EQ(e.values[1].name, "Torque actual value");
  EXPECT_EQ(e.values[1].value, Value::of_signed(DataType::Integer16, -10));
  ASSERT_NE(t.rx.tpdo(5, 4), nullptr);
  EXPECT_EQ(t.rx.tpdo(5, 4)->comm.transmission_type, 0xFF);
  EXPECT_EQ(t.rx.tpdo(5, 4)->comm.event_timer, 10);
}

TEST(PdoEds, Pdo_Cia402RpdoWrittenByGateway) {
  FakeClock clock;
  std::vector<std::string> sent;
  PdoTransmitter tx{[&](const can::Frame& f) { sent.push_back(can::to_string(f)); }};
  auto dev = eds::load_device_description(source("deploy/eds/cia402-drive.eds"), 5);
  ASSERT_EQ(*tx.add_rpdo(5, 2, dev.od, clock.now()), 3U);
  const std::vector<MappedValue> v{{0x6040, 0, {}, Value::of_unsigned(DataType::Unsigned16, 0x000F)},
                                   {0x6060, 0, {}, Value::of_signed(DataType::Integer8, 1)}};
  ASSERT_FALSE(tx.set_values(5, 2, v, clock.now()));
  ASSERT_EQ(*tx.add_rpdo(5, 3, dev.od, clock.now()), 6U);
  ASSERT_FALSE(tx.set_value(5, 3, 0x607A, 0, Value::of_signed(DataType::Integer32, -1000), clock.now()));
  EXPECT_EQ(sent, (std::vector<std::string>{"305#0F0001", "405#000018FCFFFF"}));
}

}  // namespace
}  // namespace canopen::pdo
