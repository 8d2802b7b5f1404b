#include "canopen/pdo/transmitter.hpp"
#include "canopen/pdo/receiver.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "canopen/clock.hpp"
#include "unit/stack/pdo/pdo_test_util.hpp"

namespace canopen::pdo {
namespace {

using namespace std::chrono_literals;
using test::add_comm;
using test::add_map;
using test::add_var;

// Remote node 5 with RPDO1: U16 output word at 6300h; COB-ID 205h.
od::ObjectDictionary drive(std::uint8_t type, std::uint16_t inhibit = 0, std::uint16_t timer = 0,
                           std::uint8_t sync_start = 0, std::uint32_t cob_flags = 0) {
  od::ObjectDictionary d;
  add_var(d, 0x6300, "Output word", DataType::Unsigned16);
  add_var(d, 0x6301, "Output flag", DataType::Boolean);
  add_comm(d, Direction::Receive, 1, 0x205U | cob_flags, type, inhibit, timer, sync_start);
  add_map(d, Direction::Receive, 1, {0x63000010});
  return d;
}

struct Fixture {
  FakeClock clock;
  std::vector<std::string> sent;
  PdoTransmitter tx{[this](const can::Frame& f) { sent.push_back(test::text(f)); }};

  void set(std::uint16_t v) {
    ASSERT_FALSE(tx.set_value(5, 1, 0x6300, 0, Value::of_unsigned(DataType::Unsigned16, v), clock.now()));
  }
  // Runs on_time at every deadline up to now + d, as a driver would.
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    while (tx.next_deadline() <= end) {
      clock.advance_to(tx.next_deadline());
      tx.on_time(clock.now());
    }
    clock.advance_to(end);
  }
};

TEST(PdoTransmitter, Pdo_7_2_2_2_AcyclicSyncType0SentOnNextSyncAfterChange) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(0), t.clock.now()));
  t.tx.on_sync(std::nullopt, t.clock.now());
  EXPECT_TRUE(t.sent.empty());  // nothing changed
  t.set(0x1234);
  EXPECT_TRUE(t.sent.empty());  // waits for SYNC
  t.tx.on_sync(std::nullopt, t.clock.now());
  t.tx.on_sync(std::nullopt, t.clock.now());
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#3412"}));
}

TEST(PdoTransmitter, Pdo_7_2_2_CyclicSyncType3SentOnEveryThirdSync) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(3), t.clock.now()));
  t.set(0x0001);
  std::vector<std::size_t> counts;
  for (int i = 1; i <= 9; ++i) {
    if (i == 5) t.set(0x0002);
    t.tx.on_sync(std::nullopt, t.clock.now());
    counts.push_back(t.sent.size());
  }
  EXPECT_EQ(counts, (std::vector<std::size_t>{0, 0, 1, 1, 1, 2, 2, 2, 3}));
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#0100", "205#0200", "205#0200"}));
}

TEST(PdoTransmitter, Pdo_7_5_2_36_SyncStartValueDelaysFirstTransmission) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(2, 0, 0, 4), t.clock.now()));
  std::vector<std::uint8_t> sent_at;
  for (std::uint8_t c = 1; c <= 10; ++c) {
    const auto before = t.sent.size();
    t.tx.on_sync(c, t.clock.now());
    if (t.sent.size() != before) sent_at.push_back(c);
  }
  EXPECT_EQ(sent_at, (std::vector<std::uint8_t>{4, 6, 8, 10}));
}

TEST(PdoTransmitter, Pdo_InhibitTimeHoldsBackEventPdo) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(255, 100), t.clock.now()));  // 10 ms
  t.set(1);
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#0100"}));
  t.clock.advance(3ms);
  t.set(2);
  t.clock.advance(2ms);
  t.set(3);  // replaces the held value
  EXPECT_EQ(t.sent.size(), 1U);
  EXPECT_EQ(t.tx.next_deadline(), t.clock.now() + 5ms);
  t.run_for(4ms);
  EXPECT_EQ(t.sent.size(), 1U);
  t.run_for(1ms);  // inhibit time over: the held event goes out, not lost
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#0100", "205#0300"}));
  EXPECT_EQ(t.tx.next_deadline(), TimePoint::max());
  t.run_for(20ms);
  t.set(4);  // outside the inhibit time: at once
  EXPECT_EQ(t.sent.back(), "205#0400");
}

TEST(PdoTransmitter, Pdo_EventTimerResends) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(254, 0, 100), t.clock.now()));
  const TimePoint start = t.clock.now();
  std::vector<Duration> at;
  t.set(7);
  at.push_back(t.clock.now() - start);
  t.run_for(50ms);
  t.set(8);  // an event restarts the timer
  t.run_for(250ms);
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#0700", "205#0800", "205#0800", "205#0800"}));
  EXPECT_EQ(t.tx.next_deadline(), start + 350ms);
}

TEST(PdoTransmitter, Pdo_EventTimerDuringInhibitWaitsForIt) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(255, 200, 10), t.clock.now()));  // inhibit 20 ms, timer 10 ms
  t.set(1);
  t.run_for(15ms);
  EXPECT_EQ(t.sent.size(), 1U);
  t.run_for(5ms);
  EXPECT_EQ(t.sent.size(), 2U);
}

TEST(PdoTransmitter, Pdo_7_2_2_3_RtrOnlyType253SentOnRtr) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(253), t.clock.now()));
  t.set(0xBEEF);
  t.tx.on_sync(std::nullopt, t.clock.now());
  EXPECT_TRUE(t.sent.empty());
  EXPECT_FALSE(t.tx.on_frame(*can::parse_frame("205#0000"), t.clock.now()));
  EXPECT_FALSE(t.tx.on_frame(*can::parse_frame("206#R2"), t.clock.now()));
  EXPECT_TRUE(t.tx.on_frame(*can::parse_frame("205#R2"), t.clock.now()));
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#EFBE"}));
}

TEST(PdoTransmitter, Pdo_7_2_2_3_Type252SendsDataSampledAtSync) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(252), t.clock.now()));
  t.set(1);
  t.tx.on_sync(std::nullopt, t.clock.now());
  t.set(2);
  EXPECT_TRUE(t.tx.on_frame(*can::parse_frame("205#R2"), t.clock.now()));
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#0100"}));
}

TEST(PdoTransmitter, Pdo_7_4_8_1_NoRtrBitAndInvalidPdo) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(253, 0, 0, 0, 0x40000000U), t.clock.now()));
  EXPECT_FALSE(t.tx.on_frame(*can::parse_frame("205#R2"), t.clock.now()));
  EXPECT_TRUE(t.sent.empty());
  EXPECT_EQ(t.tx.add_rpdo(6, 1, drive(255, 0, 0, 0, 0x80000000U), t.clock.now()).code(),
            make_error_code(SdoAbort::NoSuchObject));
}

TEST(PdoTransmitter, Pdo_SetValueAndRawChecked) {
  Fixture t;
  ASSERT_TRUE(t.tx.add_rpdo(5, 1, drive(255), t.clock.now()));
  const TimePoint now = t.clock.now();
  EXPECT_EQ(t.tx.set_value(5, 1, 0x6301, 0, Value::of_bool(true), now), make_error_code(SdoAbort::NotMappable));
  EXPECT_EQ(t.tx.set_value(5, 1, 0x6300, 0, Value::of_unsigned(DataType::Unsigned8, 1), now),
            make_error_code(SdoAbort::LengthMismatch));
  EXPECT_EQ(t.tx.set_value(5, 2, 0x6300, 0, Value::of_unsigned(DataType::Unsigned16, 1), now),
            make_error_code(SdoAbort::NoSuchObject));
  const Bytes three{1, 2, 3};
  EXPECT_EQ(t.tx.set_raw(5, 1, three, now), make_error_code(SdoAbort::LengthMismatch));
  EXPECT_TRUE(t.sent.empty());
  const Bytes two{0xAA, 0x55};
  EXPECT_FALSE(t.tx.set_raw(5, 1, two, now));
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#AA55"}));
}

TEST(PdoTransmitter, Pdo_BitMappedRpdoWithDummyPacked) {
  Fixture t;
  od::ObjectDictionary d = drive(255);
  add_map(d, Direction::Receive, 1, {0x63010001, 0x00010001, 0x63000010});  // flag, 1-bit dummy, word at bit 2
  ASSERT_EQ(*t.tx.add_rpdo(5, 1, d, t.clock.now()), 3U);
  const std::vector<MappedValue> values{{0x6301, 0, {}, Value::of_bool(true)},
                                        {0x6300, 0, {}, Value::of_unsigned(DataType::Unsigned16, 0xFFFF)}};
  ASSERT_FALSE(t.tx.set_values(5, 1, values, t.clock.now()));
  EXPECT_EQ(t.sent, (std::vector<std::string>{"205#FDFF03"}));  // one event for both values
}

}  // namespace
}  // namespace canopen::pdo

namespace canopen::pdo {
namespace {

TEST(PdoTransmitter, Pdo_CanFdPdoOfTwelveBytes) {
  FakeClock clock;
  std::vector<std::string> sent;
  PdoTransmitter tx{[&](const can::Frame& f) { sent.push_back(test::text(f)); }};
  od::ObjectDictionary own;  // the gateway's own TPDO1 on CAN FD
  test::add_var(own, 0x2000, "A", DataType::Unsigned64);
  test::add_var(own, 0x2001, "B", DataType::Unsigned32);
  ASSERT_FALSE(own.set(0x2001, 0, Value::of_unsigned(DataType::Unsigned32, 0x11223344)));
  test::add_comm(own, Direction::Transmit, 1, 0x1FF);
  test::add_map(own, Direction::Transmit, 1, {0x20000040, 0x20010020});
  EXPECT_FALSE(tx.add_from(0x7F, Direction::Transmit, 1, own, clock.now()));  // 12 bytes > 8
  ASSERT_EQ(*tx.add_from(0x7F, Direction::Transmit, 1, own, clock.now(), 64), 12U);
  ASSERT_FALSE(tx.set_value(0x7F, 1, 0x2000, 0, Value::of_unsigned(DataType::Unsigned64, 0x0807060504030201ULL),
                            clock.now()));
  EXPECT_EQ(sent, (std::vector<std::string>{"1FF##4010203040506070844332211"}));

  std::vector<PdoEvent> events;
  PdoReceiver rx{[](const can::Frame&) {}, [&](PdoEvent e) { events.push_back(std::move(e)); }, 64};
  ASSERT_TRUE(rx.add_node(0x7F, own).empty());
  ASSERT_TRUE(rx.on_frame(*can::parse_frame(sent[0]), clock.now()));
  ASSERT_EQ(events.size(), 1U);
  ASSERT_EQ(events[0].values.size(), 2U);
  EXPECT_EQ(events[0].values[1].value, Value::of_unsigned(DataType::Unsigned32, 0x11223344));
}

}  // namespace
}  // namespace canopen::pdo
