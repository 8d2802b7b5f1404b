// Tests for stack/src/emcy/emcy.cpp: the EMCY producer of the gateway's own
// node and the EMCY consumer (CiA 301 7.2.7, 1001h, 1003h, 1014h, 1015h,
// 1028h), one test per rule, driven by FakeClock, asserting exact frames.
#include "canopen/emcy/emcy.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "canopen/od/gateway_dictionary.hpp"

namespace canopen::emcy {
namespace {

using namespace std::chrono_literals;
namespace reg = error_register;

constexpr std::uint8_t kNode = 5;  // own EMCY COB-ID 85h

Value u16v(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned16, v); }
Value u32v(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned32, v); }

can::Frame frame(const char* text) {
  auto f = can::parse_frame(text);
  EXPECT_TRUE(f.has_value()) << text;
  return f.value_or(can::Frame{});
}

class EmcyProducerTest : public ::testing::Test {
 protected:
  explicit EmcyProducerTest(std::uint8_t history = 8)
      : od(od::make_gateway_dictionary(kNode, {}, {.error_history_size = history})),
        producer(od, [this](const can::Frame& f) { sent.push_back(can::to_string(f)); }) {}

  std::uint64_t get(std::uint16_t index, std::uint8_t sub) const { return od.get_unsigned(index, sub).value_or(~0ULL); }

  FakeClock clock;
  od::ObjectDictionary od;
  std::vector<std::string> sent;
  EmcyProducer producer;
};

class EmcySmallHistoryTest : public EmcyProducerTest {
 protected:
  EmcySmallHistoryTest() : EmcyProducerTest(2) {}
};

TEST_F(EmcyProducerTest, Emcy_7_2_7_3_FrameIsCodeLeRegisterAndManufacturerField) {
  EXPECT_TRUE(producer.raise(0x8130, reg::kCommunication, clock.now(), {1, 2, 3, 4, 5}));
  EXPECT_EQ(sent, (std::vector<std::string>{"085#3081110102030405"}));
}

TEST_F(EmcyProducerTest, Emcy_7_5_2_2_ErrorRegisterIsOrOfPresentErrorsWithGenericBit) {
  EXPECT_EQ(get(0x1001, 0), 0U);
  producer.raise(0x3100, reg::kVoltage, clock.now());
  EXPECT_EQ(get(0x1001, 0), 0x05U);
  producer.raise(0x4200, reg::kTemperature, clock.now());
  EXPECT_EQ(get(0x1001, 0), 0x0DU);
  producer.clear(0x3100, clock.now());
  EXPECT_EQ(get(0x1001, 0), 0x09U);
  EXPECT_EQ(producer.error_register(), 0x09U);
  // A generic error with no category bits still sets bit 0.
  producer.clear(0x4200, clock.now());
  producer.raise(0x1000, 0, clock.now());
  EXPECT_EQ(get(0x1001, 0), 0x01U);
}

TEST_F(EmcyProducerTest, Emcy_7_5_2_4_HistoryNewestAtSub1OlderMoveDown) {
  producer.raise(0x3100, reg::kVoltage, clock.now(), {}, 0x0001);
  producer.raise(0x4200, reg::kTemperature, clock.now());
  producer.raise(0x8110, reg::kCommunication, clock.now(), {}, 0xABCD);
  EXPECT_EQ(get(0x1003, 0), 3U);
  EXPECT_EQ(get(0x1003, 1), 0xABCD8110U);  // additional information in the upper 16 bits
  EXPECT_EQ(get(0x1003, 2), 0x00004200U);
  EXPECT_EQ(get(0x1003, 3), 0x00013100U);
  // Clearing an error does not rewrite the history.
  producer.clear(0x4200, clock.now());
  EXPECT_EQ(get(0x1003, 0), 3U);
  EXPECT_EQ(get(0x1003, 1), 0xABCD8110U);
}

TEST_F(EmcySmallHistoryTest, Emcy_7_5_2_4_FullHistoryDropsTheOldest) {
  producer.raise(0x1000, 0, clock.now());
  producer.raise(0x2000, reg::kCurrent, clock.now());
  producer.raise(0x3000, reg::kVoltage, clock.now());
  EXPECT_EQ(get(0x1003, 0), 2U);
  EXPECT_EQ(get(0x1003, 1), 0x3000U);
  EXPECT_EQ(get(0x1003, 2), 0x2000U);
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_InhibitTimeHoldsBackTheSecondEmcy) {
  ASSERT_FALSE(od.set(0x1015, 0, u16v(10)));  // 10 x 100 us = 1 ms
  const TimePoint t0 = clock.now();
  producer.raise(0x8110, reg::kCommunication, t0);
  EXPECT_EQ(sent.size(), 1U);
  clock.advance(500us);
  producer.raise(0x8120, reg::kCommunication, clock.now());
  EXPECT_EQ(sent.size(), 1U);
  EXPECT_EQ(producer.queued(), 1U);
  EXPECT_EQ(producer.next_deadline(), t0 + 1ms);
  clock.advance_to(t0 + 999us);
  producer.on_time(clock.now());
  EXPECT_EQ(sent.size(), 1U);
  clock.advance_to(t0 + 1ms);
  producer.on_time(clock.now());
  EXPECT_EQ(sent, (std::vector<std::string>{"085#1081110000000000", "085#2081110000000000"}));
  EXPECT_EQ(producer.queued(), 0U);
  EXPECT_EQ(producer.next_deadline(), TimePoint::max());
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_EmcyExactlyAtEndOfInhibitTimeIsSentAtOnce) {
  ASSERT_FALSE(od.set(0x1015, 0, u16v(10)));
  producer.raise(0x8110, reg::kCommunication, clock.now());
  clock.advance(1ms);
  producer.raise(0x8120, reg::kCommunication, clock.now());
  EXPECT_EQ(sent.size(), 2U);
  EXPECT_EQ(producer.queued(), 0U);
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_HeldBackEmcysAreQueuedInOrderOnePerInhibitTime) {
  ASSERT_FALSE(od.set(0x1015, 0, u16v(20)));  // 2 ms
  const TimePoint t0 = clock.now();
  producer.raise(0x3100, reg::kVoltage, t0);
  producer.raise(0x4200, reg::kTemperature, t0);
  producer.clear(0x3100, t0);
  EXPECT_EQ(producer.queued(), 2U);
  std::vector<TimePoint> when;
  while (producer.next_deadline() != TimePoint::max()) {
    clock.advance_to(producer.next_deadline());
    producer.on_time(clock.now());
    when.push_back(clock.now());
  }
  EXPECT_EQ(when, (std::vector<TimePoint>{t0 + 2ms, t0 + 4ms}));
  // Each frame carries the register of the moment it was raised.
  EXPECT_EQ(sent, (std::vector<std::string>{"085#0031050000000000", "085#00420D0000000000",
                                            "085#0000090000000000"}));
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_NoInhibitTimeSendsEveryEmcyAtOnce) {
  producer.raise(0x3100, reg::kVoltage, clock.now());
  producer.raise(0x4200, reg::kTemperature, clock.now());
  EXPECT_EQ(sent.size(), 2U);
  EXPECT_EQ(producer.next_deadline(), TimePoint::max());
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_ClearingTheLastErrorSendsErrorReset) {
  producer.raise(0x5000, 0, clock.now(), {9, 9, 9, 9, 9});
  EXPECT_TRUE(producer.clear(0x5000, clock.now()));
  EXPECT_EQ(sent.back(), "085#0000000000000000");
  EXPECT_EQ(get(0x1001, 0), 0U);
  EXPECT_FALSE(producer.has_errors());
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_ClearingOneOfTwoErrorsSendsResetWithRemainingRegister) {
  producer.raise(0x3100, reg::kVoltage, clock.now());
  producer.raise(0x8110, reg::kCommunication, clock.now());
  producer.clear(0x8110, clock.now());
  EXPECT_EQ(sent.back(), "085#0000050000000000");
  EXPECT_TRUE(producer.is_present(0x3100));
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_ClearAllSendsOneErrorReset) {
  producer.raise(0x3100, reg::kVoltage, clock.now());
  producer.raise(0x8110, reg::kCommunication, clock.now());
  producer.clear_all(clock.now());
  EXPECT_EQ(sent.size(), 3U);
  EXPECT_EQ(sent.back(), "085#0000000000000000");
  producer.clear_all(clock.now());  // error-free already: nothing
  EXPECT_EQ(sent.size(), 3U);
}

TEST_F(EmcyProducerTest, Emcy_7_2_7_1_AnErrorEventTriggersOneEmcyOnly) {
  EXPECT_TRUE(producer.raise(0x8130, reg::kCommunication, clock.now()));
  EXPECT_FALSE(producer.raise(0x8130, reg::kCommunication, clock.now()));
  EXPECT_FALSE(producer.raise(0x0000, 0, clock.now()));   // not an error
  EXPECT_FALSE(producer.clear(0x1000, clock.now()));      // not present
  EXPECT_EQ(sent.size(), 1U);
  EXPECT_EQ(get(0x1003, 0), 1U);
}

TEST_F(EmcyProducerTest, Emcy_7_5_2_17_InvalidCobIdSendsNothingButKeeps1001hAnd1003h) {
  ASSERT_FALSE(od.set(0x1014, 0, u32v(0x80000085)));
  producer.raise(0x8110, reg::kCommunication, clock.now());
  EXPECT_TRUE(sent.empty());
  EXPECT_EQ(producer.queued(), 0U);
  EXPECT_EQ(get(0x1001, 0), 0x11U);
  EXPECT_EQ(get(0x1003, 1), 0x8110U);
}

TEST_F(EmcyProducerTest, Emcy_7_5_2_17_HeldBackEmcysAreDiscardedWhenCobIdTurnsInvalid) {
  ASSERT_FALSE(od.set(0x1015, 0, u16v(10)));
  producer.raise(0x1000, 0, clock.now());
  producer.raise(0x2000, reg::kCurrent, clock.now());
  ASSERT_EQ(producer.queued(), 1U);
  ASSERT_FALSE(od.set(0x1014, 0, u32v(0x80000085)));
  clock.advance(1ms);
  producer.on_time(clock.now());
  EXPECT_EQ(sent.size(), 1U);
  EXPECT_EQ(producer.queued(), 0U);
  EXPECT_EQ(producer.next_deadline(), TimePoint::max());
}

TEST_F(EmcyProducerTest, Emcy_7_5_2_17_CobIdIsReadAtEachSendWith29BitIds) {
  ASSERT_FALSE(od.set(0x1014, 0, u32v(0x000000A5)));
  producer.raise(0x1000, 0, clock.now());
  ASSERT_FALSE(od.set(0x1014, 0, u32v(0x20012345)));
  producer.raise(0x2000, 0, clock.now());
  EXPECT_EQ(sent, (std::vector<std::string>{"0A5#0010010000000000", "00012345#0020010000000000"}));
}

// ---- consumer --------------------------------------------------------------------

class EmcyConsumerTest : public ::testing::Test {
 protected:
  EmcyConsumerTest() : consumer({}, [this](const EmcyEvent& e) { events.push_back(e); }) {}
  FakeClock clock;
  std::vector<EmcyEvent> events;
  EmcyConsumer consumer;
};

TEST_F(EmcyConsumerTest, Emcy_7_2_7_ConsumerDecodesDefaultCobId) {
  EXPECT_TRUE(consumer.on_frame(frame("083#3081110102030405"), clock.now()));
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].node, 3U);
  EXPECT_EQ(events[0].error_code, 0x8130U);
  EXPECT_EQ(events[0].error_register, 0x11U);
  EXPECT_EQ(events[0].manufacturer, (ManufacturerField{1, 2, 3, 4, 5}));
  EXPECT_EQ(events[0].description, "Life guard error or heartbeat error");
  EXPECT_TRUE(consumer.on_frame(frame("0FF#0000000000000000"), clock.now()));
  EXPECT_EQ(events.back().node, 127U);
  EXPECT_EQ(events.back().description, "Error reset or no error");
}

TEST_F(EmcyConsumerTest, Emcy_7_2_7_ConsumerIgnoresOtherIdsAndRemoteFrames) {
  EXPECT_FALSE(consumer.on_frame(frame("080#"), clock.now()));        // SYNC
  EXPECT_FALSE(consumer.on_frame(frame("100#0000000000"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("083#R"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("00000083#0010010000000000"), clock.now()));  // 29-bit
  EXPECT_TRUE(events.empty());
}

TEST_F(EmcyConsumerTest, Emcy_7_2_7_ShortFrameIsReportedAsMalformed) {
  EXPECT_TRUE(consumer.on_frame(frame("084#103001"), clock.now()));
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].node, 4U);
  EXPECT_EQ(events[0].error_code, 0x3010U);
  EXPECT_EQ(events[0].error_register, 0x01U);
  EXPECT_EQ(events[0].manufacturer, (ManufacturerField{}));
  EXPECT_EQ(events[0].description, "malformed EMCY: 3 data bytes, 8 expected");
  consumer.on_frame(frame("084#"), clock.now());
  EXPECT_EQ(events.back().description, "malformed EMCY: 0 data bytes, 8 expected");
}

TEST(EmcyDescription, Emcy_7_2_7_1_DescriptionForACodeOfEachClass) {
  const std::vector<std::pair<std::uint16_t, std::string>> cases = {
      {0x0000, "Error reset or no error"},
      {0x0001, "Error reset or no error"},
      {0x1000, "Generic error"},
      {0x1001, "Generic error"},
      {0x2001, "Current"},
      {0x2110, "Current, CANopen device input side"},
      {0x2210, "Current inside the CANopen device"},
      {0x2310, "Current, CANopen device output side"},
      {0x2400, "Current"},  // unlisted sub-class: its general class
      {0x3001, "Voltage"},
      {0x3110, "Mains voltage"},
      {0x3210, "Voltage inside the CANopen device"},
      {0x3310, "Output voltage"},
      {0x4001, "Temperature"},
      {0x4110, "Ambient temperature"},
      {0x4210, "CANopen device temperature"},
      {0x5010, "CANopen device hardware"},
      {0x6001, "CANopen device software"},
      {0x6110, "Internal software"},
      {0x6201, "User software"},
      {0x6301, "Data set"},
      {0x7001, "Additional modules"},
      {0x8001, "Monitoring"},
      {0x8101, "Communication"},
      {0x8100, "Communication - generic"},
      {0x8110, "CAN overrun (objects lost)"},
      {0x8120, "CAN in error passive mode"},
      {0x8130, "Life guard error or heartbeat error"},
      {0x8140, "Recovered from bus off"},
      {0x8150, "CAN-ID collision"},
      {0x8201, "Protocol error"},
      {0x8210, "PDO not processed due to length error"},
      {0x8220, "PDO length exceeded"},
      {0x8230, "DAM MPDO not processed, destination object not available"},
      {0x8240, "Unexpected SYNC data length"},
      {0x8250, "RPDO timeout"},
      {0x9001, "External error"},
      {0xF001, "Additional functions"},
      {0xFF01, "CANopen device specific"},
      {0xFF00, "Device specific - generic error"},
      {0xA000, "Unknown error code class"},
      {0xF100, "Unknown error code class"},
  };
  for (const auto& [code, text] : cases) EXPECT_EQ(emcy_description(code), text) << std::hex << code;
  EXPECT_EQ(emcy_class_description(0x8110), "Communication");
}

TEST(EmcyConsumer1028h, Emcy_7_5_2_31_ConsumerUses1028hCobIdsPerNode) {
  od::ObjectDictionary od;
  od.insert(od::make_array(0x1028, "Emergency consumer", DataType::Unsigned32, od::Access::ReadWrite, 4));
  ASSERT_FALSE(od.set(0x1028, 1, u32v(0x80000081)));  // node 1: not consumed
  ASSERT_FALSE(od.set(0x1028, 2, u32v(0x1A0)));       // node 2 on 1A0h
  ASSERT_FALSE(od.set(0x1028, 3, u32v(0x20000333)));  // node 3 on a 29-bit CAN-ID
  ASSERT_FALSE(od.set(0x1028, 4, u32v(0x84)));
  std::vector<EmcyEvent> events;
  EmcyConsumer consumer(EmcyConsumerConfig::from_dictionary(od), [&](const EmcyEvent& e) { events.push_back(e); });
  FakeClock clock;
  EXPECT_FALSE(consumer.on_frame(frame("081#0010010000000000"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("082#0010010000000000"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("085#0010010000000000"), clock.now()));  // not listed
  EXPECT_TRUE(consumer.on_frame(frame("1A0#1082110000000000"), clock.now()));
  EXPECT_TRUE(consumer.on_frame(frame("00000333#5082210000000000"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("333#5082210000000000"), clock.now()));  // 11-bit: other object
  EXPECT_TRUE(consumer.on_frame(frame("084#0000000000000000"), clock.now()));
  ASSERT_EQ(events.size(), 3U);
  EXPECT_EQ(events[0].node, 2U);
  EXPECT_EQ(events[0].description, "PDO not processed due to length error");
  EXPECT_EQ(events[1].node, 3U);
  EXPECT_EQ(events[1].description, "RPDO timeout");
  EXPECT_EQ(events[2].node, 4U);
}

TEST(EmcyConsumer1028h, Emcy_7_5_2_31_AllEntriesInvalidConsumesNothing) {
  od::ObjectDictionary od;
  od.insert(od::make_array(0x1028, "Emergency consumer", DataType::Unsigned32, od::Access::ReadWrite, 1));
  ASSERT_FALSE(od.set(0x1028, 1, u32v(0x80000081)));
  EmcyConsumer consumer(EmcyConsumerConfig::from_dictionary(od), nullptr);
  FakeClock clock;
  EXPECT_FALSE(consumer.on_frame(frame("081#0010010000000000"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("082#0010010000000000"), clock.now()));
}

TEST(EmcyConsumer1028h, Emcy_7_5_2_31_Without1028hEveryNodeOnItsDefaultCobId) {
  const auto od = od::make_gateway_dictionary(kNode, {});
  ASSERT_EQ(od.find(0x1028), nullptr);
  const auto cfg = EmcyConsumerConfig::from_dictionary(od);
  EXPECT_TRUE(cfg.cob_ids.empty());
  int n = 0;
  EmcyConsumer consumer(cfg, [&](const EmcyEvent&) { ++n; });
  FakeClock clock;
  EXPECT_TRUE(consumer.on_frame(frame("081#0010010000000000"), clock.now()));
  EXPECT_TRUE(consumer.on_frame(frame("0FF#0010010000000000"), clock.now()));
  EXPECT_FALSE(consumer.on_frame(frame("100#0010010000000000"), clock.now()));
  EXPECT_EQ(n, 2);
}

}  // namespace
}  // namespace canopen::emcy
