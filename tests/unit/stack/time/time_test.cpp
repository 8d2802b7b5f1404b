// Tests for stack/src/time/time.cpp: TIME producer and consumer (CiA 301
// 7.2.6, 1012h, TIME_OF_DAY of 7.1.6.5).
#include "canopen/time/time.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "canopen/od/gateway_dictionary.hpp"

namespace canopen::time {
namespace {

using namespace std::chrono_literals;

// 2024-02-29 12:00:00.000 UTC: day 14669 (394Dh) after 1984-01-01,
// 43 200 000 ms (0293 2E00h) after midnight.
constexpr std::int64_t kLeapDayNoon = 1709208000000;
constexpr const char* kLeapDayNoonFrame = "100#002E93024D39";

Value u32v(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned32, v); }

can::Frame frame(const char* text) {
  auto f = can::parse_frame(text);
  EXPECT_TRUE(f.has_value()) << text;
  return f.value_or(can::Frame{});
}

class TimeTest : public ::testing::Test {
 protected:
  TimeTest() : od(od::make_gateway_dictionary(5, {})) {}
  FakeClock clock;
  od::ObjectDictionary od;
  std::vector<std::string> sent;
  std::vector<TimeEvent> events;
  FrameSink sink() {
    return [this](const can::Frame& f) { sent.push_back(can::to_string(f)); };
  }
};

TEST_F(TimeTest, Time_7_2_6_ProducerSendsTimeOfDayBytes) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x40000100)));
  TimeProducer producer(od, sink());
  EXPECT_TRUE(producer.send(kLeapDayNoon));
  EXPECT_EQ(sent, (std::vector<std::string>{kLeapDayNoonFrame}));
  EXPECT_EQ(producer.next_deadline(), TimePoint::max());
}

TEST_F(TimeTest, Time_7_1_6_5_EpochIs1984_01_01) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x40000100)));
  TimeProducer producer(od, sink());
  producer.send(441763200000);  // 1984-01-01 00:00:00.000 UTC
  producer.send(441763200000 + 86400000 + 1);  // 1984-01-02 00:00:00.001
  EXPECT_EQ(sent, (std::vector<std::string>{"100#000000000000", "100#010000000100"}));
}

TEST_F(TimeTest, Time_7_5_2_15_ProducerOffWhenBit30Clear) {
  TimeProducer producer(od, sink());  // default 1012h: 100h, neither bit
  EXPECT_FALSE(producer.send(kLeapDayNoon));
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x80000100)));  // consume only
  EXPECT_FALSE(producer.send(kLeapDayNoon));
  EXPECT_TRUE(sent.empty());
}

TEST_F(TimeTest, Time_7_5_2_15_ExtendedCobId) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x60000100)));
  TimeProducer producer(od, sink());
  producer.send(kLeapDayNoon);
  EXPECT_EQ(sent, (std::vector<std::string>{"00000100#002E93024D39"}));
}

TEST_F(TimeTest, Time_7_2_6_PeriodicProducerSendsOnItsGrid) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x40000100)));
  const TimePoint t0 = clock.now();
  TimeProducer producer(od, sink(), 1s, t0);
  EXPECT_EQ(producer.next_deadline(), t0 + 1s);
  producer.on_time(t0 + 999ms, kLeapDayNoon);
  EXPECT_TRUE(sent.empty());
  producer.on_time(t0 + 1s, kLeapDayNoon);
  EXPECT_EQ(sent, (std::vector<std::string>{kLeapDayNoonFrame}));
  EXPECT_EQ(producer.next_deadline(), t0 + 2s);
  producer.on_time(t0 + 3500ms, kLeapDayNoon + 1000);  // late: once, grid kept
  EXPECT_EQ(sent.size(), 2U);
  EXPECT_EQ(sent[1], "100#E8319302" "4D39");
  EXPECT_EQ(producer.next_deadline(), t0 + 4s);
}

TEST_F(TimeTest, Time_7_2_6_ConsumerDecodesTimeOfDay) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x80000100)));
  TimeConsumer consumer(od, [this](const TimeEvent& e) { events.push_back(e); });
  EXPECT_TRUE(consumer.on_frame(frame(kLeapDayNoonFrame), clock.now()));
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].time, (TimeOfDay{43200000, 14669}));
  EXPECT_EQ(unix_ms_from_time_of_day(events[0].time), kLeapDayNoon);
}

TEST_F(TimeTest, Time_7_1_6_5_ReservedBitsOfMsAreIgnored) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x80000100)));
  TimeConsumer consumer(od, [this](const TimeEvent& e) { events.push_back(e); });
  consumer.on_frame(frame("100#002E93F24D39"), clock.now());
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].time.ms, 43200000U);
}

TEST_F(TimeTest, Time_7_5_2_15_ConsumerOffWhenBit31Clear) {
  TimeConsumer consumer(od, [this](const TimeEvent& e) { events.push_back(e); });
  EXPECT_FALSE(consumer.on_frame(frame(kLeapDayNoonFrame), clock.now()));
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x40000100)));  // produce only
  EXPECT_FALSE(consumer.on_frame(frame(kLeapDayNoonFrame), clock.now()));
  EXPECT_TRUE(events.empty());
}

TEST_F(TimeTest, Time_7_2_6_ConsumerIgnoresOtherIdsAndCountsShortFrames) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0x80000100)));
  TimeConsumer consumer(od, [this](const TimeEvent& e) { events.push_back(e); });
  EXPECT_FALSE(consumer.on_frame(frame("101#002E93024D39"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("100#R"), clock.now()));
  EXPECT_TRUE(consumer.on_frame(frame("100#002E93024D"), clock.now()));
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(consumer.malformed_count(), 1U);
}

TEST_F(TimeTest, Time_7_2_6_ProducerAndConsumerRoundTrip) {
  ASSERT_FALSE(od.set(0x1012, 0, u32v(0xC0000100)));
  TimeConsumer consumer(od, [this](const TimeEvent& e) { events.push_back(e); });
  TimeProducer producer(od, [&](const can::Frame& f) { consumer.on_frame(f, clock.now()); });
  producer.send(kLeapDayNoon + 123);
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(unix_ms_from_time_of_day(events[0].time), kLeapDayNoon + 123);
}

}  // namespace
}  // namespace canopen::time
