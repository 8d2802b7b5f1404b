// Tests for stack/src/can/bus_state.cpp: folding Linux CAN error frames and
// link changes into the ISO 11898-1 fault-confinement state.
#include "canopen/can/bus_state.hpp"

#include <gtest/gtest.h>

namespace canopen::can {
namespace {

ErrorFrameInfo controller(bool warning = false, bool passive = false, bool active = false) {
  ErrorFrameInfo e;
  e.controller = true;
  e.rx_warning = warning;
  e.rx_passive = passive;
  e.back_to_active = active;
  return e;
}

BusStateTracker up_tracker() {
  BusStateTracker t;
  t.on_link_up();
  return t;
}

TEST(BusState, StateAndCauseNames) {
  EXPECT_EQ(to_string(BusState::ErrorActive), "error-active");
  EXPECT_EQ(to_string(BusState::ErrorWarning), "error-warning");
  EXPECT_EQ(to_string(BusState::ErrorPassive), "error-passive");
  EXPECT_EQ(to_string(BusState::BusOff), "bus-off");
  EXPECT_EQ(to_string(BusState::Down), "down");
  EXPECT_EQ(to_string(BusEventCause::ErrorFrame), "error-frame");
  EXPECT_EQ(to_string(BusEventCause::ControllerRestarted), "restarted");
  EXPECT_EQ(to_string(BusEventCause::LinkDown), "link-down");
  EXPECT_EQ(to_string(BusEventCause::LinkRemoved), "link-removed");
  EXPECT_EQ(to_string(BusEventCause::LinkUp), "link-up");
  EXPECT_EQ(to_string(BusEventCause::RxOverflow), "rx-overflow");
}

TEST(BusStateTracker, StartsDown) {
  BusStateTracker t;
  EXPECT_EQ(t.state(), BusState::Down);
  EXPECT_EQ(t.protocol_errors(), 0U);
}

TEST(BusStateTracker, LinkUpMovesToErrorActive) {
  BusStateTracker t;
  const auto ev = t.on_link_up();
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->previous, BusState::Down);
  EXPECT_EQ(ev->state, BusState::ErrorActive);
  EXPECT_EQ(ev->cause, BusEventCause::LinkUp);
  EXPECT_EQ(t.state(), BusState::ErrorActive);
}

TEST(BusStateTracker, LinkUpWhenAlreadyUpReportsNothing) {
  auto t = up_tracker();
  EXPECT_FALSE(t.on_link_up());
  EXPECT_EQ(t.state(), BusState::ErrorActive);
}

TEST(BusStateTracker, LinkDownAndRemovedAreDistinguished) {
  auto t = up_tracker();
  const auto down = t.on_link_down(false);
  ASSERT_TRUE(down);
  EXPECT_EQ(down->cause, BusEventCause::LinkDown);
  EXPECT_EQ(down->previous, BusState::ErrorActive);
  EXPECT_EQ(down->state, BusState::Down);

  auto t2 = up_tracker();
  const auto removed = t2.on_link_down(true);
  ASSERT_TRUE(removed);
  EXPECT_EQ(removed->cause, BusEventCause::LinkRemoved);
  EXPECT_EQ(removed->state, BusState::Down);
}

TEST(BusStateTracker, LinkDownWhenAlreadyDownReportsNothing) {
  auto t = up_tracker();
  ASSERT_TRUE(t.on_link_down(false));
  EXPECT_FALSE(t.on_link_down(false));
}

TEST(BusStateTracker, WarningThenPassiveThenBusOff) {
  auto t = up_tracker();
  auto ev = t.on_error_frame(controller(true));
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->previous, BusState::ErrorActive);
  EXPECT_EQ(ev->state, BusState::ErrorWarning);
  EXPECT_EQ(ev->cause, BusEventCause::ErrorFrame);

  ev = t.on_error_frame(controller(false, true));
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->previous, BusState::ErrorWarning);
  EXPECT_EQ(ev->state, BusState::ErrorPassive);

  ErrorFrameInfo off;
  off.bus_off = true;
  ev = t.on_error_frame(off);
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->previous, BusState::ErrorPassive);
  EXPECT_EQ(ev->state, BusState::BusOff);
  EXPECT_EQ(t.state(), BusState::BusOff);
}

TEST(BusStateTracker, TxWarningAndTxPassiveCountLikeRx) {
  auto t = up_tracker();
  ErrorFrameInfo w;
  w.controller = true;
  w.tx_warning = true;
  ASSERT_TRUE(t.on_error_frame(w));
  EXPECT_EQ(t.state(), BusState::ErrorWarning);
  ErrorFrameInfo p;
  p.controller = true;
  p.tx_passive = true;
  ASSERT_TRUE(t.on_error_frame(p));
  EXPECT_EQ(t.state(), BusState::ErrorPassive);
}

TEST(BusStateTracker, RepeatedSameStateReportsOnce) {
  auto t = up_tracker();
  EXPECT_TRUE(t.on_error_frame(controller(true)));
  EXPECT_FALSE(t.on_error_frame(controller(true)));
  EXPECT_EQ(t.state(), BusState::ErrorWarning);
}

TEST(BusStateTracker, BackToActiveRecovers) {
  auto t = up_tracker();
  t.on_error_frame(controller(false, true));
  const auto ev = t.on_error_frame(controller(false, false, true));
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->previous, BusState::ErrorPassive);
  EXPECT_EQ(ev->state, BusState::ErrorActive);
  EXPECT_EQ(ev->cause, BusEventCause::ErrorFrame);
}

TEST(BusStateTracker, PassiveFallingBackToWarning) {
  auto t = up_tracker();
  t.on_error_frame(controller(false, true));
  const auto ev = t.on_error_frame(controller(true));
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->previous, BusState::ErrorPassive);
  EXPECT_EQ(ev->state, BusState::ErrorWarning);
}

TEST(BusStateTracker, MostSevereFlagWins) {
  auto t = up_tracker();
  ErrorFrameInfo e = controller(true, true, true);
  EXPECT_EQ(t.on_error_frame(e)->state, BusState::ErrorPassive);

  auto t2 = up_tracker();
  e.bus_off = true;
  EXPECT_EQ(t2.on_error_frame(e)->state, BusState::BusOff);
}

TEST(BusStateTracker, ControllerFlagsIgnoredWithoutControllerClass) {
  auto t = up_tracker();
  ErrorFrameInfo e;
  e.rx_passive = true;  // CAN_ERR_CRTL not set: data[1] is not meaningful
  EXPECT_FALSE(t.on_error_frame(e));
  EXPECT_EQ(t.state(), BusState::ErrorActive);
}

TEST(BusStateTracker, RestartAfterBusOffReturnsToActive) {
  auto t = up_tracker();
  ErrorFrameInfo off;
  off.bus_off = true;
  t.on_error_frame(off);
  ErrorFrameInfo restart;
  restart.restarted = true;
  const auto ev = t.on_error_frame(restart);
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->previous, BusState::BusOff);
  EXPECT_EQ(ev->state, BusState::ErrorActive);
  EXPECT_EQ(ev->cause, BusEventCause::ControllerRestarted);
}

TEST(BusStateTracker, RestartIsReportedEvenWithoutStateChange) {
  auto t = up_tracker();
  ErrorFrameInfo restart;
  restart.restarted = true;
  const auto ev = t.on_error_frame(restart);
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->cause, BusEventCause::ControllerRestarted);
  EXPECT_EQ(ev->previous, BusState::ErrorActive);
  EXPECT_EQ(ev->state, BusState::ErrorActive);
}

TEST(BusStateTracker, RxOverflowReportedWithoutStateChange) {
  auto t = up_tracker();
  t.on_error_frame(controller(true));
  ErrorFrameInfo e;
  e.controller = true;
  e.rx_overflow = true;
  const auto ev = t.on_error_frame(e);
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->cause, BusEventCause::RxOverflow);
  EXPECT_EQ(ev->state, BusState::ErrorWarning);
  EXPECT_EQ(ev->previous, BusState::ErrorWarning);
  EXPECT_EQ(t.state(), BusState::ErrorWarning);
  // Each overflow is reported.
  EXPECT_TRUE(t.on_error_frame(e));
}

TEST(BusStateTracker, ProtocolErrorsAreCountedWithoutStateChange) {
  auto t = up_tracker();
  ErrorFrameInfo e;
  e.protocol_error = true;
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(t.on_error_frame(e));
  EXPECT_EQ(t.protocol_errors(), 3U);
  EXPECT_EQ(t.state(), BusState::ErrorActive);
}

TEST(BusStateTracker, ProtocolErrorCountedAlongsideStateChange) {
  auto t = up_tracker();
  ErrorFrameInfo e = controller(true);
  e.protocol_error = true;
  EXPECT_TRUE(t.on_error_frame(e));
  EXPECT_EQ(t.protocol_errors(), 1U);
}

TEST(BusStateTracker, EventsCarryLatestErrorCounters) {
  auto t = up_tracker();
  ErrorFrameInfo e = controller(true);
  e.has_counters = true;
  e.tx_error_counter = 96;
  e.rx_error_counter = 12;
  const auto ev = t.on_error_frame(e);
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->tx_error_counter, 96);
  EXPECT_EQ(ev->rx_error_counter, 12);

  // A later frame without counters keeps the last known values.
  const auto ev2 = t.on_error_frame(controller(false, true));
  ASSERT_TRUE(ev2);
  EXPECT_EQ(ev2->tx_error_counter, 96);
  EXPECT_EQ(ev2->rx_error_counter, 12);
}

TEST(BusStateTracker, CountersUpdateEvenWithoutStateChange) {
  auto t = up_tracker();
  ErrorFrameInfo e;
  e.has_counters = true;
  e.tx_error_counter = 200;
  e.rx_error_counter = 130;
  EXPECT_FALSE(t.on_error_frame(e));
  const auto ev = t.on_error_frame(controller(false, true));
  ASSERT_TRUE(ev);
  EXPECT_EQ(ev->tx_error_counter, 200);
  EXPECT_EQ(ev->rx_error_counter, 130);
}

TEST(BusStateTracker, LinkUpAfterDownResetsCounters) {
  auto t = up_tracker();
  ErrorFrameInfo e = controller(false, true);
  e.has_counters = true;
  e.tx_error_counter = 140;
  e.rx_error_counter = 5;
  t.on_error_frame(e);
  const auto down = t.on_link_down(false);
  ASSERT_TRUE(down);
  EXPECT_EQ(down->previous, BusState::ErrorPassive);
  EXPECT_EQ(down->tx_error_counter, 140);
  const auto up = t.on_link_up();
  ASSERT_TRUE(up);
  EXPECT_EQ(up->state, BusState::ErrorActive);
  EXPECT_EQ(up->tx_error_counter, 0);
  EXPECT_EQ(up->rx_error_counter, 0);
}

TEST(BusStateTracker, BusOffToLinkDownToUp) {
  auto t = up_tracker();
  ErrorFrameInfo off;
  off.bus_off = true;
  t.on_error_frame(off);
  const auto down = t.on_link_down(false);
  ASSERT_TRUE(down);
  EXPECT_EQ(down->previous, BusState::BusOff);
  EXPECT_TRUE(t.on_link_up());
  EXPECT_EQ(t.state(), BusState::ErrorActive);
}

TEST(BusStateTracker, RemovalAfterLinkDownIsStillReported) {
  auto t = up_tracker();
  ASSERT_TRUE(t.on_link_down(false));
  const auto removed = t.on_link_down(true);
  ASSERT_TRUE(removed) << "an interface deleted while down must be reported as removed";
  EXPECT_EQ(removed->cause, BusEventCause::LinkRemoved);
  EXPECT_EQ(removed->previous, BusState::Down);
  EXPECT_FALSE(t.on_link_down(true));
  EXPECT_FALSE(t.on_link_down(false));
}

}  // namespace
}  // namespace canopen::can
