// Boot-up configuration (CiA 302-2 spirit) against a simulated CiA 402 drive
// over the in-memory bus with a fake clock: NmtMaster + SdoClient +
// BootConfigurator on one side, NmtSlave + SdoServer on the drive's EDS
// dictionary on the other.
#include "canopen/master/boot_configurator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/clock.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/nmt/master.hpp"
#include "canopen/nmt/slave.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/sdo/server.hpp"

namespace canopen::master {
namespace {

using namespace std::chrono_literals;
using Step = BootConfigEvent::Step;
using nmt::NmtMaster;
using nmt::NmtSlave;

constexpr std::uint8_t kNode = 5;
constexpr std::uint32_t kSerial = 0x00012345;  // the DCF's LSS serial / 1018h sub 4

std::string source_path(const char* rel) { return std::string(CANOPEN_SOURCE_DIR) + "/" + rel; }

struct Record {
  BootConfigEvent event;
  TimePoint at;
};

class Network {
 public:
  explicit Network(bool with_server = true)
      : device_od(eds::load_device_description(source_path("deploy/eds/cia402-drive.eds"), kNode).od),
        dcf(eds::load_device_description(source_path("tests/support/eds/cia402-drive-node5.dcf"))) {
    // The drive on the bus is the one the DCF names.
    EXPECT_FALSE(device_od.set(0x1018, 4, Value::of_unsigned(DataType::Unsigned32, kSerial)));
    device_ep = bus.attach("device");
    master_ep = bus.attach("master");
    slave = std::make_unique<NmtSlave>(device_od, kNode, [this](const can::Frame& f) { device_ep->send(f); });
    if (with_server) {
      sdo::ServerConfig sc;
      sc.node_id = kNode;
      server = std::make_unique<sdo::SdoServer>(device_od, sc, [this](const can::Frame& f) { device_ep->send(f); });
    }
    client = std::make_unique<sdo::SdoClient>(sdo::ClientConfig{},
                                              [this](const can::Frame& f) { master_ep->send(f); });
    master = std::make_unique<NmtMaster>(
        [this](const can::Frame& f) { master_ep->send(f); },
        [this](const EventBody& b, can::Frame::Clock::time_point) {
          if (const auto* n = std::get_if<NodeStateEvent>(&b); n && n->cause == NodeStateEvent::Cause::BootUp) {
            // Safe from the master's event sink: on_boot_up never calls send_nmt synchronously.
            boot->on_boot_up(n->node, clock.now());
          }
          if (const auto* h = std::get_if<HeartbeatEvent>(&b)) heartbeats.push_back(*h);
        });
    boot = std::make_unique<BootConfigurator>(
        *client,
        [this](NmtCommand cs, std::uint8_t node) {
          nmt_sent.push_back(cs);
          master->send_command(cs, node);
        },
        [this](const BootConfigEvent& e) { events.push_back({e, clock.now()}); },
        [this] { return clock.now(); });
    device_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) {
        if (device_filter && !device_filter(f)) continue;
        slave->on_frame(f, clock.now());
        if (server) server->on_frame(f, clock.now());
      }
    });
    master_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) {
        master->on_frame(f, clock.now());
        client->on_frame(f, clock.now());
      }
    });
  }

  TimePoint next_deadline() const {
    TimePoint t = std::min({master->next_deadline(), client->next_deadline(), slave->next_deadline()});
    if (server) t = std::min(t, server->next_deadline());
    return t;
  }

  // Runs every service until `end`, delivering frames after every step.
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      bus.deliver();
      const TimePoint next = next_deadline();
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      master->on_time(clock.now());
      client->on_time(clock.now());
      slave->on_time(clock.now());
      if (server) server->on_time(clock.now());
    }
    clock.advance_to(end);
    bus.deliver();
  }

  std::vector<Step> steps() const {
    std::vector<Step> out;
    for (const auto& r : events) out.push_back(r.event.step);
    return out;
  }

  // Every entry the DCF configures has its final value in the device.
  void expect_device_configured() const {
    std::map<std::pair<std::uint16_t, std::uint8_t>, Bytes> last;
    for (const auto& w : plan_configuration(dcf)) {
      if (!w.invalidate) last[{w.index, w.sub}] = w.data;
    }
    ASSERT_FALSE(last.empty());
    for (const auto& [where, data] : last) {
      auto got = device_od.read(where.first, where.second);
      ASSERT_TRUE(got.ok()) << std::hex << where.first << " sub " << unsigned{where.second};
      EXPECT_EQ(got.value(), data) << std::hex << where.first << " sub " << unsigned{where.second};
    }
  }

  FakeClock clock;
  can::MemoryBus bus;
  od::ObjectDictionary device_od;
  eds::DeviceDescription dcf;
  std::unique_ptr<can::MemoryEndpoint> device_ep;
  std::unique_ptr<can::MemoryEndpoint> master_ep;
  std::unique_ptr<NmtSlave> slave;
  std::unique_ptr<sdo::SdoServer> server;
  std::unique_ptr<sdo::SdoClient> client;
  std::unique_ptr<NmtMaster> master;
  std::unique_ptr<BootConfigurator> boot;
  std::function<bool(const can::Frame&)> device_filter;  // false: the device does not see the frame
  std::vector<Record> events;
  std::vector<HeartbeatEvent> heartbeats;
  std::vector<NmtCommand> nmt_sent;
};

std::uint64_t device_u(const Network& n, std::uint16_t index, std::uint8_t sub) {
  return n.device_od.get_unsigned(index, sub).value_or(0xDEADBEEF);
}

TEST(BootConfigurator, BootUp_IdentityMatches_DcfWritten_NodeStartedAndHeartbeatShowsOperational) {
  Network n;
  ASSERT_TRUE(n.boot->configure(kNode, boot_config_from_dcf(n.dcf)));
  n.slave->start(n.clock.now());
  n.run_for(2s);

  EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::CheckIdentity, Step::Configure, Step::Start,
                                          Step::Done}));
  EXPECT_FALSE(n.boot->busy(kNode));
  // The identity the device answered travels with the CheckIdentity step
  // (the gateway shows it per node).
  const auto& checked = n.events.at(1).event;
  ASSERT_TRUE(checked.identity);
  EXPECT_EQ(checked.identity->device_type, device_u(n, 0x1000, 0));
  EXPECT_EQ(checked.identity->vendor_id, device_u(n, 0x1018, 1));
  EXPECT_EQ(checked.identity->product_code, device_u(n, 0x1018, 2));
  EXPECT_EQ(checked.identity->revision, device_u(n, 0x1018, 3));
  EXPECT_FALSE(n.events.at(0).event.identity);
  n.expect_device_configured();
  // The DCF's differences from the EDS: TPDO2 remapped, event timers, heartbeat.
  EXPECT_EQ(device_u(n, 0x1A01, 0), 2U);
  EXPECT_EQ(device_u(n, 0x1A01, 2), 0x60770010U);
  EXPECT_EQ(device_u(n, 0x1801, 1), 0x285U);  // valid again
  EXPECT_EQ(device_u(n, 0x1800, 5), 50U);
  EXPECT_EQ(device_u(n, 0x1803, 2), 0xFFU);
  EXPECT_EQ(device_u(n, 0x1017, 0), 100U);
  EXPECT_EQ(device_u(n, 0x1016, 1), 0x007F01F4U);
  EXPECT_EQ(n.device_od.get(0x607D, 1).value(), n.dcf.od.get(0x607D, 1).value());

  EXPECT_EQ(n.nmt_sent, std::vector<NmtCommand>{NmtCommand::Start});
  EXPECT_EQ(n.slave->state(), NmtSlave::State::Operational);
  EXPECT_EQ(n.slave->heartbeat_period(), 100ms);
  ASSERT_FALSE(n.heartbeats.empty());
  EXPECT_EQ(n.heartbeats.back().node, kNode);
  EXPECT_EQ(n.heartbeats.back().state, NmtState::Operational);
}

// The identity and COB-ID reads are UNSIGNED32: they go out as normal upload
// initiates (CiA 301 7.2.4.3.5, 40h), never as block initiates (7.2.4.3.13),
// so a device without block transfer costs no refusal while booting.
TEST(BootConfigurator, Reads_7_2_4_3_5_AreNormalUploadsNotBlockInitiates) {
  Network n;
  std::vector<std::uint8_t> commands;  // byte 0 of every SDO request to the node
  n.device_filter = [&commands](const can::Frame& f) {
    if (f.id == 0x600 + kNode) commands.push_back(f.data[0]);
    return true;
  };
  ASSERT_TRUE(n.boot->configure(kNode, boot_config_from_dcf(n.dcf)));
  n.slave->start(n.clock.now());
  n.run_for(2s);
  ASSERT_EQ(n.steps().back(), Step::Done);
  const auto uploads = std::count(commands.begin(), commands.end(), std::uint8_t{0x40});
  EXPECT_GE(uploads, 5) << "1000h and 1018h sub 1..4 at least";
  EXPECT_EQ(std::count_if(commands.begin(), commands.end(), [](std::uint8_t c) { return (c & 0xE0U) == 0xA0U; }), 0)
      << "no block upload initiate";
}

TEST(BootConfigurator, PdoRemapping_7_5_2_35_InvalidateCountZeroEntriesCountThenValidCobId) {
  Network n;
  struct Write {
    std::uint16_t index;
    std::uint8_t sub;
    std::uint64_t value;
  };
  std::vector<Write> writes;
  for (std::uint16_t index : {std::uint16_t{0x1801}, std::uint16_t{0x1A01}}) {
    n.device_od.on_write(index, [&writes, index](od::SubEntry& e, const Value& v) {
      writes.push_back({index, e.sub, std::get<std::uint64_t>(v.data)});
      return std::error_code{};
    });
  }
  n.boot->configure(kNode, boot_config_from_dcf(n.dcf));
  n.slave->start(n.clock.now());
  n.run_for(2s);

  // TPDO2: COB-ID invalid, other comm subs, count 0, entries 1..2, count 2, COB-ID valid.
  std::vector<std::pair<std::uint16_t, std::uint8_t>> order;
  for (const auto& w : writes) order.emplace_back(w.index, w.sub);
  EXPECT_EQ(order, (std::vector<std::pair<std::uint16_t, std::uint8_t>>{
                       {0x1801, 1}, {0x1801, 2}, {0x1801, 3}, {0x1801, 5}, {0x1A01, 0}, {0x1A01, 1}, {0x1A01, 2},
                       {0x1A01, 0}, {0x1801, 1}}));
  ASSERT_EQ(writes.size(), 9U);
  EXPECT_EQ(writes.front().value, 0x80000285U);
  EXPECT_EQ(writes[4].value, 0U);
  EXPECT_EQ(writes[6].value, 0x60770010U);
  EXPECT_EQ(writes[7].value, 2U);
  EXPECT_EQ(writes.back().value, 0x285U);
}

TEST(BootConfigurator, PdoAlreadyInvalid_CobIdNotWrittenTwice) {
  Network n;
  ASSERT_FALSE(n.device_od.set(0x1801, 1, Value::of_unsigned(DataType::Unsigned32, 0x80000285U)));
  std::vector<std::uint64_t> cob_writes;
  n.device_od.on_write(0x1801, [&cob_writes](od::SubEntry& e, const Value& v) {
    if (e.sub == 1) cob_writes.push_back(std::get<std::uint64_t>(v.data));
    return std::error_code{};
  });
  n.boot->configure(kNode, boot_config_from_dcf(n.dcf));
  n.slave->start(n.clock.now());
  n.run_for(2s);
  EXPECT_EQ(cob_writes, std::vector<std::uint64_t>{0x285U});
  EXPECT_EQ(n.steps().back(), Step::Done);
}

TEST(BootConfigurator, IdentityMismatch_FailsWithDetailAndDoesNotStart) {
  Network n;
  NodeBootConfig c = boot_config_from_dcf(n.dcf);
  c.vendor_id = 0x00001234;
  n.boot->configure(kNode, c);
  n.slave->start(n.clock.now());
  n.run_for(2s);

  EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::Failed}));
  const BootConfigEvent& e = n.events.back().event;
  EXPECT_EQ(e.node, kNode);
  EXPECT_EQ(e.error, make_error_code(BootError::VendorIdMismatch));
  EXPECT_NE(e.detail.find("1018h sub 1"), std::string::npos) << e.detail;
  EXPECT_NE(e.detail.find("000005A1h"), std::string::npos) << e.detail;
  EXPECT_NE(e.detail.find("expected 00001234h"), std::string::npos) << e.detail;
  EXPECT_TRUE(n.nmt_sent.empty());
  EXPECT_EQ(n.slave->state(), NmtSlave::State::PreOperational);
  EXPECT_EQ(device_u(n, 0x1017, 0), 0U);  // nothing configured
  EXPECT_FALSE(n.boot->busy(kNode));
}

TEST(BootConfigurator, DeviceTypeMismatch_FailsWithDeviceTypeError) {
  Network n;
  NodeBootConfig c;
  c.device_type = 0x00020191;
  n.boot->configure(kNode, c);
  n.slave->start(n.clock.now());
  n.run_for(2s);
  ASSERT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::Failed}));
  EXPECT_EQ(n.events.back().event.error, make_error_code(BootError::DeviceTypeMismatch));
  EXPECT_TRUE(n.nmt_sent.empty());
}

TEST(BootConfigurator, NoSdoServer_FailsWithTimeoutAfterSdoTimeout_NoHang) {
  Network n(false);
  n.client->set_node_timeout(kNode, 300ms);
  n.boot->configure(kNode, boot_config_from_dcf(n.dcf));
  const TimePoint booted = n.clock.now();
  n.slave->start(booted);
  n.run_for(5s);

  ASSERT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::Failed}));
  const Record& r = n.events.back();
  EXPECT_EQ(r.event.error, make_error_code(SdoAbort::Timeout));
  EXPECT_EQ(r.at - booted, 300ms);
  EXPECT_NE(r.event.detail.find("1000h sub 0"), std::string::npos) << r.event.detail;
  EXPECT_TRUE(n.nmt_sent.empty());
  EXPECT_FALSE(n.boot->busy(kNode));
  EXPECT_FALSE(n.client->busy(kNode));
}

TEST(BootConfigurator, DeviceAbortsWrite_FailsWithThatAbortCodeAndDoesNotStart) {
  Network n;
  n.device_od.on_write(0x1A01, [](od::SubEntry&, const Value&) {
    return make_error_code(SdoAbort::ParameterIncompatible);
  });
  n.boot->configure(kNode, boot_config_from_dcf(n.dcf));
  n.slave->start(n.clock.now());
  n.run_for(2s);

  ASSERT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::CheckIdentity, Step::Configure, Step::Failed}));
  const BootConfigEvent& e = n.events.back().event;
  EXPECT_EQ(e.error, make_error_code(SdoAbort::ParameterIncompatible));
  EXPECT_NE(e.detail.find("writing 1A01h sub 0"), std::string::npos) << e.detail;
  EXPECT_TRUE(n.nmt_sent.empty());
  EXPECT_EQ(n.slave->state(), NmtSlave::State::PreOperational);
}

TEST(BootConfigurator, SecondBootUpDuringConfiguration_RestartsSequence) {
  Network n;
  bool rebooted = false;
  // The drive resets when the first write to 1A01h arrives: it never answers
  // it and sends boot-up again.
  n.device_filter = [&](const can::Frame& f) {
    if (!rebooted && f.id == 0x600U + kNode && f.len >= 4 && f.data[1] == 0x01 && f.data[2] == 0x1A) {
      rebooted = true;
      n.slave->start(n.clock.now());
      return false;
    }
    return true;
  };
  n.boot->configure(kNode, boot_config_from_dcf(n.dcf));
  n.slave->start(n.clock.now());
  n.run_for(3s);

  EXPECT_TRUE(rebooted);
  EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::CheckIdentity, Step::Configure, Step::Identify,
                                          Step::CheckIdentity, Step::Configure, Step::Start, Step::Done}));
  EXPECT_EQ(n.nmt_sent, std::vector<NmtCommand>{NmtCommand::Start});
  n.expect_device_configured();
  EXPECT_EQ(n.slave->state(), NmtSlave::State::Operational);
}

TEST(BootConfigurator, NoDcfAndStartFalse_OnlyIdentifiesAndChecks) {
  Network n;
  NodeBootConfig c;
  c.vendor_id = 0x000005A1;
  c.start = false;
  n.boot->configure(kNode, c);
  n.slave->start(n.clock.now());
  n.run_for(2s);
  EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::CheckIdentity, Step::Done}));
  EXPECT_TRUE(n.nmt_sent.empty());
  EXPECT_EQ(n.slave->state(), NmtSlave::State::PreOperational);
}

TEST(BootConfigurator, IdentitySubs2To4Absent_IgnoredUnlessExpected) {
  for (const bool expect_product : {false, true}) {
    Network n;
    // A device with only the vendor-ID in 1018h.
    n.device_od.on_read(0x1018, [](const od::SubEntry& e) -> Result<Bytes> {
      if (e.sub <= 1) return encode(e.value);
      return make_error_code(SdoAbort::NoSuchSubIndex);
    });
    NodeBootConfig c;
    c.vendor_id = 0x000005A1;
    if (expect_product) c.product_code = 0x00000402;
    n.boot->configure(kNode, c);
    n.slave->start(n.clock.now());
    n.run_for(2s);
    if (expect_product) {
      ASSERT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::Failed}));
      EXPECT_EQ(n.events.back().event.error, make_error_code(SdoAbort::NoSuchSubIndex));
      EXPECT_NE(n.events.back().event.detail.find("reading 1018h sub 2"), std::string::npos);
      EXPECT_TRUE(n.nmt_sent.empty());
    } else {
      EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::CheckIdentity, Step::Start, Step::Done}));
      EXPECT_EQ(n.nmt_sent, std::vector<NmtCommand>{NmtCommand::Start});
    }
  }
}

TEST(BootConfigurator, ConfigureDuringSequence_AppliesFromNextBootUp) {
  Network n;
  NodeBootConfig c;
  c.vendor_id = 0x000005A1;
  n.boot->configure(kNode, c);
  n.slave->start(n.clock.now());
  n.bus.deliver_one();  // boot-up: the sequence starts
  ASSERT_TRUE(n.boot->busy(kNode));
  c.vendor_id = 0x00001234;
  n.boot->configure(kNode, c);
  n.run_for(2s);
  EXPECT_EQ(n.steps().back(), Step::Done);

  n.events.clear();
  n.slave->start(n.clock.now());
  n.run_for(2s);
  EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::Failed}));
}

TEST(BootConfigurator, UnconfiguredNode_BootUpIgnored) {
  Network n;
  n.slave->start(n.clock.now());
  n.run_for(2s);
  EXPECT_TRUE(n.events.empty());
  EXPECT_FALSE(n.boot->busy(kNode));
  EXPECT_FALSE(n.boot->configure(0, {}));
  EXPECT_FALSE(n.boot->configure(128, {}));
}

// Issue 28 item 1 (CiA 302-2): a node found without a boot-up, powered
// before the manager. Its boot-up went out before the configuration existed.
TEST(BootConfigurator, FoundPreOperational_RunsTheWholeSequence) {
  Network n;
  n.slave->start(n.clock.now());
  n.run_for(200ms);  // boot-up ignored: not configured yet
  ASSERT_TRUE(n.boot->configure(kNode, boot_config_from_dcf(n.dcf)));
  EXPECT_TRUE(n.boot->on_found(kNode, NmtState::PreOperational, n.clock.now()));
  EXPECT_FALSE(n.boot->on_found(kNode, NmtState::PreOperational, n.clock.now())) << "a running sequence is left alone";
  n.run_for(2s);
  EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::CheckIdentity, Step::Configure, Step::Start,
                                          Step::Done}));
  n.expect_device_configured();
  EXPECT_EQ(n.nmt_sent, std::vector<NmtCommand>{NmtCommand::Start});
  EXPECT_EQ(n.slave->state(), NmtSlave::State::Operational);
}

TEST(BootConfigurator, FoundOperational_IdentityCheckedOnly_NotConfiguredOrRestarted) {
  Network n;
  n.slave->start(n.clock.now());
  n.run_for(200ms);
  n.master->send_command(NmtCommand::Start, kNode);  // another master started it
  n.run_for(200ms);
  ASSERT_EQ(n.slave->state(), NmtSlave::State::Operational);
  const auto heartbeat_before = device_u(n, 0x1017, 0);
  ASSERT_NE(heartbeat_before, n.dcf.od.get_unsigned(0x1017, 0).value()) << "the DCF would change 1017h";
  ASSERT_TRUE(n.boot->configure(kNode, boot_config_from_dcf(n.dcf)));
  EXPECT_TRUE(n.boot->on_found(kNode, NmtState::Operational, n.clock.now()));
  n.run_for(2s);
  EXPECT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::CheckIdentity, Step::Done}));
  EXPECT_EQ(n.events.back().event.detail, "already operational: identity checked, not configured or restarted");
  EXPECT_EQ(device_u(n, 0x1017, 0), heartbeat_before) << "nothing written";
  EXPECT_TRUE(n.nmt_sent.empty()) << "the configurator sent no NMT command";
  EXPECT_EQ(n.slave->state(), NmtSlave::State::Operational);

  // Its identity is still checked: the wrong device fails.
  n.events.clear();
  auto wrong = boot_config_from_dcf(n.dcf);
  wrong.serial = kSerial + 1;
  n.boot->configure(kNode, wrong);
  EXPECT_TRUE(n.boot->on_found(kNode, NmtState::Operational, n.clock.now()));
  n.run_for(2s);
  ASSERT_EQ(n.steps(), (std::vector<Step>{Step::Identify, Step::Failed}));
  EXPECT_EQ(n.events.back().event.error, make_error_code(BootError::SerialNumberMismatch));
}

TEST(BootConfigurator, FoundStoppedOrUnconfigured_NothingStarts) {
  Network n;
  EXPECT_FALSE(n.boot->on_found(kNode, NmtState::PreOperational, n.clock.now())) << "not configured";
  n.boot->configure(kNode, boot_config_from_dcf(n.dcf));
  EXPECT_FALSE(n.boot->on_found(kNode, NmtState::Stopped, n.clock.now())) << "no SDO in stopped (7.3.2.2)";
  n.run_for(1s);
  EXPECT_TRUE(n.events.empty());
  EXPECT_FALSE(n.boot->busy(kNode));
}

TEST(BootConfigPlan, StoreRestoreAndReadOnlyEntriesNeverWritten_HeartbeatAlways) {
  const auto dcf = eds::load_device_description(source_path("tests/support/eds/cia402-drive-node5.dcf"));
  const auto plan = plan_configuration(dcf);
  bool heartbeat = false;
  for (const auto& w : plan) {
    EXPECT_NE(w.index, 0x1010);
    EXPECT_NE(w.index, 0x1011);
    const od::SubEntry* e = dcf.od.find(w.index, w.sub);
    ASSERT_NE(e, nullptr);
    EXPECT_TRUE(od::writable(e->access)) << std::hex << w.index << " sub " << unsigned{w.sub};
    heartbeat = heartbeat || w.index == 0x1017;
  }
  EXPECT_TRUE(heartbeat);
  // Index order: the plan never goes back to a lower object, except within a PDO (comm then mapping).
  for (std::size_t i = 1; i < plan.size(); ++i) {
    const auto comm = [](std::uint16_t ix) {
      return static_cast<std::uint16_t>(((ix >= 0x1600 && ix <= 0x17FF) || (ix >= 0x1A00 && ix <= 0x1BFF)) ? ix - 0x200
                                                                                                          : ix);
    };
    EXPECT_LE(comm(plan[i - 1].index), comm(plan[i].index)) << i;
  }
}

}  // namespace
}  // namespace canopen::master
