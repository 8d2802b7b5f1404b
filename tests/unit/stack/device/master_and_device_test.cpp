// Our master (canopen::Network, BootConfigurator, a master-side
// PdoTransmitter) against our Device over the in-memory bus with the fake
// clock: the whole life of a node as CiA 301 describes it.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/device.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/network.hpp"
#include "canopen/master/boot_configurator.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/pdo/transmitter.hpp"

namespace canopen {
namespace {

using namespace std::chrono_literals;
constexpr std::uint8_t kNode = 5;
constexpr std::uint32_t kSerial = 0x00012345;  // the DCF names this device

std::string source_path(const char* rel) { return std::string(CANOPEN_SOURCE_DIR) + "/" + rel; }

struct Seen {
  Event event;
  TimePoint at;  // fake-clock time the master reported it
};

struct MasterAndDevice {
  MasterAndDevice()
      : device_od(eds::load_device_description(source_path("deploy/eds/cia402-drive.eds"), kNode).od),
        dcf(eds::load_device_description(source_path("tests/support/eds/cia402-drive-node5.dcf"))) {
    EXPECT_FALSE(device_od.set(0x1018, 4, Value::of_unsigned(DataType::Unsigned32, kSerial)));
    DeviceConfig cfg;
    cfg.node_id = kNode;
    device = std::make_unique<Device>(device_od, cfg, [this](const can::Frame& f) { dev_ep->send(f); });
    dev_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) device->on_frame(f, clock.now());
    });
    net = std::make_unique<Network>(
        own, [this](const can::Frame& f) { gw_ep->send(f); },
        [this](const Event& e) {
          seen.push_back({e, clock.now()});
          if (const auto* n = std::get_if<NodeStateEvent>(&e.body);
              n && n->cause == NodeStateEvent::Cause::BootUp && boot) {
            boot->on_boot_up(n->node, clock.now());
          }
        });
    gw_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) net->on_frame(f, clock.now());
    });
    boot = std::make_unique<master::BootConfigurator>(
        net->sdo(), [this](NmtCommand cs, std::uint8_t node) { net->nmt().send_command(cs, node); },
        [this](const BootConfigEvent& e) { steps.push_back(e.step); }, [this] { return clock.now(); });
  }

  TimePoint next_deadline() const {
    return std::min({net->next_deadline(), device->next_deadline(), rpdo.next_deadline()});
  }
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      bus.deliver();
      const TimePoint next = next_deadline();
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      if (net->next_deadline() <= clock.now()) net->on_time(clock.now());
      if (device->next_deadline() <= clock.now()) device->on_time(clock.now());
      if (rpdo.next_deadline() <= clock.now()) rpdo.on_time(clock.now());
    }
    clock.advance_to(end);
    bus.deliver();
  }
  template <typename T>
  std::vector<std::pair<const T*, TimePoint>> of() const {
    std::vector<std::pair<const T*, TimePoint>> out;
    for (const auto& s : seen)
      if (const auto* b = std::get_if<T>(&s.event.body)) out.emplace_back(b, s.at);
    return out;
  }
  std::optional<NmtState> last_state() const {
    auto states = of<NodeStateEvent>();
    if (states.empty()) return std::nullopt;
    return states.back().first->state;
  }

  FakeClock clock;
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> gw_ep = bus.attach("gateway");
  std::unique_ptr<can::MemoryEndpoint> dev_ep = bus.attach("device");
  od::ObjectDictionary own = od::make_gateway_dictionary(127, {});
  od::ObjectDictionary device_od;
  eds::DeviceDescription dcf;
  std::unique_ptr<Device> device;
  std::unique_ptr<Network> net;
  std::unique_ptr<master::BootConfigurator> boot;
  pdo::PdoTransmitter rpdo{[this](const can::Frame& f) { gw_ep->send(f); }};
  std::vector<Seen> seen;
  std::vector<BootConfigEvent::Step> steps;
};

TEST(MasterAndDevice, MasterAndDevice_7_2_2_BootConfigureStartPdoBothWaysLossAtConsumerTimeAndRecovery) {
  MasterAndDevice m;
  ASSERT_TRUE(m.net->add_node(kNode, m.dcf.od).empty());
  ASSERT_TRUE(m.boot->configure(kNode, master::boot_config_from_dcf(m.dcf)));
  ASSERT_TRUE(m.net->nmt().set_heartbeat_consumer(kNode, 250ms));

  // Boot-up (7.2.8.3.3) starts the configuration from the DCF and the NMT start.
  m.device->start(m.clock.now());
  m.run_for(2s);
  ASSERT_FALSE(m.steps.empty());
  EXPECT_EQ(m.steps.back(), BootConfigEvent::Step::Done);
  EXPECT_EQ(m.device->state(), NmtState::Operational);
  EXPECT_EQ(m.last_state(), NmtState::Operational) << "heartbeat shows operational";
  EXPECT_EQ(m.device_od.get_unsigned(0x1017, 0), 100U) << "DCF heartbeat time written";
  EXPECT_EQ(m.device_od.get_unsigned(0x1A01, 2), 0x60770010U) << "DCF remapping of TPDO2 written";
  EXPECT_TRUE(m.device->pdo_errors().empty());

  // Device -> master: the device's TPDO1 (6041h Statusword), decoded by name.
  const std::size_t pdo_before = m.of<PdoEvent>().size();
  ASSERT_FALSE(m.device->set(0x6041, 0, Value::of_unsigned(DataType::Unsigned16, 0x0637), m.clock.now()));
  m.run_for(1ms);
  bool statusword = false;
  const auto pdos = m.of<PdoEvent>();
  for (std::size_t i = pdo_before; i < pdos.size(); ++i) {
    const PdoEvent& p = *pdos[i].first;
    if (p.node != kNode || p.number != 1) continue;
    ASSERT_EQ(p.values.size(), 1U);
    EXPECT_EQ(p.values[0].name, "Statusword");
    statusword = statusword || p.values[0].value == Value::of_unsigned(DataType::Unsigned16, 0x0637);
  }
  EXPECT_TRUE(statusword) << "TPDO1 with the new statusword decoded";
  // TPDO2 with the DCF's remapping: 6077h Torque actual value, by name.
  ASSERT_FALSE(m.device->set(0x6077, 0, Value::of_signed(DataType::Integer16, -42), m.clock.now()));
  m.run_for(1ms);
  const PdoEvent& last = *m.of<PdoEvent>().back().first;
  EXPECT_EQ(last.number, 2);
  ASSERT_EQ(last.values.size(), 2U);
  EXPECT_EQ(last.values[1].index, 0x6077);
  EXPECT_EQ(last.values[1].value, Value::of_signed(DataType::Integer16, -42));

  // Master -> device: RPDO1 (6040h Controlword) from the device's description.
  ASSERT_TRUE(m.rpdo.add_rpdo(kNode, 1, m.dcf.od, m.clock.now()));
  ASSERT_FALSE(m.rpdo.set_value(kNode, 1, 0x6040, 0, Value::of_unsigned(DataType::Unsigned16, 0x000F), m.clock.now()));
  m.run_for(1ms);
  EXPECT_EQ(m.device_od.get_unsigned(0x6040, 0), 0x000FU);

  // Node loss: the device falls silent; lost exactly 250 ms after its last heartbeat.
  m.run_for(37ms);  // somewhere between heartbeats
  TimePoint last_heartbeat{};
  for (const auto& [h, at] : m.of<HeartbeatEvent>())
    if (h->node == kNode) last_heartbeat = at;
  m.dev_ep->set_link_up(false);
  m.run_for(1s);
  std::optional<TimePoint> lost_at;
  for (const auto& [s, at] : m.of<NodeStateEvent>())
    if (s->node == kNode && s->cause == NodeStateEvent::Cause::Lost) lost_at = at;
  ASSERT_TRUE(lost_at.has_value());
  EXPECT_EQ(*lost_at, last_heartbeat + 250ms);

  // Recovery: the device speaks again; its next heartbeat recovers it.
  m.dev_ep->set_link_up(true);
  m.run_for(150ms);
  bool recovered = false;
  for (const auto& [s, at] : m.of<NodeStateEvent>())
    recovered = recovered || (s->node == kNode && s->cause == NodeStateEvent::Cause::Recovered &&
                              s->state == NmtState::Operational);
  EXPECT_TRUE(recovered);
}

TEST(MasterAndDevice, MasterAndDevice_7_2_8_3_1_ResetNodeFromMasterReconfiguresAndRestarts) {
  MasterAndDevice m;
  ASSERT_TRUE(m.net->add_node(kNode, m.dcf.od).empty());
  ASSERT_TRUE(m.boot->configure(kNode, master::boot_config_from_dcf(m.dcf)));
  m.device->start(m.clock.now());
  m.run_for(2s);
  ASSERT_EQ(m.device->state(), NmtState::Operational);
  m.steps.clear();
  m.net->nmt().send_command(NmtCommand::ResetNode, kNode);
  m.run_for(2s);
  ASSERT_FALSE(m.steps.empty());
  EXPECT_EQ(m.steps.front(), BootConfigEvent::Step::Identify);
  EXPECT_EQ(m.steps.back(), BootConfigEvent::Step::Done);
  EXPECT_EQ(m.device->state(), NmtState::Operational);
}

}  // namespace
}  // namespace canopen
