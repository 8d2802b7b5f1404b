// The gateway's picture of remote nodes' PDO parameters (issue 11): how SDO
// downloads and reads change it (CiA 301 7.5.2.35-7.5.2.39), how the decoder
// and producer take a changed PDO, and the SDO read of a node's records.
#include "canopen/pdo/remote_config.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/clock.hpp"
#include "canopen/pdo/config_reader.hpp"
#include "canopen/pdo/receiver.hpp"
#include "canopen/pdo/transmitter.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/sdo/server.hpp"
#include "unit/stack/pdo/pdo_test_util.hpp"

namespace canopen::pdo {
namespace {

using namespace std::chrono_literals;
using test::add_comm;
using test::add_map;
using test::add_var;

constexpr PdoKey kTpdo1{Direction::Transmit, 1};
constexpr PdoKey kRpdo1{Direction::Receive, 1};

Bytes le(std::uint32_t v, std::size_t n = 4) {
  Bytes b;
  for (std::size_t i = 0; i < n; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  return b;
}

// Node 5: TPDO1 on 185h maps 6000h (u8), RPDO1 on 205h maps 6200h (u8); 6401h
// sub 1 (i16) and 6402h (u32) are mappable too.
od::ObjectDictionary io_module() {
  od::ObjectDictionary d;
  add_var(d, 0x6000, "Digital inputs", DataType::Unsigned8);
  add_var(d, 0x6200, "Digital outputs", DataType::Unsigned8);
  add_var(d, 0x6402, "Counter", DataType::Unsigned32);
  od::Object analog;
  analog.index = 0x6401;
  analog.name = "Analogue inputs";
  analog.code = od::ObjectCode::Array;
  analog.subs[0] = test::entry(0, "Highest sub-index supported", DataType::Unsigned8,
                               Value::of_unsigned(DataType::Unsigned8, 1));
  analog.subs[1] = test::entry(1, "Analogue input 1", DataType::Integer16, Value::of_signed(DataType::Integer16, 0));
  d.insert(std::move(analog));
  add_comm(d, Direction::Transmit, 1, 0x185);
  add_map(d, Direction::Transmit, 1, {0x60000008, 0, 0, 0});
  (void)d.set(0x1A00, 0, Value::of_unsigned(DataType::Unsigned8, 1));
  add_comm(d, Direction::Receive, 1, 0x205);
  add_map(d, Direction::Receive, 1, {0x62000008});
  return d;
}

TEST(RemotePdoTable, RemotePdo_7_5_2_39_RemappingSequenceStepByStep) {
  RemotePdoTable t;
  ASSERT_TRUE(t.add_node(5, io_module()).empty());
  ASSERT_TRUE(t.resolve(5, kTpdo1));
  EXPECT_EQ(t.find(5, kTpdo1)->source, ConfigSource::Eds);

  // 1) COB-ID bit 31: the PDO no longer exists on the bus.
  EXPECT_EQ(t.apply_download(5, 0x1800, 1, le(0x80000185)), kTpdo1);
  EXPECT_FALSE(t.resolve(5, kTpdo1)->comm.cob_id.valid());
  EXPECT_EQ(t.find(5, kTpdo1)->source, ConfigSource::Written);
  // 2) sub 0 = 0: nothing mapped, a consistent (empty) state.
  EXPECT_TRUE(t.apply_download(5, 0x1A00, 0, le(0, 1)));
  EXPECT_TRUE(t.resolve(5, kTpdo1)->entries.empty());
  // 3) entries while sub 0 is 0 change nothing that is in use.
  EXPECT_TRUE(t.apply_download(5, 0x1A00, 1, le(0x64010110)));
  EXPECT_TRUE(t.apply_download(5, 0x1A00, 2, le(0x64020020)));
  EXPECT_TRUE(t.resolve(5, kTpdo1)->entries.empty());
  // 4) sub 0 = 2, 5) enabled: the new mapping, typed and named by the description.
  EXPECT_TRUE(t.apply_download(5, 0x1A00, 0, le(2, 1)));
  EXPECT_TRUE(t.apply_download(5, 0x1800, 1, le(0x185)));
  auto cfg = t.resolve(5, kTpdo1);
  ASSERT_TRUE(cfg) << cfg.error().detail;
  EXPECT_TRUE(cfg->comm.cob_id.valid());
  ASSERT_EQ(cfg->entries.size(), 2U);
  EXPECT_EQ(cfg->entries[0].name, "Analogue input 1");
  EXPECT_EQ(cfg->entries[0].type, DataType::Integer16);
  EXPECT_EQ(cfg->entries[1].name, "Counter");
  EXPECT_EQ(cfg->byte_length(), 6U);
}

TEST(RemotePdoTable, RemotePdo_7_5_2_35_CommunicationSubsAndWhatIsNotAPdoParameter) {
  RemotePdoTable t;
  ASSERT_TRUE(t.add_node(5, io_module()).empty());
  EXPECT_TRUE(t.apply_download(5, 0x1800, 2, le(1, 1)));      // transmission type: every SYNC
  EXPECT_TRUE(t.apply_download(5, 0x1800, 3, le(100, 2)));    // inhibit time
  EXPECT_TRUE(t.apply_download(5, 0x1800, 5, le(250, 2)));    // event timer
  EXPECT_TRUE(t.apply_download(5, 0x1800, 6, le(3, 1)));      // SYNC start value
  const CommParams& c = t.find(5, kTpdo1)->parameters.comm;
  EXPECT_EQ(c.transmission_type, 1);
  EXPECT_EQ(c.inhibit_time, 100);
  EXPECT_EQ(c.event_timer, 250);
  EXPECT_EQ(c.sync_start, 3);
  EXPECT_FALSE(t.apply_download(5, 0x1800, 0, le(6, 1)));  // highest sub-index: not a parameter
  EXPECT_FALSE(t.apply_download(5, 0x1800, 4, le(0, 1)));  // reserved
  EXPECT_FALSE(t.apply_download(5, 0x1A00, 65, le(0)));     // beyond 64 entries
  EXPECT_FALSE(t.apply_download(5, 0x1017, 0, le(100, 2)));  // not a PDO record
  EXPECT_FALSE(t.apply_download(5, 0x1800, 1, Bytes{}));
  EXPECT_FALSE(t.apply_download(9, 0x1800, 1, le(0x189)));  // node without a description
  EXPECT_EQ(pdo_of_index(0x1BFF), (PdoKey{Direction::Transmit, 512}));
  EXPECT_EQ(pdo_of_index(0x15FF), (PdoKey{Direction::Receive, 512}));
  EXPECT_FALSE(pdo_of_index(0x1C00));
}

TEST(RemotePdoTable, RemotePdo_7_5_2_39_UnresolvableMappingSaysWhy) {
  RemotePdoTable t;
  ASSERT_TRUE(t.add_node(5, io_module()).empty());
  t.apply_download(5, 0x1A00, 1, le(0x60000010));  // u8 mapped with 16 bits
  auto r = t.resolve(5, kTpdo1);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().detail, "TPDO1 entry 1: 16 bits for UNSIGNED8");
  t.apply_download(5, 0x1A00, 1, le(0x20000008));
  EXPECT_NE(t.resolve(5, kTpdo1).error().detail.find("2000h sub 0 does not exist"), std::string::npos);
  // A PDO the description lacks is created by its first write, disabled.
  const PdoKey t3{Direction::Transmit, 3};
  EXPECT_EQ(t.apply_download(5, 0x1A02, 0, le(1, 1)), t3);
  EXPECT_EQ(t.resolve(5, t3).error().detail, "TPDO3 entry 1: missing");
  EXPECT_FALSE(t.find(5, t3)->parameters.comm.cob_id.valid());
}

TEST(RemotePdoTable, RemotePdo_7_2_2_ReadFromTheDeviceWins) {
  RemotePdoTable t;
  ASSERT_TRUE(t.add_node(5, io_module()).empty());
  PdoParameters p;
  p.comm.cob_id.raw = 0x195;
  p.count = 1;
  p.entries[1] = 0x64020020;
  ASSERT_TRUE(t.apply_read(5, kTpdo1, p));
  EXPECT_EQ(t.find(5, kTpdo1)->source, ConfigSource::Device);
  EXPECT_EQ(t.find(5, kTpdo1)->parameters.entries.size(), 1U) << "the EDS entries 2-4 are not the device's";
  EXPECT_EQ(t.resolve(5, kTpdo1)->comm.cob_id.can_id(), 0x195U);
  t.set_read_error(5, kTpdo1, "TPDO1: 1800h sub 1: timeout");
  EXPECT_EQ(t.find(5, kTpdo1)->read_error, "TPDO1: 1800h sub 1: timeout");
  EXPECT_FALSE(t.apply_read(9, kTpdo1, p));
  EXPECT_EQ(to_string(ConfigSource::Written), "written");
  ASSERT_EQ(t.pdos(5).size(), 2U);
  EXPECT_EQ(t.pdos(5)[0]->key, kRpdo1);  // RPDOs first
}

TEST(PdoReceiver, Pdo_7_2_2_SetTpdoReplacesTheMappingInUse) {
  std::vector<PdoEvent> events;
  PdoReceiver rx([](const can::Frame&) {}, [&](PdoEvent ev) { events.push_back(std::move(ev)); });
  od::ObjectDictionary d = io_module();
  ASSERT_TRUE(rx.add_node(5, d).empty());
  RemotePdoTable t;
  ASSERT_TRUE(t.add_node(5, d).empty());
  t.apply_download(5, 0x1A00, 1, le(0x64010110));
  ASSERT_TRUE(rx.set_tpdo(5, *t.resolve(5, kTpdo1)).empty());
  ASSERT_TRUE(rx.on_frame(can::Frame::standard(0x185, {0x18, 0xFC}), TimePoint{}));
  ASSERT_EQ(events.size(), 1U);
  ASSERT_EQ(events[0].values.size(), 1U);
  EXPECT_EQ(events[0].values[0].name, "Analogue input 1");
  EXPECT_EQ(events[0].values[0].value, Value::of_signed(DataType::Integer16, -1000));

  // Unusable: still node 5's TPDO1, raw and the reason, no values.
  PdoConfig off = *t.resolve(5, kTpdo1);
  off.entries.clear();
  ASSERT_TRUE(rx.set_tpdo(5, off, "TPDO1 entry 1: 2000h sub 0 does not exist").empty());
  ASSERT_TRUE(rx.on_frame(can::Frame::standard(0x185, {0x18, 0xFC}), TimePoint{}));
  EXPECT_EQ(events[1].node, 5);
  EXPECT_EQ(events[1].number, 1);
  EXPECT_TRUE(events[1].values.empty());
  ASSERT_TRUE(events[1].error);
  EXPECT_NE(events[1].error->find("2000h sub 0 does not exist"), std::string::npos);

  // Disabled: the CAN-ID is nobody's.
  off.comm.cob_id.raw |= 0x80000000U;
  ASSERT_TRUE(rx.set_tpdo(5, off).empty());
  ASSERT_TRUE(rx.on_frame(can::Frame::standard(0x185, {0x18, 0xFC}), TimePoint{}));
  EXPECT_EQ(events[2].node, 0);
  // Moved onto a COB-ID another node's TPDO uses: reported; the lower
  // node-ID keeps it.
  PdoConfig moved = *t.resolve(5, kTpdo1);
  moved.comm.cob_id.raw = 0x185;
  ASSERT_TRUE(rx.set_tpdo(5, moved).empty());
  moved.comm.cob_id.raw = 0x185;
  auto problems = rx.set_tpdo(6, moved);
  ASSERT_EQ(problems.size(), 1U);
  EXPECT_EQ(problems[0], "TPDO1: COB-ID 389 already used by node 5");
}

TEST(PdoTransmitter, Pdo_7_5_2_38_ReconfigureKeepsTheValuesOfObjectsStillMapped) {
  std::vector<std::string> sent;
  PdoTransmitter tx([&](const can::Frame& f) { sent.push_back(test::text(f)); });
  od::ObjectDictionary d = io_module();
  (void)d.set(0x6402, 0, Value::of_unsigned(DataType::Unsigned32, 0x11223344));
  ASSERT_TRUE(tx.add_rpdo(5, 1, d, TimePoint{}));
  ASSERT_FALSE(tx.set_value(5, 1, 0x6200, 0, Value::of_unsigned(DataType::Unsigned8, 0xA5), TimePoint{}));
  RemotePdoTable t;
  ASSERT_TRUE(t.add_node(5, d).empty());
  t.apply_download(5, 0x1600, 1, le(0x64020020));
  t.apply_download(5, 0x1600, 2, le(0x62000008));
  t.apply_download(5, 0x1600, 0, le(2, 1));
  sent.clear();
  auto r = tx.reconfigure(5, *t.resolve(5, kRpdo1), TimePoint{}, &d);
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, 5U);
  EXPECT_TRUE(sent.empty()) << "reconfiguring sends nothing";
  // 6402h from the description, 6200h kept from the last write.
  EXPECT_EQ(*tx.payload(5, 1), (Bytes{0x44, 0x33, 0x22, 0x11, 0xA5}));
  EXPECT_EQ(tx.config(5, 1)->entries.size(), 2U);
  ASSERT_FALSE(tx.set_value(5, 1, 0x6200, 0, Value::of_unsigned(DataType::Unsigned8, 0x01), TimePoint{}));
  EXPECT_EQ(sent, (std::vector<std::string>{"205#4433221101"}));

  PdoConfig disabled = *t.resolve(5, kRpdo1);
  disabled.comm.cob_id.raw |= 0x80000000U;
  EXPECT_FALSE(tx.reconfigure(5, disabled, TimePoint{}));
  EXPECT_EQ(tx.payload(5, 1), nullptr) << "a disabled RPDO is not produced";
  EXPECT_EQ(tx.config(5, 1), nullptr);
}

// The reader against an SDO server on the node's dictionary.
struct ReaderRig {
  ReaderRig() {
    gw->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) client.on_frame(f, clock.now());
    });
    dev->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) server.on_frame(f, clock.now());
    });
  }
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      bus.deliver();
      const TimePoint next = std::min(client.next_deadline(), server.next_deadline());
      if (next > end) break;
      clock.advance_to(std::max(next, clock.now()));
      if (client.next_deadline() <= clock.now()) client.on_time(clock.now());
      if (server.next_deadline() <= clock.now()) server.on_time(clock.now());
    }
    clock.advance_to(end);
    bus.deliver();
  }
  FakeClock clock;
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> gw = bus.attach("gateway");
  std::unique_ptr<can::MemoryEndpoint> dev = bus.attach("device");
  od::ObjectDictionary device = io_module();
  sdo::SdoClient client{sdo::ClientConfig{}, [this](const can::Frame& f) { gw->send(f); }};
  sdo::SdoServer server{device, sdo::ServerConfig{5}, [this](const can::Frame& f) { dev->send(f); }};
  PdoConfigReader reader{client, [this] { return clock.now(); }};
};

TEST(PdoConfigReader, PdoRead_7_5_2_35_ReadsEachPdoAndAnAbortFailsOnlyThatPdo) {
  ReaderRig rig;
  (void)rig.device.set(0x1A00, 0, Value::of_unsigned(DataType::Unsigned8, 2));
  (void)rig.device.set(0x1A00, 2, Value::of_unsigned(DataType::Unsigned32, 0x64010110));
  (void)rig.device.set(0x1800, 5, Value::of_unsigned(DataType::Unsigned16, 500));
  std::vector<PdoReadReport> reports;
  const std::vector<PdoReadPlan> plan = {{kRpdo1, {}}, {{Direction::Transmit, 2}, {}}, {kTpdo1, {3, 5}}};
  ASSERT_FALSE(rig.reader.read(5, plan, [&](const PdoReadReport& r) { reports.push_back(r); }, rig.clock.now()));
  // A second caller joins the running read.
  ASSERT_FALSE(rig.reader.read(5, {}, [&](const PdoReadReport& r) { reports.push_back(r); }, rig.clock.now()));
  EXPECT_TRUE(rig.reader.busy(5));
  rig.run_for(100ms);
  ASSERT_EQ(reports.size(), 2U);
  const PdoReadReport& r = reports[0];
  EXPECT_FALSE(r.stopped);
  ASSERT_EQ(r.pdos.size(), 3U);
  ASSERT_TRUE(r.pdos[0].parameters);
  EXPECT_EQ(r.pdos[0].parameters->entries.at(1), 0x62000008U);
  // TPDO2 does not exist on the device: 06020000h, and the read goes on.
  EXPECT_FALSE(r.pdos[1].parameters);
  EXPECT_EQ(r.pdos[1].error, make_error_code(SdoAbort::NoSuchObject));
  EXPECT_EQ(r.pdos[1].detail.rfind("TPDO2: 1801h sub 1: ", 0), 0U) << r.pdos[1].detail;
  ASSERT_TRUE(r.pdos[2].parameters);
  const PdoParameters& t1 = *r.pdos[2].parameters;
  EXPECT_EQ(t1.comm.cob_id.raw, 0x185U);
  EXPECT_EQ(t1.comm.event_timer, 500);
  EXPECT_EQ(t1.count, 2);
  EXPECT_EQ(t1.entries.size(), 2U) << "only sub 1..sub 0 are read";
  EXPECT_EQ(t1.entries.at(2), 0x64010110U);
  EXPECT_EQ(r.read_count(), 2U);
  EXPECT_EQ(r.summary().rfind("2 of 3 PDOs read from the device; TPDO2: 1801h sub 1: ", 0), 0U) << r.summary();
  EXPECT_FALSE(rig.reader.busy(5));
}

TEST(PdoConfigReader, PdoRead_7_2_4_3_TimeoutStopsTheReadAndCancelReports) {
  ReaderRig rig;
  rig.dev->set_link_up(false);
  std::optional<PdoReadReport> report;
  ASSERT_FALSE(rig.reader.read(5, {{kRpdo1, {}}, {kTpdo1, {}}}, [&](const PdoReadReport& r) { report = r; },
                               rig.clock.now()));
  rig.run_for(5s);
  ASSERT_TRUE(report);
  EXPECT_EQ(report->stopped, make_error_code(SdoAbort::Timeout));
  ASSERT_EQ(report->pdos.size(), 2U);
  EXPECT_EQ(report->pdos[1].detail.rfind("TPDO1: not read: ", 0), 0U) << report->pdos[1].detail;

  report.reset();
  ASSERT_FALSE(rig.reader.read(5, {{kTpdo1, {}}}, [&](const PdoReadReport& r) { report = r; }, rig.clock.now()));
  rig.reader.cancel(5, rig.clock.now());
  ASSERT_TRUE(report);
  EXPECT_TRUE(report->cancelled);
  EXPECT_EQ(report->pdos[0].error, std::make_error_code(std::errc::operation_canceled));
  EXPECT_FALSE(rig.client.busy(5)) << "its SDO transfer is cancelled too";
  EXPECT_EQ(rig.reader.read(0, {}, {}, rig.clock.now()), std::make_error_code(std::errc::invalid_argument));
}

}  // namespace
}  // namespace canopen::pdo
