// Tests for stack/src/sync/sync.cpp: SYNC producer and consumer (CiA 301
// 7.2.5, 1005h, 1006h, 1007h, 1019h), driven by FakeClock.
#include "canopen/sync/sync.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "canopen/od/gateway_dictionary.hpp"

namespace canopen::sync {
namespace {

using namespace std::chrono_literals;

Value u8v(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned8, v); }
Value u32v(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned32, v); }

can::Frame frame(const char* text) {
  auto f = can::parse_frame(text);
  EXPECT_TRUE(f.has_value()) << text;
  return f.value_or(can::Frame{});
}

class SyncProducerTest : public ::testing::Test {
 protected:
  SyncProducerTest() : od(od::make_gateway_dictionary(5, {})) {}

  // Configures 1005h/1006h/1019h (locally, as a configuration tool would
  // have) and builds the producer at t0.
  SyncProducer& make(std::uint32_t cob_id, std::uint32_t period_us, std::uint8_t overflow = 0) {
    EXPECT_FALSE(od.set(0x1005, 0, u32v(cob_id)));
    EXPECT_FALSE(od.set(0x1006, 0, u32v(period_us)));
    EXPECT_FALSE(od.set(0x1019, 0, u8v(overflow)));
    t0 = clock.now();
    producer.emplace(od, [this](const can::Frame& f) {
      sent.push_back(can::to_string(f));
      when.push_back(clock.now());
    }, t0);
    return *producer;
  }
  // Fires the producer's timer as a driver would, up to `t`.
  void run_until(TimePoint t) {
    while (producer->next_deadline() <= t) {
      clock.advance_to(producer->next_deadline());
      producer->on_time(clock.now());
    }
    clock.advance_to(t);
  }

  FakeClock clock;
  TimePoint t0{};
  od::ObjectDictionary od;
  std::optional<SyncProducer> producer;
  std::vector<std::string> sent;
  std::vector<TimePoint> when;
};

TEST_F(SyncProducerTest, Sync_7_5_2_6_PeriodIsExact) {
  EXPECT_EQ(make(0x40000080, 10000).state(), SyncProducer::State::Running);
  EXPECT_EQ(producer->next_deadline(), t0 + 10ms);
  run_until(t0 + 35ms);
  EXPECT_EQ(when, (std::vector<TimePoint>{t0 + 10ms, t0 + 20ms, t0 + 30ms}));
  EXPECT_EQ(sent, (std::vector<std::string>{"080#", "080#", "080#"}));
  EXPECT_EQ(producer->next_deadline(), t0 + 40ms);
}

TEST_F(SyncProducerTest, Sync_7_5_2_6_PeriodInMicroseconds) {
  make(0x40000080, 1250);
  run_until(t0 + 5ms);
  EXPECT_EQ(when, (std::vector<TimePoint>{t0 + 1250us, t0 + 2500us, t0 + 3750us, t0 + 5000us}));
}

TEST_F(SyncProducerTest, Sync_7_5_2_5_ProducerOffWhenBit30Clear) {
  EXPECT_EQ(make(0x00000080, 10000).state(), SyncProducer::State::Off);
  EXPECT_EQ(producer->next_deadline(), TimePoint::max());
  clock.advance(1s);
  producer->on_time(clock.now());
  EXPECT_TRUE(sent.empty());
}

TEST_F(SyncProducerTest, Sync_7_5_2_6_ProducerOffWhenPeriodIsZero) {
  EXPECT_EQ(make(0x40000080, 0).state(), SyncProducer::State::Off);
  clock.advance(1s);
  producer->on_time(clock.now());
  EXPECT_TRUE(sent.empty());
}

TEST_F(SyncProducerTest, Sync_7_5_2_22_OverflowZeroSendsNoCounterByte) {
  make(0x40000080, 1000, 0);
  EXPECT_EQ(producer->next_counter(), std::nullopt);
  run_until(t0 + 2ms);
  EXPECT_EQ(sent, (std::vector<std::string>{"080#", "080#"}));
}

TEST_F(SyncProducerTest, Sync_7_2_5_CounterStartsAtOneAndCountsUp) {
  make(0x40000080, 1000, 3);
  EXPECT_EQ(producer->next_counter(), 1U);
  run_until(t0 + 7ms);
  EXPECT_EQ(sent, (std::vector<std::string>{"080#01", "080#02", "080#03", "080#01", "080#02", "080#03",
                                            "080#01"}));
}

TEST_F(SyncProducerTest, Sync_7_2_5_CounterWrapsAfterOverflowValue) {
  make(0x40000080, 1000, 240);
  run_until(t0 + 241ms);
  ASSERT_EQ(sent.size(), 241U);
  EXPECT_EQ(sent[0], "080#01");
  EXPECT_EQ(sent[238], "080#EF");
  EXPECT_EQ(sent[239], "080#F0");
  EXPECT_EQ(sent[240], "080#01");
}

TEST_F(SyncProducerTest, Sync_7_2_5_ResetCounterRestartsAtOne) {
  make(0x40000080, 1000, 10);
  run_until(t0 + 3ms);
  producer->reset_counter();
  run_until(t0 + 4ms);
  EXPECT_EQ(sent, (std::vector<std::string>{"080#01", "080#02", "080#03", "080#01"}));
}

TEST_F(SyncProducerTest, Sync_7_5_2_6_ReconfigureStartsOnePeriodAfterTheUpdate) {
  make(0x40000080, 10000, 5);
  run_until(t0 + 15ms);
  ASSERT_FALSE(od.set(0x1006, 0, u32v(4000)));
  producer->reconfigure(clock.now());
  EXPECT_EQ(producer->next_deadline(), t0 + 19ms);
  run_until(t0 + 23ms);
  EXPECT_EQ(when, (std::vector<TimePoint>{t0 + 10ms, t0 + 19ms, t0 + 23ms}));
  EXPECT_EQ(sent, (std::vector<std::string>{"080#01", "080#01", "080#02"}));
  // Clearing bit 30 stops it.
  ASSERT_FALSE(od.set(0x1005, 0, u32v(0x80)));
  producer->reconfigure(clock.now());
  EXPECT_EQ(producer->next_deadline(), TimePoint::max());
}

TEST_F(SyncProducerTest, Sync_7_2_5_LateTimerSendsOnceAndKeepsTheGrid) {
  make(0x40000080, 10000, 4);
  clock.advance_to(t0 + 35ms);
  producer->on_time(clock.now());
  EXPECT_EQ(sent, (std::vector<std::string>{"080#01"}));
  EXPECT_EQ(producer->next_deadline(), t0 + 40ms);
  producer->on_time(clock.now());  // not due again
  EXPECT_EQ(sent.size(), 1U);
}

TEST_F(SyncProducerTest, Sync_7_5_2_5_ExtendedCobId) {
  make(0x60000080, 1000);
  run_until(t0 + 1ms);
  EXPECT_EQ(sent, (std::vector<std::string>{"00000080#"}));
}

// ---- consumer --------------------------------------------------------------------

class SyncConsumerTest : public ::testing::Test {
 protected:
  SyncConsumerTest()
      : od(od::make_gateway_dictionary(5, {})), consumer(od, [this](const SyncEvent& e) { events.push_back(e); }) {}
  FakeClock clock;
  od::ObjectDictionary od;
  std::vector<SyncEvent> events;
  SyncConsumer consumer;
};

TEST_F(SyncConsumerTest, Sync_7_2_5_EventPerSyncWithOptionalCounter) {
  EXPECT_TRUE(consumer.on_frame(frame("080#"), clock.now()));
  EXPECT_TRUE(consumer.on_frame(frame("080#07"), clock.now()));
  ASSERT_EQ(events.size(), 2U);
  EXPECT_EQ(events[0].counter, std::nullopt);
  EXPECT_EQ(events[1].counter, 7U);
  EXPECT_EQ(consumer.last_counter(), 7U);
  EXPECT_EQ(consumer.last_sync(), clock.now());
}

TEST_F(SyncConsumerTest, Sync_7_2_5_8240h_UnexpectedLengthIsCountedNotReported) {
  EXPECT_TRUE(consumer.on_frame(frame("080#0102"), clock.now()));
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(consumer.bad_length_count(), 1U);
  EXPECT_EQ(consumer.last_sync(), std::nullopt);
}

TEST_F(SyncConsumerTest, Sync_7_5_2_5_ConsumerFollows1005h) {
  EXPECT_FALSE(consumer.on_frame(frame("081#"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("080#R"), clock.now()));
  ASSERT_FALSE(od.set(0x1005, 0, u32v(0x20000090)));
  EXPECT_FALSE(consumer.on_frame(frame("080#"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("090#"), clock.now()));
  EXPECT_TRUE(consumer.on_frame(frame("00000090#"), clock.now()));
  EXPECT_EQ(events.size(), 1U);
}

TEST_F(SyncConsumerTest, Sync_1007h_WindowZeroMeansAlwaysInside) {
  EXPECT_TRUE(consumer.in_sync_window(clock.now()));
  consumer.on_frame(frame("080#"), clock.now());
  clock.advance(1h);
  EXPECT_TRUE(consumer.in_sync_window(clock.now()));
}

TEST_F(SyncConsumerTest, Sync_1007h_LateFrameIsOutsideWindow) {
  ASSERT_FALSE(od.set(0x1007, 0, u32v(2000)));  // 2 ms
  EXPECT_FALSE(consumer.in_sync_window(clock.now()));  // no SYNC yet
  const TimePoint t = clock.now();
  consumer.on_frame(frame("080#"), t);
  EXPECT_TRUE(consumer.in_sync_window(t));
  EXPECT_TRUE(consumer.in_sync_window(t + 1999us));
  EXPECT_FALSE(consumer.in_sync_window(t + 2000us));
  EXPECT_FALSE(consumer.in_sync_window(t + 9ms));
  // The next SYNC opens the next window.
  consumer.on_frame(frame("080#"), t + 10ms);
  EXPECT_TRUE(consumer.in_sync_window(t + 11ms));
  EXPECT_FALSE(consumer.in_sync_window(t + 12ms));
}

TEST(SyncLoopback, Sync_1007h_ProducedSyncFedToConsumerOpensTheWindow) {
  FakeClock clock;
  auto od = od::make_gateway_dictionary(5, {});
  ASSERT_FALSE(od.set(0x1005, 0, u32v(0x40000080)));
  ASSERT_FALSE(od.set(0x1006, 0, u32v(10000)));
  ASSERT_FALSE(od.set(0x1007, 0, u32v(3000)));
  int events = 0;
  SyncConsumer consumer(od, [&](const SyncEvent&) { ++events; });
  SyncProducer producer(od, [&](const can::Frame& f) { consumer.on_frame(f, clock.now()); }, clock.now());
  const TimePoint t0 = clock.now();
  clock.advance_to(producer.next_deadline());
  producer.on_time(clock.now());
  EXPECT_EQ(events, 1);
  EXPECT_TRUE(consumer.in_sync_window(t0 + 12ms));
  EXPECT_FALSE(consumer.in_sync_window(t0 + 13ms));
}

}  // namespace
}  // namespace canopen::sync
