#include "canopen/pdo/receiver.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "canopen/clock.hpp"
#include "unit/stack/pdo/pdo_test_util.hpp"

namespace canopen::pdo {
namespace {

using test::add_comm;
using test::add_map;
using test::add_var;

struct Fixture {
  FakeClock clock;
  std::vector<can::Frame> sent;
  std::vector<PdoEvent> events;
  PdoReceiver rx{[this](const can::Frame& f) { sent.push_back(f); }, [this](PdoEvent e) { events.push_back(std::move(e)); }};
};

od::ObjectDictionary simple_node(std::uint8_t node, std::uint8_t type = 255, std::uint32_t cob_flags = 0) {
  od::ObjectDictionary d;
  add_var(d, 0x6000, "Digital inputs", DataType::Unsigned8);
  add_var(d, 0x6401, "Analogue input", DataType::Integer16);
  add_comm(d, Direction::Transmit, 1, (0x180U + node) | cob_flags, type);
  add_map(d, Direction::Transmit, 1, {0x60000008, 0x64010010});
  return d;
}

TEST(PdoReceiver, Pdo_7_2_2_5_1_TpdoDecodedWithNamesAndTypes) {
  Fixture t;
  EXPECT_TRUE(t.rx.add_node(3, simple_node(3)).empty());
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("183#5AFEFF"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  const PdoEvent& e = t.events[0];
  EXPECT_EQ(e.node, 3);
  EXPECT_EQ(e.number, 1);
  EXPECT_EQ(e.cob_id, 0x183U);
  EXPECT_EQ(e.raw, (Bytes{0x5A, 0xFE, 0xFF}));
  EXPECT_FALSE(e.error);
  ASSERT_EQ(e.values.size(), 2U);
  EXPECT_EQ(e.values[0].index, 0x6000);
  EXPECT_EQ(e.values[0].name, "Digital inputs");
  EXPECT_EQ(e.values[0].value, Value::of_unsigned(DataType::Unsigned8, 0x5A));
  EXPECT_EQ(e.values[1].value, Value::of_signed(DataType::Integer16, -2));
}

TEST(PdoReceiver, Pdo_LengthMismatchReported) {
  Fixture t;
  (void)t.rx.add_node(3, simple_node(3));
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("183#5AFE"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  EXPECT_TRUE(t.events[0].error);
  EXPECT_TRUE(t.events[0].values.empty());
  EXPECT_EQ(t.events[0].raw, (Bytes{0x5A, 0xFE}));
}

TEST(PdoReceiver, Pdo_7_5_2_36_LongerPayloadUsesMappedBytesAndIsReported) {
  Fixture t;
  (void)t.rx.add_node(3, simple_node(3));
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("183#5AFEFF0102"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  EXPECT_TRUE(t.events[0].error);
  ASSERT_EQ(t.events[0].values.size(), 2U);
  EXPECT_EQ(t.events[0].values[1].value, Value::of_signed(DataType::Integer16, -2));
}

TEST(PdoReceiver, Pdo_UnclaimedPdoGivesNodeZero) {
  Fixture t;
  (void)t.rx.add_node(3, simple_node(3));
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("284#0102"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  EXPECT_EQ(t.events[0].node, 0);
  EXPECT_EQ(t.events[0].number, 0);
  EXPECT_EQ(t.events[0].cob_id, 0x284U);
  EXPECT_EQ(t.events[0].raw, (Bytes{1, 2}));
  // Not PDOs: SYNC, EMCY, SDO, heartbeat, RTR.
  for (const char* s : {"080#", "083#0000000000000000", "603#4000100000000000", "703#05", "183#R3"})
    EXPECT_FALSE(t.rx.on_frame(*can::parse_frame(s), t.clock.now())) << s;
  EXPECT_EQ(t.events.size(), 1U);
}

TEST(PdoReceiver, Pdo_7_2_2_2_SyncTpdoOutsideWindowDropped) {
  Fixture t;
  (void)t.rx.add_node(3, simple_node(3, 1));
  (void)t.rx.add_node(4, simple_node(4, 255));
  const TimePoint sync = t.clock.now();
  t.rx.set_sync_window([sync](TimePoint now) { return now - sync <= std::chrono::milliseconds(2); });
  t.clock.advance(std::chrono::milliseconds(1));
  EXPECT_TRUE(t.rx.on_frame(*can::parse_frame("183#010000"), t.clock.now()));
  t.clock.advance(std::chrono::milliseconds(5));
  EXPECT_TRUE(t.rx.on_frame(*can::parse_frame("183#020000"), t.clock.now()));  // late: dropped
  EXPECT_TRUE(t.rx.on_frame(*can::parse_frame("184#030000"), t.clock.now()));  // event-driven: kept
  ASSERT_EQ(t.events.size(), 2U);
  EXPECT_EQ(t.events[0].raw[0], 1);
  EXPECT_EQ(t.events[1].node, 4);
  EXPECT_EQ(t.rx.dropped_late(), 1U);
}

TEST(PdoReceiver, Pdo_7_2_2_5_2_RtrOnlyWhenCobIdAllowsIt) {
  Fixture t;
  (void)t.rx.add_node(3, simple_node(3));
  (void)t.rx.add_node(4, simple_node(4, 255, 0x40000000U));
  (void)t.rx.add_node(5, simple_node(5, 255, 0x80000000U));
  EXPECT_TRUE(t.rx.request(3, 1, t.clock.now()));
  EXPECT_FALSE(t.rx.request(4, 1, t.clock.now()));  // bit 30: no RTR
  EXPECT_FALSE(t.rx.request(5, 1, t.clock.now()));  // bit 31: invalid
  EXPECT_FALSE(t.rx.request(3, 2, t.clock.now()));  // no such TPDO
  ASSERT_EQ(t.sent.size(), 1U);
  EXPECT_EQ(test::text(t.sent[0]), "183#R3");
}

TEST(PdoReceiver, Pdo_InvalidTpdoNotClaimedAndDuplicateCobIdReported) {
  Fixture t;
  (void)t.rx.add_node(5, simple_node(5, 255, 0x80000000U));
  EXPECT_TRUE(t.rx.on_frame(*can::parse_frame("185#010000"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  EXPECT_EQ(t.events[0].node, 0);  // the PDO does not exist on node 5
  (void)t.rx.add_node(3, simple_node(3));
  auto problems = t.rx.add_node(9, simple_node(3));  // node 9 claims 183h too
  ASSERT_EQ(problems.size(), 1U);
  EXPECT_NE(problems[0].find("node 3"), std::string::npos) << problems[0];
}

TEST(PdoReceiver, Pdo_ExtendedCobId) {
  Fixture t;
  od::ObjectDictionary d = simple_node(3);
  add_comm(d, Direction::Transmit, 1, 0x20012345U);
  (void)t.rx.add_node(3, d);
  can::Frame f = can::Frame::extended_id(0x12345, std::initializer_list<std::uint8_t>{0x01, 0x02, 0x03});
  EXPECT_TRUE(t.rx.on_frame(f, t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  EXPECT_EQ(t.events[0].node, 3);
  EXPECT_EQ(t.events[0].values[1].value, Value::of_signed(DataType::Integer16, 0x0302));
}

}  // namespace
}  // namespace canopen::pdo
