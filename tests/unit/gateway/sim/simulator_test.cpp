// The simulator (gateway/sim): a simulated CiA 402 drive on an AsioMemoryBus,
// with canopen::Network on the other side driven by a ServiceDriver, all in
// one io_context run for a bounded time.
#include "sim/simulator.hpp"

#include <gtest/gtest.h>

#include <set>
#include <variant>
#include <vector>

#include "canopen/network.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/socketcan/service_driver.hpp"
#include "sim/asio_memory_bus.hpp"
#include "sim/device_objects.hpp"

namespace canopen::sim {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kDrive = 5;
constexpr std::uint8_t kIo = 10;

std::string source_path(const char* rel) { return std::string(CANOPEN_SOURCE_DIR) + "/" + rel; }

struct Bench {
  explicit Bench(SimulatorOptions opt) : sim(io, *sim_ch, opt, [this](std::string_view l) { lines.emplace_back(l); }) {
    driver.add(net);
  }
  boost::asio::io_context io;
  AsioMemoryBus bus{io};
  std::unique_ptr<AsioMemoryChannel> gw_ch = bus.attach("gateway");
  std::unique_ptr<AsioMemoryChannel> sim_ch = bus.attach("sim");
  od::ObjectDictionary own = od::make_gateway_dictionary(127, {});
  std::vector<Event> events;
  Network net{own, [this](const can::Frame& f) { gw_ch->send(f); }, [this](const Event& e) { on_event(e); }};
  socketcan::ServiceDriver driver{io, *gw_ch};
  std::vector<std::string> lines;
  Simulator sim;
  bool started = false;

  void on_event(const Event& e) {
    events.push_back(e);
    if (const auto* s = std::get_if<NodeStateEvent>(&e.body); s && s->cause == NodeStateEvent::Cause::BootUp) {
      // Start every node once the last one has booted (NMT start, 7.2.8.3.1).
      if (!started && s->node == kIo) {
        started = true;
        net.nmt().send_command(NmtCommand::Start, 0);
      }
    }
  }
  template <typename T>
  std::vector<const T*> of() const {
    std::vector<const T*> out;
    for (const auto& e : events)
      if (const auto* b = std::get_if<T>(&e.body)) out.push_back(b);
    return out;
  }
};

TEST(Simulator, DriveAndIoModule_BootHeartbeatAndAfterNmtStartChangingTpdoValuesByName) {
  SimulatorOptions opt;
  opt.heartbeat = 50ms;
  opt.tpdo_period = 20ms;
  opt.sync_period = 25ms;  // the drive's TPDO3/4 are synchronous
  Bench b(opt);
  b.sim.add_node(kDrive, source_path("deploy/eds/cia402-drive.eds"));
  b.sim.add_node(kIo, source_path("deploy/eds/cia401-io-module.eds"));
  auto drive = eds::load_device_description(source_path("deploy/eds/cia402-drive.eds"), kDrive);
  auto io_module = eds::load_device_description(source_path("deploy/eds/cia401-io-module.eds"), kIo);
  EXPECT_TRUE(b.net.add_node(kDrive, drive.od).empty());
  EXPECT_TRUE(b.net.add_node(kIo, io_module.od).empty());
  b.sim.start();
  b.io.run_for(1200ms);  // bounded: the simulator never stops by itself
  b.sim.stop();

  std::set<std::uint8_t> booted;
  bool drive_operational = false;
  for (const auto* s : b.of<NodeStateEvent>()) {
    if (s->cause == NodeStateEvent::Cause::BootUp) booted.insert(s->node);
    drive_operational = drive_operational || (s->node == kDrive && s->state == NmtState::Operational);
  }
  EXPECT_EQ(booted, (std::set<std::uint8_t>{kDrive, kIo}));
  EXPECT_TRUE(drive_operational);
  std::size_t drive_heartbeats = 0;
  for (const auto* h : b.of<HeartbeatEvent>()) drive_heartbeats += h->node == kDrive ? 1U : 0U;
  EXPECT_GE(drive_heartbeats, 10U) << "50 ms heartbeat over ~1.2 s";

  std::set<std::int64_t> positions;
  std::set<std::uint64_t> digital;
  for (const auto* p : b.of<PdoEvent>()) {
    for (const auto& v : p->values) {
      if (p->node == kDrive && v.name == "Position actual value") positions.insert(std::get<std::int64_t>(v.value.data));
      if (p->node == kIo && v.index == 0x6000) digital.insert(std::get<std::uint64_t>(v.value.data));
    }
  }
  EXPECT_GE(positions.size(), 3U) << "the drive's position changes";
  EXPECT_GE(digital.size(), 2U) << "the I/O module's digital inputs toggle";
  EXPECT_FALSE(b.lines.empty());
  EXPECT_NE(std::find(b.lines.begin(), b.lines.end(), "node 5 state operational"), b.lines.end());
}

TEST(Simulator, EmcyOnCommandAndPeriodic_ReachTheMasterWithTheStandardsText) {
  SimulatorOptions opt;
  opt.emcy_period = 100ms;
  opt.auto_start = true;
  Bench b(opt);
  b.sim.add_node(kDrive, source_path("deploy/eds/cia402-drive.eds"));
  b.sim.start();
  b.io.run_for(50ms);
  EXPECT_TRUE(b.sim.raise_emcy(kDrive, 0x8110));
  b.io.run_for(500ms);  // the first periodic EMCY is due at 100 ms; slack for loaded machines
  b.sim.stop();
  std::set<std::uint16_t> codes;
  for (const auto* e : b.of<EmcyEvent>()) codes.insert(e->error_code);
  EXPECT_TRUE(codes.contains(0x8110));
  EXPECT_TRUE(codes.contains(0x3210));
  EXPECT_NE(std::find(b.lines.begin(), b.lines.end(), "node 5 emcy 8110"), b.lines.end());
  EXPECT_EQ(b.sim.device(kDrive)->state(), NmtState::Operational) << "--auto-start";
}

TEST(Simulator, ResetNode_RebootsWithBootUpAndRestoresHeartbeat) {
  SimulatorOptions opt;
  opt.heartbeat = 40ms;
  opt.auto_start = false;
  Bench b(opt);
  b.sim.add_node(kDrive, source_path("deploy/eds/cia402-drive.eds"));
  b.sim.start();
  b.io.run_for(100ms);
  b.net.nmt().send_command(NmtCommand::ResetNode, kDrive);
  b.io.run_for(200ms);
  b.sim.stop();
  std::size_t boots = 0;
  for (const auto* s : b.of<NodeStateEvent>()) boots += s->cause == NodeStateEvent::Cause::BootUp ? 1U : 0U;
  EXPECT_EQ(boots, 2U);
  EXPECT_EQ(b.sim.device(kDrive)->dictionary().get_unsigned(0x1017, 0), 40U);
}

// Runs the io_context in slices until `done` or 10 s passed (bounded: the
// simulator never stops by itself).
template <typename Pred>
bool run_until(boost::asio::io_context& io, Pred done) {
  for (int i = 0; i < 1000 && !done(); ++i) io.run_for(10ms);
  return done();
}

std::vector<std::uint8_t> booted(const Bench& b) {
  std::vector<std::uint8_t> out;
  for (const auto* s : b.of<NodeStateEvent>())
    if (s->cause == NodeStateEvent::Cause::BootUp) out.push_back(s->node);
  return out;
}

// Issue 16 item 4, CiA 305: a device that starts unconfigured says nothing
// but LSS; assign-all gives it a node-ID, it boots with it and is a node
// like any other (facts C.4 item 1).
TEST(Simulator, UnconfiguredDeviceIsSilentUntilLssGivesItANodeIdThenBoots_Cia305) {
  SimulatorOptions opt;
  opt.heartbeat = 50ms;
  Bench b(opt);
  b.sim.add_node(kDrive, source_path("deploy/eds/cia402-drive.eds"));
  b.sim.add_unconfigured_node(source_path("deploy/eds/cia401-io-module.eds"));
  EXPECT_EQ(b.sim.size(), 1U);
  EXPECT_EQ(b.sim.unconfigured(), 1U);
  // Short step windows: the in-process bus answers within the io_context's turn.
  b.net.lss().set_config({.timeout = 200ms, .scan_step_timeout = 5ms, .queue_limit = 16, .fastscan_restarts = 2});
  b.sim.start();
  b.io.run_for(200ms);
  EXPECT_EQ(booted(b), std::vector<std::uint8_t>{kDrive}) << "no boot-up from the unconfigured device";

  std::optional<Result<bool>> nonconf;
  ASSERT_FALSE(b.net.lss().identify_non_configured([&](Result<bool> r) { nonconf.emplace(std::move(r)); },
                                                   SteadyClock::now()));
  ASSERT_TRUE(run_until(b.io, [&] { return nonconf.has_value(); }));
  EXPECT_TRUE(nonconf->value());

  std::optional<lss::AssignAllResult> got;
  lss::AssignAllRequest req;
  req.first_node_id = 20;
  ASSERT_FALSE(b.net.lss().assign_all(req, [&](const lss::AssignAllResult& r) { got = r; }, SteadyClock::now()));
  ASSERT_TRUE(run_until(b.io, [&] { return got.has_value() && b.sim.device(20) != nullptr; }));
  ASSERT_FALSE(got->error) << got->error.message();
  ASSERT_EQ(got->assigned.size(), 1U);
  EXPECT_EQ(got->assigned[0].node_id, 20);
  // The IO module's 1018h, with the simulator's serial for the first unconfigured device.
  EXPECT_EQ(got->assigned[0].identity, (lss::Identity{0x5A1, 0x8822, 0x00010003, 0x55000001}));
  ASSERT_TRUE(run_until(b.io, [&] { return booted(b).size() == 2; }));
  EXPECT_EQ(booted(b), (std::vector<std::uint8_t>{kDrive, 20}));
  EXPECT_EQ(b.sim.unconfigured(), 0U);
  EXPECT_EQ(b.sim.size(), 2U);
  // Its 1018h sub 4 is its LSS serial; its SDO server answers at its new node-ID.
  std::optional<sdo::TransferResult> serial;
  sdo::Request rq;
  rq.node = 20;
  rq.index = 0x1018;
  rq.sub = 4;
  rq.on_done = [&](sdo::TransferResult&& r) { serial.emplace(std::move(r)); };
  ASSERT_TRUE(b.net.sdo().upload(std::move(rq), SteadyClock::now()).ok());
  ASSERT_TRUE(run_until(b.io, [&] { return serial.has_value(); }));
  ASSERT_TRUE(serial->ok());
  EXPECT_EQ(serial->data, (Bytes{0x01, 0x00, 0x00, 0x55}));
  b.sim.stop();
}

// CiA 305 / facts D.8: a configured device takes a new node-ID only at its
// next NMT reset communication, and then boots with it.
TEST(Simulator, ConfiguredDeviceTakesLssNodeIdAtResetCommunication_Cia305) {
  SimulatorOptions opt;
  opt.heartbeat = 50ms;
  Bench b(opt);
  b.sim.add_node(kDrive, source_path("deploy/eds/cia402-drive.eds"));
  b.sim.start();
  b.io.run_for(100ms);
  ASSERT_NE(b.sim.lss(kDrive), nullptr);
  const lss::Identity id = b.sim.lss(kDrive)->identity();
  EXPECT_EQ(id.serial, 0x53000000U + kDrive) << "EDS serial 0: the simulator's, unique per node";
  int step = 0;
  std::error_code failed;
  auto next = [&](auto r) {
    if (!r.ok()) failed = r.code();
    ++step;
  };
  auto& lss = b.net.lss();
  ASSERT_FALSE(lss.switch_state_selective(id, [&](Result<lss::Ack> r) { next(r); }, SteadyClock::now()));
  std::optional<std::uint8_t> inquired;
  ASSERT_FALSE(lss.inquire_node_id(
      [&](Result<std::uint8_t> r) {
        if (r.ok()) inquired = r.value();
        next(r);
      },
      SteadyClock::now()));
  ASSERT_FALSE(lss.configure_node_id(7, [&](Result<lss::Ack> r) { next(r); }, SteadyClock::now()));
  ASSERT_FALSE(lss.switch_state_global(lss::Mode::Waiting, [&](Result<lss::Ack> r) { next(r); }, SteadyClock::now()));
  ASSERT_TRUE(run_until(b.io, [&] { return step == 4; }));
  ASSERT_FALSE(failed) << failed.message();
  EXPECT_EQ(inquired, kDrive);
  b.io.run_for(100ms);
  EXPECT_NE(b.sim.device(kDrive), nullptr) << "still node 5 until reset communication";
  b.net.nmt().send_command(NmtCommand::ResetCommunication, kDrive);
  ASSERT_TRUE(run_until(b.io, [&] { return b.sim.device(7) != nullptr && booted(b).size() == 2; }));
  EXPECT_EQ(booted(b), (std::vector<std::uint8_t>{kDrive, 7})) << "no second boot-up as node 5";
  EXPECT_EQ(b.sim.device(kDrive), nullptr);
  b.sim.stop();
}

// One SDO transfer through the gateway's client, run until it completes.
sdo::TransferResult transfer(Bench& b, std::uint8_t node, std::uint16_t index, std::uint8_t sub,
                             std::optional<Bytes> data) {
  std::optional<sdo::TransferResult> got;
  sdo::Request rq;
  rq.node = node;
  rq.index = index;
  rq.sub = sub;
  rq.on_done = [&](sdo::TransferResult&& r) { got.emplace(std::move(r)); };
  const auto id = data ? b.net.sdo().download(std::move(rq), *data, SteadyClock::now())
                       : b.net.sdo().upload(std::move(rq), SteadyClock::now());
  EXPECT_TRUE(id.ok());
  EXPECT_TRUE(run_until(b.io, [&] { return got.has_value(); }));
  return got.value_or(sdo::TransferResult{});
}

Bytes le32(std::uint32_t v) { return encode(Value::of_unsigned(DataType::Unsigned32, v)); }

// CiA 301 7.5.2.13/14 on a simulated device: "save" keeps a changed value
// across reset node; "load" brings the EDS default back at the next reset;
// another value is refused with 08000020h; reading 1010h sub 1 says "on command".
TEST(Simulator, StoreAndRestore_1010hSave1011hLoad_ValuesAcrossResetNode) {
  SimulatorOptions opt;
  opt.tpdo_period = 0ms;
  Bench b(opt);
  b.sim.add_node(kIo, source_path("deploy/eds/cia401-io-module.eds"));
  b.sim.start();
  ASSERT_TRUE(run_until(b.io, [&] { return booted(b).size() == 1; }));
  const auto eds_default = b.sim.device(kIo)->dictionary().get_unsigned(0x2002, 0);
  auto filter_time = [&] {
    const auto r = transfer(b, kIo, 0x2002, 0, std::nullopt);
    return r.ok() ? decode(DataType::Unsigned16, r.data).value() : Value{};
  };
  auto reset = [&](std::size_t boots) {
    b.net.send_nmt(NmtCommand::ResetNode, kIo);
    ASSERT_TRUE(run_until(b.io, [&] { return booted(b).size() == boots; }));
  };
  EXPECT_EQ(transfer(b, kIo, 0x1010, 1, std::nullopt).data, le32(1)) << "stores on command";
  ASSERT_TRUE(transfer(b, kIo, 0x2002, 0, Bytes{99, 0}).ok());
  EXPECT_EQ(transfer(b, kIo, 0x1010, 1, le32(0x12345678)).error, SdoAbort::CannotStore);
  ASSERT_TRUE(transfer(b, kIo, 0x1010, 1, le32(0x65766173)).ok());  // "save"
  reset(2);
  EXPECT_EQ(filter_time(), Value::of_unsigned(DataType::Unsigned16, 99)) << "kept across reset node";
  ASSERT_TRUE(transfer(b, kIo, 0x1011, 1, le32(0x64616F6C)).ok());  // "load"
  EXPECT_EQ(filter_time(), Value::of_unsigned(DataType::Unsigned16, 99)) << "7.5.2.14: at the next reset";
  reset(3);
  EXPECT_EQ(filter_time(), Value::of_unsigned(DataType::Unsigned16, eds_default.value_or(0))) << "the EDS default";
  b.sim.stop();
}

// CiA 302-3 on a simulated device: a program downloaded to 1F50h and
// started survives reset node; 1F56h identifies it.
TEST(Simulator, ProgramDownloadObjects_ImageKeptAcrossResetNode) {
  SimulatorOptions opt;
  opt.tpdo_period = 0ms;
  Bench b(opt);
  b.sim.add_node(kIo, source_path("deploy/eds/cia401-io-module.eds"));
  b.sim.start();
  ASSERT_TRUE(run_until(b.io, [&] { return booted(b).size() == 1; }));
  const Bytes image{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  ASSERT_TRUE(transfer(b, kIo, 0x1F51, 1, Bytes{3}).ok());  // clear
  ASSERT_TRUE(transfer(b, kIo, 0x1F50, 1, image).ok());
  ASSERT_TRUE(transfer(b, kIo, 0x1F51, 1, Bytes{1}).ok());  // start
  b.net.send_nmt(NmtCommand::ResetNode, kIo);
  ASSERT_TRUE(run_until(b.io, [&] { return booted(b).size() == 2; }));
  EXPECT_EQ(transfer(b, kIo, 0x1F56, 1, std::nullopt).data, le32(program_identification(image)));
  EXPECT_EQ(transfer(b, kIo, 0x1F51, 1, std::nullopt).data, Bytes{1}) << "still running";
  b.sim.stop();
}

}  // namespace
}  // namespace canopen::sim
