// Tests for stack/src/lss/master.cpp, master_switch.cpp,
// master_configure.cpp and master_identify.cpp: every master service's
// request frames byte for byte and its answer handling (CiA 305; facts
// C.1): slave error codes, wrong cs and DLC != 8 ignored, timeouts on a
// fake clock, the queue, deadlines.
#include <gtest/gtest.h>

#include <chrono>
#include <optional>

#include "canopen/lss/master.hpp"
#include "unit/stack/lss/lss_test_support.hpp"

namespace canopen::lss {
namespace {

using namespace std::chrono_literals;
using Strings = std::vector<std::string>;
using test::parse;

template <typename T>
struct Got {
  std::optional<Result<T>> r;
  int calls = 0;
  Handler<T> handler() {
    return [this](Result<T> res) {
      ++calls;
      r.emplace(std::move(res));
    };
  }
};

class MasterTest : public ::testing::Test {
 protected:
  void rx(const std::string& f) { master.on_frame(parse(f), clock.now()); }
  void advance(Duration d) {
    clock.advance(d);
    if (master.next_deadline() <= clock.now()) master.on_time(clock.now());
  }

  FakeClock clock;
  test::FrameLog log;
  LssMaster master{MasterConfig{}, log.sink()};
};

TEST_F(MasterTest, SwitchGlobalIsUnconfirmedAndDoneAtNextOnTimeFactsC1) {
  Got<Ack> got;
  ASSERT_FALSE(master.switch_state_global(Mode::Configuration, got.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#0401000000000000"});
  EXPECT_EQ(got.calls, 0);  // never inside the submit
  EXPECT_EQ(master.next_deadline(), clock.now());
  master.on_time(clock.now());
  ASSERT_EQ(got.calls, 1);
  EXPECT_TRUE(got.r->ok());
  EXPECT_FALSE(master.busy());
  EXPECT_EQ(master.next_deadline(), TimePoint::max());
}

TEST_F(MasterTest, SwitchSelectiveSendsFourFramesAndWaitsFor44hFactsC1) {
  Got<Ack> got;
  ASSERT_FALSE(master.switch_state_selective({0x123, 0x4567, 0x10002, 0xBEEF}, got.handler(), clock.now()));
  EXPECT_EQ(log.take(), (Strings{"7E5#4023010000000000", "7E5#4167450000000000", "7E5#4202000100000000",
                                 "7E5#43EFBE0000000000"}));
  rx("7E4#4F00000000000000");  // wrong cs: not the answer
  rx("7E4#44000000000000");    // DLC 7: not an LSS frame
  EXPECT_EQ(got.calls, 0);
  rx("7E4#4400000000000000");
  ASSERT_EQ(got.calls, 1);
  EXPECT_TRUE(got.r->ok());
}

TEST_F(MasterTest, SwitchSelectiveTimesOutAfterTheTimeout) {
  Got<Ack> got;
  ASSERT_FALSE(master.switch_state_selective({1, 2, 3, 4}, got.handler(), clock.now()));
  EXPECT_EQ(master.next_deadline(), clock.now() + 1s);
  advance(999ms);
  EXPECT_EQ(got.calls, 0);
  advance(1ms);
  ASSERT_EQ(got.calls, 1);
  EXPECT_EQ(got.r->code(), make_error_code(LssError::Timeout));
}

TEST_F(MasterTest, ConfigureNodeIdOkAndSlaveErrorsFactsC1) {
  Got<Ack> ok, range, manuf;
  ASSERT_FALSE(master.configure_node_id(0x22, ok.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#1122000000000000"});
  rx("7E4#1100000000000000");
  ASSERT_EQ(ok.calls, 1);
  EXPECT_TRUE(ok.r->ok());

  ASSERT_FALSE(master.configure_node_id(0x7F, range.handler(), clock.now()));
  rx("7E4#1101000000000000");
  EXPECT_EQ(range.r->code(), make_error_code(LssError::NodeIdOutOfRange));

  ASSERT_FALSE(master.configure_node_id(kUnconfiguredNodeId, manuf.handler(), clock.now()));
  EXPECT_EQ(log.take().back(), "7E5#11FF000000000000");
  rx("7E4#11FF2A0000000000");
  EXPECT_EQ(manuf.r->code(), make_error_code(LssError::NodeIdManufacturer));
  EXPECT_EQ(manuf.r->error().detail, "manufacturer-specific error code 42");
}

TEST_F(MasterTest, ConfigureNodeIdRejectsInvalidIdsAndQueuesNothing) {
  Got<Ack> got;
  EXPECT_EQ(master.configure_node_id(0, got.handler(), clock.now()), std::errc::invalid_argument);
  EXPECT_EQ(master.configure_node_id(128, got.handler(), clock.now()), std::errc::invalid_argument);
  EXPECT_TRUE(log.take().empty());
  EXPECT_FALSE(master.busy());
}

TEST_F(MasterTest, ConfigureBitTimingActivateAndStoreFactsC1) {
  Got<Ack> bt, act, store, store_err;
  ASSERT_FALSE(master.configure_bit_timing(0, 3, bt.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#1300030000000000"});
  rx("7E4#1301000000000000");
  EXPECT_EQ(bt.r->code(), make_error_code(LssError::BitTimingNotSupported));

  ASSERT_FALSE(master.activate_bit_timing(500, act.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#15F4010000000000"});
  master.on_time(clock.now());
  EXPECT_TRUE(act.r->ok());

  ASSERT_FALSE(master.store_configuration(store.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#1700000000000000"});
  rx("7E4#1700000000000000");
  EXPECT_TRUE(store.r->ok());

  ASSERT_FALSE(master.store_configuration(store_err.handler(), clock.now()));
  rx("7E4#1702000000000000");
  EXPECT_EQ(store_err.r->code(), make_error_code(LssError::StoreMediaAccess));
  EXPECT_EQ(slave_error_byte(store_err.r->code()), 2);
}

TEST_F(MasterTest, InquireIdentityPartsAndNodeIdFactsC1) {
  Got<std::uint32_t> serial;
  ASSERT_FALSE(master.inquire_identity(Part::Serial, serial.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#5D00000000000000"});
  rx("7E4#5A44332211000000");  // another part's answer: ignored
  EXPECT_EQ(serial.calls, 0);
  rx("7E4#5D44332211000000");
  EXPECT_EQ(serial.r->value(), 0x11223344U);

  Got<std::uint8_t> nid;
  ASSERT_FALSE(master.inquire_node_id(nid.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#5E00000000000000"});
  rx("7E4#5E05000000000000");
  EXPECT_EQ(nid.r->value(), 5);
}

TEST_F(MasterTest, InquireAddressAsksTheFourPartsInTurn) {
  Got<Identity> got;
  ASSERT_FALSE(master.inquire_address(got.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#5A00000000000000"});
  rx("7E4#5A01000000000000");
  EXPECT_EQ(log.take(), Strings{"7E5#5B00000000000000"});
  rx("7E4#5B02000000000000");
  rx("7E4#5C03000000000000");
  EXPECT_EQ(got.calls, 0);
  rx("7E4#5D04000000000000");
  ASSERT_EQ(got.calls, 1);
  EXPECT_EQ(got.r->value(), (Identity{1, 2, 3, 4}));
}

TEST_F(MasterTest, IdentifyRemoteSlaveWaitsTheWholeWindowFactsC1) {
  Got<bool> got;
  const IdentityRange range{0x123, 0x4567, 0, 5, 100, 200};
  ASSERT_FALSE(master.identify_remote_slave(range, got.handler(), clock.now()));
  EXPECT_EQ(log.take(), (Strings{"7E5#4623010000000000", "7E5#4767450000000000", "7E5#4800000000000000",
                                 "7E5#4905000000000000", "7E5#4A64000000000000", "7E5#4BC8000000000000"}));
  rx("7E4#4F00000000000000");
  EXPECT_EQ(got.calls, 0);  // others may still answer
  advance(100ms);
  ASSERT_EQ(got.calls, 1);
  EXPECT_TRUE(got.r->value());

  Got<bool> none;
  ASSERT_FALSE(master.identify_remote_slave(range, none.handler(), clock.now()));
  advance(100ms);
  EXPECT_FALSE(none.r->value());

  EXPECT_EQ(master.identify_remote_slave({1, 2, 5, 4, 0, 0}, none.handler(), clock.now()),
            std::errc::invalid_argument);
}

TEST_F(MasterTest, IdentifyNonConfiguredFactsC1) {
  Got<bool> got;
  ASSERT_FALSE(master.identify_non_configured(got.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#4C00000000000000"});
  rx("7E4#4F00000000000000");  // not 50h
  advance(100ms);
  EXPECT_FALSE(got.r->value());
  Got<bool> yes;
  ASSERT_FALSE(master.identify_non_configured(yes.handler(), clock.now()));
  rx("7E4#5000000000000000");
  advance(100ms);
  EXPECT_TRUE(yes.r->value());
}

TEST_F(MasterTest, OneServiceAtATimeInSubmissionOrder) {
  Got<std::uint8_t> first;
  Got<Ack> second;
  ASSERT_FALSE(master.inquire_node_id(first.handler(), clock.now()));
  ASSERT_FALSE(master.store_configuration(second.handler(), clock.now()));
  EXPECT_EQ(log.take(), Strings{"7E5#5E00000000000000"});  // the store waits
  EXPECT_EQ(master.pending(), 2U);
  rx("7E4#1700000000000000");  // not the running service's answer
  EXPECT_EQ(second.calls, 0);
  rx("7E4#5E03000000000000");
  EXPECT_EQ(first.r->value(), 3);
  EXPECT_EQ(log.take(), Strings{"7E5#1700000000000000"});
  rx("7E4#1700000000000000");
  EXPECT_TRUE(second.r->ok());
}

TEST_F(MasterTest, QueueLimitAndCancelAll) {
  master.set_config({.timeout = 1s, .scan_step_timeout = 100ms, .queue_limit = 1, .fastscan_restarts = 2});
  Got<Ack> a, b, c;
  ASSERT_FALSE(master.store_configuration(a.handler(), clock.now()));
  ASSERT_FALSE(master.store_configuration(b.handler(), clock.now()));
  EXPECT_EQ(master.store_configuration(c.handler(), clock.now()), make_error_code(LssError::QueueFull));
  master.cancel_all(clock.now());
  EXPECT_EQ(a.r->code(), make_error_code(LssError::Cancelled));
  EXPECT_EQ(b.r->code(), make_error_code(LssError::Cancelled));
  EXPECT_EQ(c.calls, 0);
  EXPECT_FALSE(master.busy());
}

TEST_F(MasterTest, HandlerMaySubmitTheNextService) {
  Got<Ack> second;
  ASSERT_FALSE(master.configure_node_id(
      4,
      [&](Result<Ack> r) {
        ASSERT_TRUE(r.ok());
        ASSERT_FALSE(master.store_configuration(second.handler(), clock.now()));
      },
      clock.now()));
  log.take();
  rx("7E4#1100000000000000");
  EXPECT_EQ(log.take(), Strings{"7E5#1700000000000000"});
  rx("7E4#1700000000000000");
  EXPECT_TRUE(second.r->ok());
}

TEST_F(MasterTest, ReportsDeadlineChangesToTheObserver) {
  std::vector<TimePoint> reported;
  master.on_deadline_change([&](TimePoint t) { reported.push_back(t); });
  Got<Ack> got;
  ASSERT_FALSE(master.store_configuration(got.handler(), clock.now()));
  ASSERT_EQ(reported.size(), 1U);
  EXPECT_EQ(reported.back(), clock.now() + 1s);
  master.cancel_all(clock.now());
  EXPECT_EQ(reported.back(), TimePoint::max());
}

TEST_F(MasterTest, OnlySlaveFramesAreTaken) {
  EXPECT_TRUE(master.on_frame(parse("7E4#4F00000000000000"), clock.now()));  // stray: taken, changes nothing
  EXPECT_FALSE(master.on_frame(parse("7E5#4F00000000000000"), clock.now()));
  EXPECT_FALSE(master.on_frame(parse("7E4#4F"), clock.now()));
  EXPECT_FALSE(master.on_frame(parse("705#05"), clock.now()));
}

}  // namespace
}  // namespace canopen::lss
