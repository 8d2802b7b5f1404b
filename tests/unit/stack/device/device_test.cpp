// canopen::Device, one test per CiA 301 rule (section in the test name),
// driven frame by frame over the in-memory bus with the fake clock.
#include "canopen/device.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/od/gateway_dictionary.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kNode = 5;

std::string source_path(const char* rel) { return std::string(CANOPEN_SOURCE_DIR) + "/" + rel; }

struct Rig {
  explicit Rig(const char* eds = "deploy/eds/cia402-drive.eds")
      : od(eds::load_device_description(source_path(eds), kNode).od) {}
  Rig(od::ObjectDictionary dictionary, std::uint8_t node) : node_id(node), od(std::move(dictionary)) {}

  void make() {
    DeviceConfig cfg;
    cfg.node_id = node_id;
    cfg.time_period = time_period;
    if (time_period > Duration::zero()) cfg.unix_ms = [] { return std::int64_t{1'700'000'000'000}; };
    dev = std::make_unique<Device>(od, cfg, [this](const can::Frame& f) { dev_ep->send(f); }, cb);
    dev_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) dev->on_frame(f, clock.now());
    });
    tester->on_frames([this](std::span<const can::Frame> fs) {
      rx.insert(rx.end(), fs.begin(), fs.end());
      rx_times.insert(rx_times.end(), fs.size(), clock.now());
    });
    dev->start(clock.now());
    bus.deliver();
  }
  void send(const can::Frame& f) {
    tester->send(f);
    bus.deliver();
  }
  void nmt(NmtCommand cs) { send(can::Frame::standard(0x000, {static_cast<std::uint8_t>(cs), node_id})); }
  // Runs the device's timers until now + d.
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      bus.deliver();
      const TimePoint next = dev->next_deadline();
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      dev->on_time(clock.now());
    }
    clock.advance_to(end);
    bus.deliver();
  }
  // Expedited SDO download; returns the server's command byte (60h ok, 80h abort).
  std::uint8_t sdo_write(std::uint16_t index, std::uint8_t sub, std::uint32_t value, unsigned size) {
    const std::uint8_t cs = size == 1 ? 0x2F : size == 2 ? 0x2B : 0x23;
    clear();
    send(can::Frame::standard(0x600U + node_id,
                              {cs, static_cast<std::uint8_t>(index), static_cast<std::uint8_t>(index >> 8), sub,
                               static_cast<std::uint8_t>(value), static_cast<std::uint8_t>(value >> 8),
                               static_cast<std::uint8_t>(value >> 16), static_cast<std::uint8_t>(value >> 24)}));
    for (const auto& f : rx)
      if (f.id == 0x580U + node_id) return f.data[0];
    return 0;
  }
  void clear() {
    rx.clear();
    rx_times.clear();
  }
  std::vector<can::Frame> frames(std::uint32_t id) const {
    std::vector<can::Frame> out;
    for (const auto& f : rx)
      if (f.id == id) out.push_back(f);
    return out;
  }
  std::uint64_t u(std::uint16_t index, std::uint8_t sub) const { return od.get_unsigned(index, sub).value_or(~0ULL); }

  std::uint8_t node_id = kNode;
  FakeClock clock;
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> dev_ep = bus.attach("device");
  std::unique_ptr<can::MemoryEndpoint> tester = bus.attach("tester");
  od::ObjectDictionary od;
  DeviceCallbacks cb;
  Duration time_period{};
  std::unique_ptr<Device> dev;
  std::vector<can::Frame> rx;
  std::vector<TimePoint> rx_times;  // receive time of each frame in rx
};

Value u16(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned16, v); }

TEST(Device, BootUp_7_2_8_3_3_StartSendsBootUpAndEntersPreOperational) {
  Rig r;
  std::vector<NmtState> states;
  r.cb.on_state_change = [&](NmtState now, NmtState) { states.push_back(now); };
  r.make();
  ASSERT_EQ(r.frames(0x705).size(), 1U);
  EXPECT_EQ(r.frames(0x705)[0].len, 1U);
  EXPECT_EQ(r.frames(0x705)[0].data[0], 0x00);
  EXPECT_EQ(r.dev->state(), NmtState::PreOperational);
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back(), NmtState::PreOperational);
}

TEST(Device, Heartbeat_7_2_8_3_2_2_ProducedEvery1017hWithTheState) {
  Rig r;
  ASSERT_FALSE(r.od.set(0x1017, 0, u16(100)));
  r.make();
  r.rx.clear();
  r.run_for(250ms);
  auto hb = r.frames(0x705);
  ASSERT_EQ(hb.size(), 2U);
  EXPECT_EQ(hb[0].data[0], 0x7F);
  r.nmt(NmtCommand::Start);
  r.rx.clear();
  r.run_for(100ms);
  ASSERT_EQ(r.frames(0x705).size(), 1U);
  EXPECT_EQ(r.frames(0x705)[0].data[0], 0x05);
}

TEST(Device, NodeControl_7_2_8_3_1_CommandsChangeStateAndAreReported) {
  Rig r;
  std::vector<NmtCommand> cmds;
  r.cb.on_nmt_command = [&](NmtCommand c) { cmds.push_back(c); };
  r.make();
  r.nmt(NmtCommand::Start);
  EXPECT_EQ(r.dev->state(), NmtState::Operational);
  r.nmt(NmtCommand::Stop);
  EXPECT_EQ(r.dev->state(), NmtState::Stopped);
  r.send(can::Frame::standard(0x000, {0x01, 0x06}));  // another node: ignored
  EXPECT_EQ(r.dev->state(), NmtState::Stopped);
  r.send(can::Frame::standard(0x000, {0x80, 0x00}));  // all nodes
  EXPECT_EQ(r.dev->state(), NmtState::PreOperational);
  EXPECT_EQ(cmds, (std::vector<NmtCommand>{NmtCommand::Start, NmtCommand::Stop, NmtCommand::EnterPreOperational}));
}

TEST(Device, ResetNode_7_2_8_3_1_RebootsWithBootUpAndCallsResetHooks) {
  Rig r;
  int app = 0, comm = 0;
  r.cb.on_reset_application = [&] { ++app; };
  r.cb.on_reset_communication = [&] { ++comm; };
  r.make();
  r.nmt(NmtCommand::Start);
  r.rx.clear();
  r.nmt(NmtCommand::ResetNode);
  EXPECT_EQ(r.frames(0x705).size(), 1U);
  EXPECT_EQ(r.dev->state(), NmtState::PreOperational);
  EXPECT_EQ(app, 2);  // power-on and the reset
  EXPECT_EQ(comm, 2);
}

TEST(Device, ResetCommunication_7_2_8_3_1_PdosRebuiltFromRestoredParameters) {
  Rig r;
  bool invalidate = false;
  // The application restores the communication area here; this one restores
  // TPDO1 as invalid, so after the reset it must be off.
  r.cb.on_reset_communication = [&] {
    if (invalidate) (void)r.od.set(0x1800, 1, Value::of_unsigned(DataType::Unsigned32, 0x80000185));
  };
  r.make();
  EXPECT_EQ(r.dev->tpdo_numbers().size(), 4U);
  invalidate = true;
  r.nmt(NmtCommand::ResetCommunication);
  EXPECT_EQ(r.frames(0x705).size(), 2U) << "boot-up after reset communication";
  EXPECT_EQ(r.dev->tpdo_numbers(), (std::vector<std::uint16_t>{2, 3, 4}));
  r.nmt(NmtCommand::Start);
  r.rx.clear();
  ASSERT_FALSE(r.dev->set(0x6041, 0, u16(0x0637), r.clock.now()));
  r.bus.deliver();
  EXPECT_TRUE(r.frames(0x185).empty());
  EXPECT_EQ(r.frames(0x285).size(), 1U) << "TPDO2 maps 6041h too";
}

TEST(Device, SdoServer_7_2_4_ServesTheDictionary) {
  Rig r;
  r.make();
  EXPECT_EQ(r.sdo_write(0x6040, 0, 0x000F, 2), 0x60);
  EXPECT_EQ(r.u(0x6040, 0), 0x000FU);
}

TEST(Device, ServicesByState_7_3_2_2_5_StoppedAnswersNoSdo) {
  Rig r;
  r.make();
  r.nmt(NmtCommand::Stop);
  EXPECT_EQ(r.sdo_write(0x6040, 0, 0x000F, 2), 0);
  EXPECT_NE(r.u(0x6040, 0), 0x000FU);
}

TEST(Device, ServicesByState_7_3_2_2_5_PdosOnlyInOperational) {
  Rig r;
  r.make();
  r.rx.clear();
  ASSERT_FALSE(r.dev->set(0x6041, 0, u16(0x0237), r.clock.now()));
  r.bus.deliver();
  EXPECT_TRUE(r.frames(0x185).empty()) << "no TPDO in pre-operational";
  r.send(can::Frame::standard(0x205, {0x06, 0x00}));
  EXPECT_NE(r.u(0x6040, 0), 6U) << "no RPDO in pre-operational";
  r.nmt(NmtCommand::Start);
  ASSERT_FALSE(r.dev->set(0x6041, 0, u16(0x0637), r.clock.now()));
  r.bus.deliver();
  ASSERT_EQ(r.frames(0x185).size(), 1U);
  EXPECT_EQ(r.frames(0x185)[0].data[0], 0x37);
  EXPECT_EQ(r.frames(0x185)[0].data[1], 0x06);
}

TEST(Device, EventDrivenTpdo_7_2_2_2_ObjectWriteByApplicationThroughDictionaryTriggersTpdo) {
  Rig r;
  r.make();
  r.nmt(NmtCommand::Start);
  r.rx.clear();
  ASSERT_FALSE(r.od.set(0x6041, 0, u16(0x0001)));  // not through the Device: observed
  EXPECT_EQ(r.dev->next_deadline(), TimePoint::min());
  r.run_for(0ms);
  EXPECT_EQ(r.frames(0x185).size(), 1U);
}

TEST(Device, PdoMapping_7_5_2_38_SdoRemapThenSdoWriteOfMappedObjectSendsTpdo) {
  Rig r;
  r.make();
  r.nmt(NmtCommand::Start);
  // The remapping sequence of 7.5.2.38: invalidate, count 0, entry, count, validate.
  EXPECT_EQ(r.sdo_write(0x1800, 1, 0x80000185, 4), 0x60);
  EXPECT_EQ(r.sdo_write(0x1A00, 0, 0, 1), 0x60);
  EXPECT_EQ(r.sdo_write(0x1A00, 1, 0x60400010, 4), 0x60);
  EXPECT_EQ(r.sdo_write(0x1A00, 0, 1, 1), 0x60);
  EXPECT_EQ(r.sdo_write(0x1800, 1, 0x185, 4), 0x60);
  EXPECT_EQ(r.sdo_write(0x6040, 0, 0x001F, 2), 0x60);
  auto tpdo = r.frames(0x185);
  ASSERT_EQ(tpdo.size(), 1U);
  EXPECT_EQ(tpdo[0].len, 2U);
  EXPECT_EQ(tpdo[0].data[0], 0x1F);
}

TEST(Device, PdoCommunication_7_5_2_37_InvalidCobIdStopsTheTpdo) {
  Rig r;
  r.make();
  r.nmt(NmtCommand::Start);
  EXPECT_EQ(r.sdo_write(0x1800, 1, 0x80000185, 4), 0x60);
  r.rx.clear();
  ASSERT_FALSE(r.dev->set(0x6041, 0, u16(7), r.clock.now()));
  r.bus.deliver();
  EXPECT_TRUE(r.frames(0x185).empty());
}

TEST(Device, EventTimer_7_5_2_37_TpdoResentEveryEventTimerWithoutEvents) {
  Rig r;
  ASSERT_FALSE(r.od.set(0x1800, 5, u16(50)));
  r.make();
  r.nmt(NmtCommand::Start);
  r.rx.clear();
  r.run_for(200ms);
  EXPECT_GE(r.frames(0x185).size(), 3U);
  EXPECT_LE(r.frames(0x185).size(), 4U);
}

TEST(Device, SynchronousTpdo_7_2_2_2_CyclicType1SentOnEverySync) {
  Rig r;  // TPDO3 of the drive: type 1
  r.make();
  r.nmt(NmtCommand::Start);
  ASSERT_FALSE(r.dev->set(0x6041, 0, u16(0x0237), r.clock.now()));
  r.rx.clear();
  r.send(can::Frame::standard(0x080, std::initializer_list<std::uint8_t>{}));
  r.send(can::Frame::standard(0x080, std::initializer_list<std::uint8_t>{}));
  ASSERT_EQ(r.frames(0x385).size(), 2U);
  EXPECT_EQ(r.frames(0x385)[0].data[0], 0x37);
}

TEST(Device, SynchronousRpdo_7_2_2_2_ActuatedAtNextSyncAndDiscardedOutsideWindow) {
  Rig r("deploy/eds/cia401-io-module.eds");
  ASSERT_FALSE(r.od.set(0x1400, 2, Value::of_unsigned(DataType::Unsigned8, 0)));  // acyclic synchronous
  ASSERT_FALSE(r.od.set(0x1007, 0, Value::of_unsigned(DataType::Unsigned32, 1000)));  // window 1 ms
  r.make();
  const auto rpdo = r.dev->rpdo_numbers();
  ASSERT_FALSE(rpdo.empty());
  r.nmt(NmtCommand::Start);
  const auto mapping = r.od.get_unsigned(0x1600, 1).value();
  const auto index = static_cast<std::uint16_t>(mapping >> 16);
  const auto sub = static_cast<std::uint8_t>(mapping >> 8);
  const auto before = r.u(index, sub);
  const std::uint8_t nv = static_cast<std::uint8_t>(before ^ 0x5A);
  r.send(can::Frame::standard(0x080, std::initializer_list<std::uint8_t>{}));
  r.send(can::Frame::standard(0x205, {nv, nv, nv, nv, nv, nv, nv, nv}));
  EXPECT_EQ(r.u(index, sub), before) << "synchronous RPDO waits for the SYNC";
  r.run_for(5ms);
  r.send(can::Frame::standard(0x080, std::initializer_list<std::uint8_t>{}));
  EXPECT_NE(r.u(index, sub), before) << "actuated at the next SYNC";
  const auto now_value = r.u(index, sub);
  r.run_for(2ms);  // window closed
  r.send(can::Frame::standard(0x205, {0, 0, 0, 0, 0, 0, 0, 0}));
  r.send(can::Frame::standard(0x080, std::initializer_list<std::uint8_t>{}));
  EXPECT_EQ(r.u(index, sub), now_value) << "received outside the window: discarded";
}

TEST(Device, Rpdo_7_2_2_ReceivedValuesWrittenToDictionaryAndReported) {
  Rig r;
  std::vector<MappedValue> got;
  r.cb.on_rpdo = [&](std::uint16_t n, std::span<const MappedValue> v) {
    EXPECT_EQ(n, 1);
    got.assign(v.begin(), v.end());
  };
  r.make();
  r.nmt(NmtCommand::Start);
  r.send(can::Frame::standard(0x205, {0x0F, 0x00}));
  EXPECT_EQ(r.u(0x6040, 0), 0x0FU);
  ASSERT_EQ(got.size(), 1U);
  EXPECT_EQ(got[0].index, 0x6040);
  EXPECT_EQ(got[0].name, "Controlword");
  EXPECT_EQ(got[0].value, u16(0x0F));
}

TEST(Device, RpdoLength_7_5_2_36_ShortRpdoIgnoredWithEmcy8210ClearedByNextGoodOne) {
  Rig r;
  r.make();
  r.nmt(NmtCommand::Start);
  r.rx.clear();
  r.send(can::Frame::standard(0x205, {0x0F}));
  EXPECT_NE(r.u(0x6040, 0), 0x0FU);
  auto emcy = r.frames(0x085);
  ASSERT_EQ(emcy.size(), 1U);
  EXPECT_EQ(emcy[0].data[0], 0x10);
  EXPECT_EQ(emcy[0].data[1], 0x82);
  EXPECT_NE(emcy[0].data[2] & emcy::error_register::kCommunication, 0);
  r.send(can::Frame::standard(0x205, {0x0F}));
  EXPECT_EQ(r.frames(0x085).size(), 1U) << "one error event, one EMCY";
  r.send(can::Frame::standard(0x205, {0x0F, 0x00}));
  EXPECT_EQ(r.u(0x6040, 0), 0x0FU);
  ASSERT_EQ(r.frames(0x085).size(), 2U);
  EXPECT_EQ(r.frames(0x085)[1].data[0], 0x00);  // error reset
  EXPECT_EQ(r.frames(0x085)[1].data[1], 0x00);
}

TEST(Device, RpdoLength_7_5_2_36_LongerRpdoUsesMappedBytesAndSignals8220) {
  Rig r;
  r.make();
  r.nmt(NmtCommand::Start);
  r.rx.clear();
  r.send(can::Frame::standard(0x205, {0x07, 0x00, 0xAA}));
  EXPECT_EQ(r.u(0x6040, 0), 0x07U);
  ASSERT_EQ(r.frames(0x085).size(), 1U);
  EXPECT_EQ(r.frames(0x085)[0].data[1], 0x82);
  EXPECT_EQ(r.frames(0x085)[0].data[0], 0x20);
}

TEST(Device, RpdoDeadline_7_5_2_35_EventTimerExpiryRaises8250AndReceptionClearsIt) {
  Rig r;
  ASSERT_FALSE(r.od.set(0x1400, 5, u16(100)));
  std::vector<std::uint16_t> timeouts;
  r.cb.on_rpdo_timeout = [&](std::uint16_t n) { timeouts.push_back(n); };
  r.make();
  r.nmt(NmtCommand::Start);
  r.run_for(500ms);
  EXPECT_TRUE(r.frames(0x085).empty()) << "monitoring starts with the first RPDO";
  r.send(can::Frame::standard(0x205, {0x01, 0x00}));
  r.rx.clear();
  r.run_for(99ms);
  EXPECT_TRUE(r.frames(0x085).empty());
  r.run_for(1ms);
  ASSERT_EQ(r.frames(0x085).size(), 1U);
  EXPECT_EQ(r.frames(0x085)[0].data[0], 0x50);
  EXPECT_EQ(r.frames(0x085)[0].data[1], 0x82);
  EXPECT_EQ(timeouts, std::vector<std::uint16_t>{1});
  r.send(can::Frame::standard(0x205, {0x02, 0x00}));
  ASSERT_EQ(r.frames(0x085).size(), 2U);
  EXPECT_EQ(r.frames(0x085)[1].data[1], 0x00);
}

TEST(Device, Emcy_7_2_7_RaiseAndResetSendEmcyFramesAndKeep1001h) {
  Rig r;
  r.make();
  r.rx.clear();
  EXPECT_TRUE(r.dev->raise_emcy(0x3210, emcy::error_register::kVoltage, r.clock.now()));
  r.bus.deliver();
  ASSERT_EQ(r.frames(0x085).size(), 1U);
  EXPECT_EQ(r.frames(0x085)[0].data[0], 0x10);
  EXPECT_EQ(r.frames(0x085)[0].data[1], 0x32);
  EXPECT_EQ(r.u(0x1001, 0), 0x05U);
  EXPECT_TRUE(r.dev->clear_emcy(0x3210, r.clock.now()));
  r.bus.deliver();
  ASSERT_EQ(r.frames(0x085).size(), 2U);
  EXPECT_EQ(r.u(0x1001, 0), 0U);
}

TEST(Device, SyncProducer_7_5_2_6_1005hBit30And1006hProduceSyncDrivingOwnSynchronousTpdos) {
  Rig r;
  std::vector<SyncEvent> syncs;
  r.cb.on_sync = [&](const SyncEvent& e) { syncs.push_back(e); };
  r.make();
  r.nmt(NmtCommand::Start);
  if (r.od.find(0x1006, 0) == nullptr)
    r.od.insert(od::make_var(0x1006, "Communication cycle period", DataType::Unsigned32, od::Access::ReadWrite,
                             Value::of_unsigned(DataType::Unsigned32, 0)));
  // Objects inserted after construction are not observed: the Device API
  // and SDO writes to 1005h pick the change up.
  ASSERT_FALSE(r.od.set(0x1006, 0, Value::of_unsigned(DataType::Unsigned32, 10000)));
  EXPECT_EQ(r.sdo_write(0x1005, 0, 0x40000080, 4), 0x60);
  r.rx.clear();
  r.run_for(35ms);
  EXPECT_EQ(r.frames(0x080).size(), 3U);
  EXPECT_EQ(r.frames(0x385).size(), 3U) << "own SYNC drives the synchronous TPDO3";
  EXPECT_EQ(syncs.size(), 3U);
}

TEST(Device, TimeProducer_7_2_6_1012hBit30SendsTimeOfDayPeriodically) {
  Rig r("deploy/eds/cia401-io-module.eds");
  ASSERT_NE(r.od.find(0x1012, 0), nullptr);
  ASSERT_FALSE(r.od.set(0x1012, 0, Value::of_unsigned(DataType::Unsigned32, 0x40000100)));
  r.time_period = 100ms;
  r.make();
  r.rx.clear();
  r.run_for(250ms);
  auto t = r.frames(0x100);
  ASSERT_EQ(t.size(), 2U);
  EXPECT_EQ(t[0].len, 6U);
}

TEST(Device, GatewayDictionary_7_2_8_3_3_TheGatewaysOwnNodeBootsAndServesSdo) {
  od::ObjectDictionary own = od::make_gateway_dictionary(127, {});
  can::MemoryBus bus;
  auto ep = bus.attach("gw");
  auto peer = bus.attach("peer");
  std::vector<can::Frame> rx;
  peer->on_frames([&](std::span<const can::Frame> fs) { rx.insert(rx.end(), fs.begin(), fs.end()); });
  FakeClock clock;
  DeviceConfig cfg;
  cfg.node_id = 127;
  Device dev(own, cfg, [&](const can::Frame& f) { ep->send(f); });
  ep->on_frames([&](std::span<const can::Frame> fs) {
    for (const auto& f : fs) dev.on_frame(f, clock.now());
  });
  dev.start(clock.now());
  bus.deliver();
  ASSERT_FALSE(rx.empty());
  EXPECT_EQ(rx[0].id, 0x77FU);
  peer->send(can::Frame::standard(0x67F, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));  // upload 1000h
  bus.deliver();
  ASSERT_EQ(rx.size(), 2U);
  EXPECT_EQ(rx[1].id, 0x5FFU);
  EXPECT_EQ(rx[1].data[0] & 0xE0, 0x40);
}

// ---- the gateway's own node: power-on values (7.3.2.2.1) -------------------------------

// The gateway's own node as the gateway sets it up: its dictionary
// configured before start() (heartbeat 100 ms from the configuration), an
// application parameter at 2100h, 1010h/1011h wired to the Device.
struct OwnNode : Rig {
  static constexpr std::uint8_t kId = 127;
  static constexpr std::uint32_t kSave = 0x65766173;  // "save", 7.5.2.13 figure 55
  static constexpr std::uint32_t kLoad = 0x64616F6C;  // "load", 7.5.2.14 figure 57
  static constexpr std::uint8_t kOk = 0x60;           // SDO download response

  OwnNode() : Rig(dictionary(this), kId) {
    od.insert(od::make_var(0x2100, "Application parameter", DataType::Unsigned16, od::Access::ReadWrite, u16(7)));
    EXPECT_FALSE(od.write(0x1017, 0, encode(u16(100))));
    make();
  }
  static od::ObjectDictionary dictionary(Rig* rig) {
    od::GatewayDictionaryOptions o;
    o.on_store = [rig](std::uint8_t sub) { return rig->dev->store_parameters(sub); };
    o.on_restore = [rig](std::uint8_t sub) { return rig->dev->restore_default_parameters(sub); };
    return od::make_gateway_dictionary(kId, {}, o);
  }
  // Spacing of the heartbeats (not boot-ups) the node sends during d.
  std::vector<Duration> heartbeat_gaps(Duration d) {
    clear();
    run_for(d);
    std::vector<Duration> gaps;
    std::optional<TimePoint> last;
    for (std::size_t i = 0; i < rx.size(); ++i) {
      if (rx[i].id != 0x700U + kId || rx[i].data[0] == 0x00) continue;
      if (last) gaps.push_back(rx_times[i] - *last);
      last = rx_times[i];
    }
    return gaps;
  }
  std::size_t count(std::uint32_t id) const { return frames(id).size(); }
};

using Gaps = std::vector<Duration>;

// Written since power-on: a slower heartbeat, a produced SYNC (1005h bit 30,
// 1006h 10 ms) and the application parameter.
void reconfigure_over_sdo(OwnNode& n) {
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1017, 0, 300, 2));
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1006, 0, 10'000, 4));
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1005, 0, 0x40000080, 4));
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x2100, 0, 42, 2));
  EXPECT_EQ(n.heartbeat_gaps(1000ms), (Gaps{300ms, 300ms}));
  EXPECT_GE(n.count(0x080), 90U) << "SYNC every 10 ms";
}

TEST(Device, OwnNode_7_3_2_2_1_ResetCommunicationSetsCommunicationParametersToPowerOnValues) {
  OwnNode n;
  EXPECT_EQ(n.heartbeat_gaps(350ms), (Gaps{100ms, 100ms}));
  reconfigure_over_sdo(n);
  n.nmt(NmtCommand::ResetCommunication);
  EXPECT_EQ(n.dev->state(), NmtState::PreOperational);
  EXPECT_EQ(n.u(0x1017, 0), 100U);
  EXPECT_EQ(n.u(0x1005, 0), 0x80U) << "SYNC producer off again";
  EXPECT_EQ(n.u(0x1006, 0), 0U);
  EXPECT_EQ(n.heartbeat_gaps(350ms), (Gaps{100ms, 100ms})) << "the heartbeat producer follows 1017h";
  EXPECT_EQ(n.count(0x080), 0U);
  EXPECT_EQ(n.u(0x2100, 0), 42U) << "reset communication leaves the application area alone";
}

TEST(Device, OwnNode_7_3_2_2_1_ResetNodeAlsoSetsTheApplicationAreaToPowerOnValues) {
  OwnNode n;
  reconfigure_over_sdo(n);
  n.nmt(NmtCommand::ResetNode);
  EXPECT_EQ(n.u(0x1017, 0), 100U);
  EXPECT_EQ(n.u(0x1005, 0), 0x80U);
  EXPECT_EQ(n.u(0x2100, 0), 7U);
  EXPECT_EQ(n.heartbeat_gaps(350ms), (Gaps{100ms, 100ms}));
  EXPECT_EQ(n.count(0x080), 0U);
}

TEST(Device, OwnNode_7_5_2_13_SavedValuesAreThePowerOnValuesUntil1011hLoadAndAReset) {
  OwnNode n;
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1017, 0, 300, 2));
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1010, 2, OwnNode::kSave, 4));  // save communication parameters
  n.nmt(NmtCommand::ResetCommunication);
  EXPECT_EQ(n.u(0x1017, 0), 300U);
  EXPECT_EQ(n.heartbeat_gaps(700ms), (Gaps{300ms}));
  // 7.5.2.14: the defaults take effect at the next reset, not at once.
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1011, 2, OwnNode::kLoad, 4));
  EXPECT_EQ(n.u(0x1017, 0), 300U);
  n.nmt(NmtCommand::ResetCommunication);
  EXPECT_EQ(n.u(0x1017, 0), 100U);
  EXPECT_EQ(n.heartbeat_gaps(350ms), (Gaps{100ms, 100ms}));
  // Group 3 (application) saved alone leaves the communication area at its power-on values.
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x2100, 0, 42, 2));
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1017, 0, 300, 2));
  ASSERT_EQ(OwnNode::kOk, n.sdo_write(0x1010, 3, OwnNode::kSave, 4));
  n.nmt(NmtCommand::ResetNode);
  EXPECT_EQ(n.u(0x2100, 0), 42U);
  EXPECT_EQ(n.u(0x1017, 0), 100U);
}

TEST(Device, Lifetime_DictionaryOutlivesDevice_ObserversDisarmed) {
  Rig r;
  r.make();
  r.dev.reset();
  EXPECT_FALSE(r.od.set(0x6041, 0, u16(1)));  // observer must not touch the destroyed device
}

}  // namespace
}  // namespace canopen
