#include <gtest/gtest.h>

#include <vector>

#include "canopen/clock.hpp"
#include "canopen/pdo/receiver.hpp"
#include "unit/stack/pdo/pdo_test_util.hpp"

namespace canopen::pdo {
namespace {

using test::add_comm;
using test::add_map;
using test::add_var;

// Producer node 10h: SAM-MPDO on TPDO1 (190h), scanner list 1FA0h with
// 6401h sub 1..4 (block of 4) and 2003h sub 2.
od::ObjectDictionary sam_producer(bool with_scanner = true) {
  od::ObjectDictionary d;
  od::Object ai = od::make_array(0x6401, "Read analogue input 16-bit", DataType::Integer16, od::Access::ReadOnly, 4);
  ai.subs[2].name = "Analogue input 2";
  d.insert(std::move(ai));
  add_var(d, 0x2000, "Not scanned", DataType::Unsigned32);
  add_comm(d, Direction::Transmit, 1, 0x190);
  add_map(d, Direction::Transmit, 1, {}, 0xFE);
  if (with_scanner) {
    od::Object scan = od::make_array(0x1FA0, "Object scanner list", DataType::Unsigned32, od::Access::ReadWrite, 2);
    scan.subs[1].value = Value::of_unsigned(DataType::Unsigned32, 0x04640101);  // block 4, 6401h sub 1
    scan.subs[2].value = Value::of_unsigned(DataType::Unsigned32, 0x01200302);  // 2003h sub 2
    d.insert(std::move(scan));
  }
  return d;
}

struct Fixture {
  FakeClock clock;
  std::vector<PdoEvent> events;
  PdoReceiver rx{[](const can::Frame&) {}, [this](PdoEvent e) { events.push_back(std::move(e)); }};
};

TEST(Mpdo, Mpdo_SamWithScannerList) {
  Fixture t;
  ASSERT_TRUE(t.rx.add_node(0x10, sam_producer()).empty());
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("190#1001640234120000"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  const PdoEvent& e = t.events[0];
  EXPECT_EQ(e.node, 0x10);
  EXPECT_EQ(e.number, 1);
  EXPECT_FALSE(e.error) << *e.error;
  ASSERT_TRUE(e.mpdo);
  EXPECT_FALSE(e.mpdo->destination_mode);
  EXPECT_EQ(e.mpdo->address, 0x10);
  EXPECT_EQ(e.mpdo->index, 0x6401);
  EXPECT_EQ(e.mpdo->sub, 2);
  EXPECT_FALSE(e.mpdo->local_index);
  ASSERT_EQ(e.values.size(), 1U);
  EXPECT_EQ(e.values[0].name, "Analogue input 2");
  EXPECT_EQ(e.values[0].value, Value::of_signed(DataType::Integer16, 0x1234));
}

TEST(Mpdo, Mpdo_7_5_2_39_SamObjectNotInScannerListReported) {
  Fixture t;
  (void)t.rx.add_node(0x10, sam_producer());
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("190#1000200001000000"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  EXPECT_TRUE(t.events[0].error);
  EXPECT_TRUE(t.events[0].values.empty());
  // Without a scanner list any object of the producer is accepted.
  (void)t.rx.add_node(0x10, sam_producer(false));
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("190#1000200001000000"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 2U);
  EXPECT_FALSE(t.events[1].error);
  EXPECT_EQ(t.events[1].values[0].value, Value::of_unsigned(DataType::Unsigned32, 1));
}

TEST(Mpdo, Mpdo_7_5_2_40_SamWithDispatcherList) {
  Fixture t;
  (void)t.rx.add_node(0x10, sam_producer());
  od::ObjectDictionary own;
  od::Object disp = od::make_array(0x1FD0, "Object dispatching list", DataType::Unsigned64, od::Access::ReadWrite, 1);
  // block 4 | producer 10h | 6401h sub 1 -> local 2100h sub 11h
  disp.subs[1].value = Value::of_unsigned(DataType::Unsigned64, 0x0410640101210011ULL);
  own.insert(std::move(disp));
  t.rx.set_dispatcher_list(own);
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("190#100164039CFF0000"), t.clock.now()));
  ASSERT_EQ(t.events.size(), 1U);
  const PdoEvent& e = t.events[0];
  ASSERT_TRUE(e.mpdo);
  EXPECT_EQ(e.mpdo->local_index, 0x2100);
  EXPECT_EQ(e.mpdo->local_sub, 0x13);
  EXPECT_EQ(e.values[0].value, Value::of_signed(DataType::Integer16, -100));
}

TEST(Mpdo, Mpdo_7_2_3_4_1_DamDecodedWithDestinationDictionary) {
  Fixture t;
  od::ObjectDictionary producer;
  add_comm(producer, Direction::Transmit, 1, 0x1A0);
  add_map(producer, Direction::Transmit, 1, {}, 0xFF);
  (void)t.rx.add_node(0x20, producer);
  od::ObjectDictionary consumer;
  add_var(consumer, 0x6040, "Controlword", DataType::Unsigned16);
  (void)t.rx.add_node(3, consumer);
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("1A0#834060000F000000"), t.clock.now()));
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("1A0#8022200001020304"), t.clock.now()));  // to all, unknown object
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("1A0#0322200001020304"), t.clock.now()));  // SAM frame on a DAM PDO
  ASSERT_TRUE(t.rx.on_frame(*can::parse_frame("1A0#83406000"), t.clock.now()));          // MPDOs are 8 bytes
  ASSERT_EQ(t.events.size(), 4U);
  EXPECT_EQ(t.events[0].node, 0x20);
  ASSERT_TRUE(t.events[0].mpdo);
  EXPECT_TRUE(t.events[0].mpdo->destination_mode);
  EXPECT_EQ(t.events[0].mpdo->address, 3);
  ASSERT_EQ(t.events[0].values.size(), 1U);
  EXPECT_EQ(t.events[0].values[0].name, "Controlword");
  EXPECT_EQ(t.events[0].values[0].value, Value::of_unsigned(DataType::Unsigned16, 0x000F));
  EXPECT_FALSE(t.events[1].error);
  EXPECT_EQ(t.events[1].mpdo->address, 0);
  EXPECT_EQ(t.events[1].values[0].value, Value::of_bytes(DataType::Domain, Bytes{1, 2, 3, 4}));
  EXPECT_TRUE(t.events[2].error);
  EXPECT_TRUE(t.events[3].error);
  EXPECT_TRUE(t.events[3].values.empty());
}

}  // namespace
}  // namespace canopen::pdo
