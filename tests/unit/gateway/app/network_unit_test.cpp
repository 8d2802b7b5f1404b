// NetworkUnit (gateway/app/network_unit.cpp): one network's channel, own
// node (LocalNode), master side and driver wired together; here on the
// simulated bus with its devices not started, a watcher on the bus.
#include "app/network_unit.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "app/composition.hpp"
#include "sim/asio_memory_bus.hpp"

namespace gateway {
namespace {

using namespace std::chrono_literals;

struct UnitRig {
  UnitRig() {
    CliOptions cli;
    cli.demo = true;
    composition = compose_networks(io, merge(Config{}, cli), log);
    unit = composition.units.at(0).get();
    watcher = unit->link.memory_bus->bus().attach("watcher");
    watcher->on_frames([this](std::span<const canopen::can::Frame> fs) { seen.insert(seen.end(), fs.begin(), fs.end()); });
    unit->on_event = [this](const canopen::Event& ev) { events.push_back(ev); };
  }
  template <typename Pred>
  bool run_until(Pred pred) {
    const auto end = std::chrono::steady_clock::now() + 5s;
    while (!pred() && std::chrono::steady_clock::now() < end) {
      io.restart();
      io.run_for(5ms);
    }
    return pred();
  }
  template <typename T>
  const T* find_event() const {
    for (const auto& ev : events)
      if (const auto* b = std::get_if<T>(&ev.body)) return b;
    return nullptr;
  }

  boost::asio::io_context io;
  Logger log{LogLevel::Error};
  Composition composition;
  NetworkUnit* unit = nullptr;
  std::unique_ptr<canopen::can::MemoryEndpoint> watcher;
  std::vector<canopen::can::Frame> seen;
  std::vector<canopen::Event> events;
};

// Issue 28 item 4, CiA 301 7.5.2.1 and 7.5.2.20: masters and tools (an
// LSS inquiry, python-canopen, a PLC's scan) tell the gateway's own node
// apart by 1000h and 1018h: a device type, the configured vendor-ID and a
// serial unique per machine, product code and revision from the program.
TEST(NetworkUnit, TheOwnNodeHasADeviceTypeAndAnIdentity_7_5_2_20) {
  UnitRig r;
  const auto& od = *r.unit->own_od;
  EXPECT_EQ(od.get_unsigned(0x1000, 0), 309U) << "profile 309: access from other networks";
  EXPECT_EQ(od.get_unsigned(0x1018, 0), 4U);
  EXPECT_EQ(od.get_unsigned(0x1018, 1), 0U) << "no vendor-ID configured";
  EXPECT_EQ(od.get_unsigned(0x1018, 2), kOwnProductCode);
  EXPECT_EQ(od.get_unsigned(0x1018, 3), own_identity({}, CANOPEN_GATEWAY_VERSION).revision);
  const auto serial = od.get_unsigned(0x1018, 4);
  ASSERT_TRUE(serial.has_value());
  EXPECT_EQ(*serial, *r.unit->cfg.identity.serial) << "merge() gave the default";
  EXPECT_NE(*serial, 0U) << "from the machine id (or the gateway id)";

  const auto id = own_identity(OwnIdentity{0x00020191, 0x000004A2, 0x12345678}, "2.7.1");
  EXPECT_EQ(id.device_type, 0x00020191U);
  EXPECT_EQ(id.vendor_id, 0x000004A2U);
  EXPECT_EQ(id.serial, 0x12345678U);
  EXPECT_EQ(id.revision, 0x00020007U) << "major 2 (CANopen behaviour), minor 7";
  EXPECT_EQ(id.software_version, "2.7.1");
  EXPECT_EQ(own_identity({}, "not a version").revision, 0U);
}

TEST(NetworkUnit, TheSyncRequestGoesOutWith1005hAndTheMasterSideHearsIt) {
  UnitRig r;
  r.unit->local->start(NetworkUnit::now());
  auto write_1005 = [&](std::uint32_t v) {
    return r.unit->own_od->write(0x1005, 0, canopen::encode(canopen::Value::of_unsigned(canopen::DataType::Unsigned32, v)));
  };
  // 7.5.2.5: the CAN-ID changes only while the node does not generate SYNC.
  ASSERT_FALSE(write_1005(0x80));
  ASSERT_FALSE(write_1005(0x81));
  r.unit->local->send_sync(3);
  ASSERT_TRUE(r.run_until([&] { return r.find_event<canopen::SyncEvent>() != nullptr; }))
      << "the master side's SYNC consumer (synchronous RPDOs) sees the gateway's own SYNC";
  EXPECT_EQ(r.find_event<canopen::SyncEvent>()->counter, std::optional<std::uint8_t>(3));
  ASSERT_TRUE(r.run_until([&] {
    return std::any_of(r.seen.begin(), r.seen.end(), [](const auto& f) { return f.id == 0x81; });
  })) << "on the bus with the COB-ID of 1005h (7.5.2.5)";
}

TEST(NetworkUnit, ALostGuardedNodeRaisesTheOwnNodes8130hWithoutAnyManualRearm) {
  UnitRig r;
  r.unit->local->start(NetworkUnit::now());
  // Node 42 does not exist: guarding (7.2.8.3.2.1) loses it after 2 x 10 ms.
  ASSERT_TRUE(r.unit->network->nmt().set_node_guarding(42, 10ms, 2, NetworkUnit::now()));
  const std::uint32_t own_emcy = 0x80U + r.unit->cfg.node_id;
  ASSERT_TRUE(r.run_until([&] {
    return std::any_of(r.seen.begin(), r.seen.end(), [&](const auto& f) {
      return f.id == own_emcy && f.data[0] == 0x30 && f.data[1] == 0x81;
    });
  })) << "8130h life guard error on the bus (7.2.7.1)";
  ASSERT_TRUE(r.run_until([&] {
    const auto* e = r.find_event<canopen::EmcyEvent>();
    return e != nullptr && e->node == r.unit->cfg.node_id && e->error_code == canopen::kEmcyLifeGuardOrHeartbeat;
  })) << "and in the network's stream, like any node's EMCY";
}

TEST(NetworkUnit, AnNmtCommandToAllNodesReachesTheOwnNode) {
  UnitRig r;
  r.unit->local->start(NetworkUnit::now());
  ASSERT_EQ(r.unit->local->state(), canopen::NmtState::PreOperational);
  r.unit->network->send_nmt(canopen::NmtCommand::Start, 0);
  ASSERT_TRUE(r.run_until([&] { return r.unit->local->state() == canopen::NmtState::Operational; }))
      << "7.2.8.3.1: node-ID 0 addresses every node, the gateway's own too";
}

// Issue 28 item 1, CiA 302-2: the manager may reset the communication of
// its nodes at its own start so that each boots (and is configured) again;
// one by one, so that a device the gateway does not manage is never reset.
TEST(NetworkUnit, BootAtStartResetCommunicationResetsEachBootNodeAndNoOther) {
  UnitRig r;
  ASSERT_GE(r.unit->cfg.nodes.size(), 2U);
  r.unit->cfg.nodes[0].boot = BootConfig{};
  r.unit->cfg.nodes[1].boot.reset();
  std::vector<std::uint8_t> with_boot;
  for (const auto& n : r.unit->cfg.nodes)
    if (n.boot) with_boot.push_back(n.id);
  const auto nmt_frames = [&] {
    std::vector<canopen::can::Frame> out;
    for (const auto& f : r.seen)
      if (f.id == 0x000) out.push_back(f);
    return out;
  };

  r.unit->boot_at_start();  // as-found, the default: nothing
  r.io.restart();
  r.io.run_for(20ms);
  EXPECT_TRUE(nmt_frames().empty()) << "as-found sends no NMT";

  r.unit->cfg.boot_at_start = NetworkConfig::BootAtStart::ResetCommunication;
  r.unit->boot_at_start();
  ASSERT_TRUE(r.run_until([&] { return !nmt_frames().empty(); }));
  r.io.restart();
  r.io.run_for(20ms);
  const auto sent = nmt_frames();
  std::vector<std::uint8_t> reset;
  for (const auto& f : sent) {
    EXPECT_EQ(f.len, 2);
    EXPECT_EQ(f.data[0], 0x82) << "reset communication (7.2.8.3.1)";
    reset.push_back(f.data[1]);
  }
  EXPECT_EQ(reset, with_boot) << "each node with boot:, addressed one by one, never node 0; node "
                              << static_cast<int>(r.unit->cfg.nodes[1].id) << " (no boot:) left alone";
}

}  // namespace
}  // namespace gateway
