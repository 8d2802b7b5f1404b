// canopen::Network: the master-side services of one network as one unit,
// and their single event stream (issue 4 item 8): per-network sequence
// numbers without gaps, timestamps from the frames that caused the events.
#include "canopen/network.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <variant>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/emcy/emcy.hpp"
#include "canopen/lss/slave.hpp"
#include "canopen/nmt/slave.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/pdo/transmitter.hpp"
#include "canopen/sdo/server.hpp"
#include "unit/stack/network/network_rig.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kDevice = 5;

struct Rig {
  FakeClock clock;
  can::Frame::Clock::time_point wall{std::chrono::seconds(1'800'000'000)};
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> gw_ep = bus.attach("gateway");
  std::unique_ptr<can::MemoryEndpoint> dev_ep = bus.attach("device");
  od::ObjectDictionary own = od::make_gateway_dictionary(127, {});
  eds::DeviceDescription desc = eds::load_device_description(CANOPEN_SOURCE_DIR "/deploy/eds/cia402-drive.eds",
                                                             kDevice);
  od::ObjectDictionary dev_od = desc.od;
  std::vector<Event> events;
  Network net{own, [this](const can::Frame& f) { gw_ep->send(f); }, [this](const Event& e) { events.push_back(e); },
              {}, [this] { return wall; }};
  nmt::NmtSlave slave{dev_od, kDevice, [this](const can::Frame& f) { dev_ep->send(f); }};
  emcy::EmcyProducer emcy{dev_od, [this](const can::Frame& f) { dev_ep->send(f); }};
  pdo::PdoTransmitter tpdo{[this](const can::Frame& f) { dev_ep->send(f); }};
  sdo::SdoServer server{dev_od, sdo::ServerConfig{kDevice}, [this](const can::Frame& f) { dev_ep->send(f); }};
  std::vector<can::Frame> device_rx;  // what the device received

  Rig() {
    // Receive time of every frame: the wall clock at delivery.
    bus.set_time_source([this] { return wall; });
    gw_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) net.on_frame(f, clock.now());
    });
    dev_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) {
        device_rx.push_back(f);
        slave.on_frame(f, clock.now());
        server.on_frame(f, clock.now());
      }
    });
    EXPECT_TRUE(net.add_node(kDevice, desc.od).empty());
    EXPECT_TRUE(tpdo.add_from(kDevice, pdo::Direction::Transmit, 1, dev_od, clock.now()));
  }
  // Advances both clocks and runs every service's timers.
  void step(Duration d) {
    clock.advance(d);
    wall += std::chrono::duration_cast<can::Frame::Clock::duration>(d);
    if (net.next_deadline() <= clock.now()) net.on_time(clock.now());
    if (slave.next_deadline() <= clock.now()) slave.on_time(clock.now());
    if (server.next_deadline() <= clock.now()) server.on_time(clock.now());
    bus.deliver();
  }
  template <typename T>
  std::vector<const Event*> of() const {
    std::vector<const Event*> out;
    for (const auto& e : events)
      if (std::holds_alternative<T>(e.body)) out.push_back(&e);
    return out;
  }
};

TEST(Network, EveryServiceReportsIntoOneStreamWithoutGaps) {
  Rig rig;
  ASSERT_FALSE(rig.dev_od.set(0x1017, 0, Value::of_unsigned(DataType::Unsigned16, 100)));  // heartbeat 100 ms
  rig.net.nmt().set_heartbeat_consumer(kDevice, 250ms);
  rig.slave.start(rig.clock.now());  // boot-up (7.2.8.3.3)
  rig.bus.deliver();
  rig.net.nmt().send_command(NmtCommand::Start, kDevice);
  rig.bus.deliver();
  rig.step(100ms);  // heartbeat: operational
  ASSERT_FALSE(rig.tpdo.set_value(kDevice, 1, 0x6041, 0, Value::of_unsigned(DataType::Unsigned16, 0x0637),
                                  rig.clock.now()));
  rig.bus.deliver();
  rig.emcy.raise(0x3210, 0x04, rig.clock.now());
  rig.bus.deliver();
  rig.net.report(can::BusEvent{can::BusState::ErrorWarning, can::BusState::ErrorActive});

  ASSERT_FALSE(rig.events.empty());
  for (std::size_t i = 0; i < rig.events.size(); ++i) EXPECT_EQ(rig.events[i].seq, i + 1) << "seq has a gap at " << i;
  EXPECT_EQ(rig.net.last_seq(), rig.events.size());
  ASSERT_EQ(rig.of<PdoEvent>().size(), 1U);
  const auto& pdo = std::get<PdoEvent>(rig.of<PdoEvent>()[0]->body);
  EXPECT_EQ(pdo.node, kDevice);
  ASSERT_EQ(pdo.values.size(), 1U);
  EXPECT_EQ(pdo.values[0].index, 0x6041);
  EXPECT_EQ(pdo.values[0].value, Value::of_unsigned(DataType::Unsigned16, 0x0637));
  ASSERT_EQ(rig.of<EmcyEvent>().size(), 1U);
  EXPECT_EQ(std::get<EmcyEvent>(rig.of<EmcyEvent>()[0]->body).error_code, 0x3210);
  EXPECT_EQ(rig.of<can::BusEvent>().size(), 1U);
  bool saw_operational = false;
  for (const auto* e : rig.of<NodeStateEvent>()) {
    const auto& s = std::get<NodeStateEvent>(e->body);
    saw_operational = saw_operational || s.state == NmtState::Operational;
  }
  EXPECT_TRUE(saw_operational);
}

// A sequence kept across restarts (the gateway's state-dir) goes on where
// it was: the first event gets the given number, the next ones +1.
TEST(Network, AContinuedSequenceStartsAtTheGivenNumber) {
  Rig rig;
  rig.net.continue_sequence(70'000);
  rig.net.report(can::BusEvent{can::BusState::ErrorActive, can::BusState::Down});
  rig.net.report(can::BusEvent{can::BusState::ErrorWarning, can::BusState::ErrorActive});
  ASSERT_EQ(rig.events.size(), 2U);
  EXPECT_EQ(rig.events[0].seq, 70'000U);
  EXPECT_EQ(rig.events[1].seq, 70'001U);
  EXPECT_EQ(rig.net.last_seq(), 70'001U);
}

TEST(Network, FrameEventsCarryTheFramesReceiveTimeAndTimerEventsTheWallTime) {
  Rig rig;
  rig.net.nmt().set_heartbeat_consumer(kDevice, 250ms);
  const auto boot_time = rig.wall;
  rig.slave.start(rig.clock.now());
  rig.bus.deliver();
  ASSERT_FALSE(rig.events.empty());
  EXPECT_EQ(rig.events.front().timestamp, boot_time) << "boot-up event stamped with the frame's receive time";

  // The device falls silent: lost exactly 250 ms after its last frame, and
  // that event has no frame, so it carries the wall time of the timer.
  rig.dev_ep->set_link_up(false);
  rig.step(249ms);
  EXPECT_TRUE(rig.of<NodeStateEvent>().size() == 1U) << "not lost before the consumer time";
  rig.step(1ms);
  const auto states = rig.of<NodeStateEvent>();
  ASSERT_EQ(states.size(), 2U);
  EXPECT_EQ(std::get<NodeStateEvent>(states[1]->body).cause, NodeStateEvent::Cause::Lost);
  EXPECT_EQ(states[1]->timestamp, boot_time + 250ms);
  EXPECT_EQ(states[1]->seq, states[0]->seq + 1);
}

// CiA 302 spirit, through the network: a boot-up starts identification,
// configuration from the DCF and NMT start; every step is an event of the
// same stream, after the boot-up it follows.
TEST(Network, BootUpConfigurationStepsJoinTheStream_7_2_8_3_3) {
  Rig rig;
  auto cfg = master::boot_config_from_dcf(rig.desc);
  ASSERT_TRUE(rig.net.configure_boot(kDevice, cfg));
  rig.slave.start(rig.clock.now());
  for (int i = 0; i < 200 && rig.slave.state() != nmt::NmtSlave::State::Operational; ++i) rig.step(1ms);
  EXPECT_EQ(rig.slave.state(), nmt::NmtSlave::State::Operational) << "started by the configurator";
  std::vector<BootConfigEvent::Step> steps;
  for (const auto* e : rig.of<BootConfigEvent>()) steps.push_back(std::get<BootConfigEvent>(e->body).step);
  using S = BootConfigEvent::Step;
  EXPECT_EQ(steps, (std::vector<S>{S::Identify, S::CheckIdentity, S::Configure, S::Start, S::Done}));
  ASSERT_FALSE(rig.events.empty());
  EXPECT_TRUE(std::holds_alternative<NodeStateEvent>(rig.events.front().body)) << "boot-up comes first";
  for (std::size_t i = 0; i < rig.events.size(); ++i) EXPECT_EQ(rig.events[i].seq, i + 1);
}

TEST(Network, BootUpConfigurationOfASilentNodeFailsWithTimeout) {
  Rig rig;
  ASSERT_TRUE(rig.net.configure_boot(kDevice, master::boot_config_from_dcf(rig.desc)));
  rig.slave.start(rig.clock.now());
  ASSERT_TRUE(rig.bus.deliver_one());  // only the boot-up
  rig.dev_ep->set_link_up(false);      // then the node says nothing more
  for (int i = 0; i < 100; ++i) rig.step(100ms);
  const auto boots = rig.of<BootConfigEvent>();
  ASSERT_FALSE(boots.empty());
  const auto& last = std::get<BootConfigEvent>(boots.back()->body);
  EXPECT_EQ(last.step, BootConfigEvent::Step::Failed);
  EXPECT_EQ(last.error, make_error_code(SdoAbort::Timeout));
}

// 7.2.2: the gateway writes process data to a node's RPDO; COB-ID and
// mapping come from the node's description (RPDO2: 6040h u16 + 6060h i8).
TEST(Network, ProcessDataGoesOutAsTheNodesRpdo_7_2_2) {
  Rig rig;
  const std::vector<MappedValue> values = {
      {0x6040, 0, "", Value::of_unsigned(DataType::Unsigned16, 0x000F)},
      {0x6060, 0, "", Value::of_signed(DataType::Integer8, 3)},
  };
  ASSERT_FALSE(rig.net.rpdo().set_values(kDevice, 2, values, rig.clock.now()));  // type 255: sent at once
  rig.bus.deliver();
  ASSERT_EQ(rig.device_rx.size(), 1U);
  EXPECT_EQ(rig.device_rx[0].id, 0x300U + kDevice);
  EXPECT_EQ(std::vector<std::uint8_t>(rig.device_rx[0].payload().begin(), rig.device_rx[0].payload().end()), (std::vector<std::uint8_t>{0x0F, 0x00, 0x03}));
  EXPECT_EQ(rig.net.rpdo().set_value(kDevice, 2, 0x6041, 0, Value::of_unsigned(DataType::Unsigned16, 1),
                                     rig.clock.now()),
            make_error_code(SdoAbort::NotMappable))
      << "an object the RPDO does not map is refused";
}

// 7.2.2.2: synchronous RPDO data (type 1) goes out on the SYNC the network sees.
TEST(Network, SynchronousRpdoDataWaitsForTheSync_7_2_2_2) {
  Rig rig;
  ASSERT_FALSE(rig.dev_od.set(0x1400, 2, Value::of_unsigned(DataType::Unsigned8, 1)));
  ASSERT_TRUE(rig.net.add_node(kDevice, rig.dev_od).empty());
  ASSERT_FALSE(rig.net.rpdo().set_value(kDevice, 1, 0x6040, 0, Value::of_unsigned(DataType::Unsigned16, 6),
                                        rig.clock.now()));
  rig.bus.deliver();
  EXPECT_TRUE(rig.device_rx.empty()) << "not before the SYNC";
  rig.dev_ep->send(can::Frame::standard(0x080, {}));  // a SYNC from another producer
  rig.bus.deliver();
  ASSERT_EQ(rig.device_rx.size(), 1U);
  EXPECT_EQ(rig.device_rx[0].id, 0x200U + kDevice);
  EXPECT_EQ(std::vector<std::uint8_t>(rig.device_rx[0].payload().begin(), rig.device_rx[0].payload().end()), (std::vector<std::uint8_t>{0x06, 0x00}));
}

// Run-time node configuration (issue 17 item 1): a node's description can be
// dropped and given again while the network runs. Without one its TPDOs are
// reported raw (7.2.2: the mapping says what the bytes mean) and its RPDOs
// are not produced; with a new one they are decoded at once.
TEST(Network, ANodesDescriptionCanBeRemovedAndGivenAgainAtRunTime_7_2_2) {
  Rig rig;
  auto tpdo_event = [&rig] {
    rig.events.clear();
    EXPECT_FALSE(rig.tpdo.set_value(kDevice, 1, 0x6041, 0, Value::of_unsigned(DataType::Unsigned16, 0x0637),
                                    rig.clock.now()));
    rig.bus.deliver();
    const auto pdos = rig.of<PdoEvent>();
    EXPECT_EQ(pdos.size(), 1U);
    return pdos.empty() ? PdoEvent{} : std::get<PdoEvent>(pdos[0]->body);
  };
  rig.net.remove_node(kDevice);
  const auto raw = tpdo_event();
  EXPECT_TRUE(raw.values.empty()) << "no description: raw bytes only";
  EXPECT_FALSE(raw.raw.empty());
  EXPECT_FALSE(rig.net.pdo_config().has_node(kDevice));
  EXPECT_EQ(rig.net.rpdo().config(kDevice, 2), nullptr) << "no description: its RPDOs are not produced";

  ASSERT_TRUE(rig.net.add_node(kDevice, rig.desc.od).empty());
  const auto decoded = tpdo_event();
  ASSERT_EQ(decoded.values.size(), 1U);
  EXPECT_EQ(decoded.values[0].index, 0x6041);
  EXPECT_NE(rig.net.rpdo().config(kDevice, 2), nullptr);
}

// add_node() of a node described before replaces the description as a
// whole: an RPDO the new one disables (COB-ID bit 31, 7.5.2.35) is no
// longer produced.
TEST(Network, AddingANodeAgainReplacesItsRpdos_7_5_2_35) {
  Rig rig;
  ASSERT_NE(rig.net.rpdo().config(kDevice, 2), nullptr);
  od::ObjectDictionary changed = rig.desc.od;
  const auto cob = changed.get(0x1401, 1);
  ASSERT_TRUE(cob);
  ASSERT_FALSE(changed.set(0x1401, 1, Value::of_unsigned(DataType::Unsigned32, std::get<std::uint64_t>(cob->data) | 0x80000000U)));
  (void)rig.net.add_node(kDevice, changed);
  EXPECT_EQ(rig.net.rpdo().config(kDevice, 2), nullptr);
  EXPECT_NE(rig.net.rpdo().config(kDevice, 1), nullptr) << "the others stay";
}

// The network's LSS master (CiA 305, issue 16): the slaves' answers (7E4h)
// reach it through Network::on_frame, its step windows run in on_time, and
// a submit reports the network's new deadline.
TEST(Network, LssMasterHearsTheSlavesAndRunsItsWindows_Cia305) {
  Rig rig;
  const lss::Identity identity{0x00000123, 0x00004567, 1, 0xBEEF};
  lss::LssSlave lss_slave{identity, lss::kUnconfiguredNodeId, [&rig](const can::Frame& f) { rig.dev_ep->send(f); }};
  rig.dev_ep->on_frames([&](std::span<const can::Frame> fs) {
    for (const auto& f : fs) lss_slave.on_frame(f);
  });
  std::vector<TimePoint> reported;
  rig.net.on_deadline_change([&](TimePoint t) { reported.push_back(t); });
  std::optional<lss::FastscanResult> got;
  ASSERT_FALSE(rig.net.lss().fastscan({}, [&](const lss::FastscanResult& r) { got = r; }, rig.clock.now()));
  ASSERT_FALSE(reported.empty());
  EXPECT_EQ(reported.back(), rig.clock.now() + 100ms);
  const std::size_t events_before = rig.events.size();
  rig.bus.deliver();
  for (int i = 0; i < 200 && !got; ++i) rig.step(100ms);
  ASSERT_TRUE(got);
  ASSERT_FALSE(got->error) << got->error.message();
  EXPECT_EQ(got->identity, identity);
  EXPECT_EQ(got->exchanges, 133U);
  EXPECT_EQ(lss_slave.mode(), lss::Mode::Configuration);
  for (std::size_t i = events_before; i < rig.events.size(); ++i)
    EXPECT_FALSE(std::holds_alternative<NodeStateEvent>(rig.events[i].body)) << "LSS frames are no node's heartbeat";
}

// Issue 28 item 2 (CiA 301 7.5.2.19): a 1017h the gateway writes to a node
// (REST, MQTT, DCF apply and the boot-up configuration all write through
// this SDO client) is the period the node is watched with at once: the
// EDS's 1000 ms would report a 3000 ms producer lost before every heartbeat.
TEST(Network, A1017hWrittenByTheGatewayIsTheWatchedPeriodAtOnce) {
  test::NetworkRig rig("deploy/eds/cia401-io-module.eds");
  ASSERT_TRUE(rig.net.nmt().set_auto_watch(test::NetworkRig::kNode, true, nmt::producer_heartbeat_time(rig.eds.od)));
  rig.power_on();
  rig.run_for(2500ms);
  ASSERT_EQ(rig.net.nmt().auto_watch_period(test::NetworkRig::kNode), 1000ms) << "the EDS's 1017h";
  ASSERT_FALSE(rig.write(0x1017, 0, {0xB8, 0x0B}));  // 3000 ms
  EXPECT_EQ(rig.net.nmt().auto_watch_period(test::NetworkRig::kNode), 3000ms);
  rig.events.clear();
  rig.run_for(30s);
  for (const auto& s : rig.bodies<NodeStateEvent>())
    EXPECT_NE(s.cause, NodeStateEvent::Cause::Lost) << "a 3000 ms producer watched with 1000 ms";
  EXPECT_GE(rig.bodies<HeartbeatEvent>().size(), 9U) << "it does produce every 3 s";
  // A write the device refuses changes nothing.
  ASSERT_TRUE(rig.write(0x1017, 1, {0x10, 0x00}));
  EXPECT_EQ(rig.net.nmt().auto_watch_period(test::NetworkRig::kNode), 3000ms);
}

// Issue 28 item 1 (CiA 302-2: the manager boots every assigned node at its
// own start, and whenever one appears without a boot-up). Devices power up
// before the gateway listens, so their boot-up goes unheard.
struct PoweredFirst : test::NetworkRig {
  static constexpr std::uint8_t kNode = test::NetworkRig::kNode;
  PoweredFirst() : NetworkRig("deploy/eds/cia401-io-module.eds") {
    (void)net.add_node(kNode, eds.od);
    gateway_listens = false;
    power_on();
    run_for(100ms);  // its boot-up: nobody listens yet
  }
  // The gateway starts: it hears what the device sends from now on.
  void gateway_starts(Duration d = 3s) {
    gateway_listens = true;
    run_for(d);
  }
  std::vector<BootConfigEvent::Step> steps() const {
    std::vector<BootConfigEvent::Step> out;
    for (const auto& b : bodies<BootConfigEvent>()) out.push_back(b.step);
    return out;
  }
  std::size_t sent_with(std::uint32_t id, std::uint8_t byte0_mask, std::uint8_t byte0) const {
    return static_cast<std::size_t>(std::count_if(sent.begin(), sent.end(), [&](const can::Frame& f) {
      return f.id == id && f.len > 0 && (f.data[0] & byte0_mask) == byte0;
    }));
  }
  std::size_t nmt_sent() const { return sent_with(0x000, 0x00, 0x00); }
  std::size_t sdo_downloads() const { return sent_with(0x600 + kNode, 0xE0, 0x20); }  // ccs 1 (7.2.4.3.3)
  std::size_t sdo_uploads() const { return sent_with(0x600 + kNode, 0xE0, 0x40); }    // ccs 2 (7.2.4.3.5)
};

TEST(Network, APreOperationalNodeHeardFirstByItsHeartbeatIsBootedAsOnABootUp_Cia302_2) {
  PoweredFirst rig;
  ASSERT_EQ(rig.device->state(), NmtState::PreOperational);
  ASSERT_TRUE(rig.net.configure_boot(PoweredFirst::kNode, master::boot_config_from_dcf(rig.eds)));
  rig.gateway_starts();
  using S = BootConfigEvent::Step;
  EXPECT_EQ(rig.steps(), (std::vector<S>{S::Identify, S::CheckIdentity, S::Configure, S::Start, S::Done}));
  EXPECT_NE(rig.bodies<BootConfigEvent>().front().detail.find("without a boot-up"), std::string::npos);
  EXPECT_GE(rig.sdo_downloads(), 1U) << "its configuration is written";
  EXPECT_EQ(rig.nmt_sent(), 1U);
  EXPECT_EQ(rig.device->state(), NmtState::Operational);
  // Heard again in the same state: nothing runs twice.
  const auto before = rig.sent.size();
  rig.run_for(5s);
  EXPECT_EQ(rig.steps().size(), 5U);
  EXPECT_EQ(rig.sent.size(), before);
}

// A running machine: the node is checked, not reconfigured or restarted.
TEST(Network, AnOperationalNodeHeardFirstIsIdentifiedAndItsPdosReadButNotWrittenOrRestarted_Cia302_2) {
  PoweredFirst rig;
  rig.device->command(NmtCommand::Start, rig.clock.now());  // started by another master, or by itself
  ASSERT_EQ(rig.device->state(), NmtState::Operational);
  ASSERT_TRUE(rig.net.configure_boot(PoweredFirst::kNode, master::boot_config_from_dcf(rig.eds), true));
  rig.gateway_starts();
  using S = BootConfigEvent::Step;
  ASSERT_EQ(rig.steps(), (std::vector<S>{S::Identify, S::CheckIdentity, S::Done}));
  const auto boots = rig.bodies<BootConfigEvent>();
  ASSERT_TRUE(boots[1].identity);
  EXPECT_EQ(boots[1].identity->vendor_id, rig.eds.od.get_unsigned(0x1018, 1).value());
  EXPECT_NE(boots.back().detail.find("already operational"), std::string::npos) << boots.back().detail;
  EXPECT_GT(rig.sdo_uploads(), 5U) << "identity and PDO configuration are read";
  EXPECT_EQ(rig.sdo_downloads(), 0U) << "nothing is written to a running node";
  EXPECT_EQ(rig.nmt_sent(), 0U) << "a running node is not reset or started";
  EXPECT_EQ(rig.device->state(), NmtState::Operational);
  bool from_device = false;
  for (const auto* p : rig.net.pdo_config().pdos(PoweredFirst::kNode))
    from_device = from_device || p->source == pdo::ConfigSource::Device;
  EXPECT_TRUE(from_device) << "the PDO mapping in use is the device's";
}

TEST(Network, AStoppedNodeOrOneWithoutBootConfigurationIsOnlyWatched_Cia302_2) {
  for (const bool configured : {true, false}) {
    PoweredFirst rig;
    if (configured) {
      rig.device->command(NmtCommand::Stop, rig.clock.now());  // no SDO in stopped (7.3.2.2)
      ASSERT_TRUE(rig.net.configure_boot(PoweredFirst::kNode, master::boot_config_from_dcf(rig.eds)));
    }
    rig.gateway_starts();
    EXPECT_TRUE(rig.bodies<BootConfigEvent>().empty()) << configured;
    EXPECT_TRUE(rig.sent.empty()) << configured;
    EXPECT_FALSE(rig.bodies<HeartbeatEvent>().empty()) << "it is watched";
  }
}

// Reset while the gateway did not hear it (cable out, power cycle): back in
// pre-operational after a loss, it is booted again.
TEST(Network, ANodeBackInPreOperationalAfterALossIsBootedAgain_Cia302_2) {
  PoweredFirst rig;
  ASSERT_TRUE(rig.net.nmt().set_auto_watch(PoweredFirst::kNode, true, nmt::producer_heartbeat_time(rig.eds.od)));
  ASSERT_TRUE(rig.net.configure_boot(PoweredFirst::kNode, master::boot_config_from_dcf(rig.eds)));
  rig.gateway_starts();
  ASSERT_EQ(rig.device->state(), NmtState::Operational);
  rig.gateway_listens = false;
  rig.run_for(5s);  // lost
  rig.power_on();   // its boot-up goes unheard
  rig.run_for(100ms);
  rig.events.clear();
  rig.gateway_starts();
  const auto states = rig.bodies<NodeStateEvent>();
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.front().cause, NodeStateEvent::Cause::Recovered);
  using S = BootConfigEvent::Step;
  EXPECT_EQ(rig.steps(), (std::vector<S>{S::Identify, S::CheckIdentity, S::Configure, S::Start, S::Done}));
  EXPECT_EQ(rig.device->state(), NmtState::Operational);
}

}  // namespace
}  // namespace canopen
