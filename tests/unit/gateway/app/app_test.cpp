// The gateway process on the simulated demo network, in-process: simulated
// devices boot, are identified and started, their TPDOs decoded into the
// state cache and the event pipeline; SDO and NMT requests get their replies
// (the same path MQTT and REST use: the request core). No CAN, no broker.
#include "app/app.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <boost/json.hpp>
#include <cstdio>
#include <vector>

#include "canopen/can/memory_bus.hpp"

#include "canopen/pdo/remote_config.hpp"
#include "messages/request_codec.hpp"
#include "support/mqtt_request.hpp"

namespace gateway {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

struct DemoRig {
  DemoRig() {
    CliOptions cli;
    cli.demo = true;
    cli.gateway_id = "test";
    Config c = merge(Config{}, cli);
    // The requests here carry no token: they may do everything (the demo
    // alone lets them read; roles are tested in app_requests_test.cpp).
    c.mqtt.requests_role = Role::Admin;
    c.state_dir.clear();  // keep no seq between tests (seq_store.hpp)
    log = std::make_unique<Logger>(LogLevel::Error);
    app = std::make_unique<App>(io, c, *log);
    app->add_consumer([this](const EncodedEventPtr& ev) { events.push_back(ev); });
    app->start();
  }
  ~DemoRig() { app->stop(); }

  // Runs the loop until pred() or the time is up.
  template <typename Pred>
  bool run_until(Pred pred, std::chrono::milliseconds limit = 10s) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!pred() && std::chrono::steady_clock::now() < end) io.run_for(10ms);
    return pred();
  }

  // A request as MQTT decodes it, executed by the App's request core, its
  // result encoded as the MQTT (and REST) reply.
  Reply request(core::Operation op, std::uint8_t node, std::string body, std::uint32_t net = 1) {
    std::optional<Reply> out;
    auto d = ::test::mqtt_request(op, net, node, body);
    EXPECT_TRUE(d.error.empty()) << d.error;
    app->requests().execute(std::move(d.request),
                            [&, opts = d.options](core::Result r) { out = encode_result(r, opts); });
    EXPECT_TRUE(run_until([&] { return out.has_value(); })) << "no reply";
    return out.value_or(Reply{0, "", ""});
  }

  boost::asio::io_context io;
  std::unique_ptr<Logger> log;
  std::unique_ptr<App> app;
  std::vector<EncodedEventPtr> events;
};

bool operational(const StateCache& c, std::uint8_t node) {
  const auto* n = c.node(1, node);
  return n != nullptr && n->state == canopen::NmtState::Operational;
}

TEST(AppDemo, SimulatedDevicesBootAreStartedAndSendDecodedPdos) {
  DemoRig rig;
  ASSERT_TRUE(rig.run_until([&] {
    return operational(rig.app->cache(), 5) && operational(rig.app->cache(), 10) && operational(rig.app->cache(), 11);
  })) << "the gateway starts the demo nodes after identifying them";
  const auto* drive = rig.app->cache().node(1, 5);
  EXPECT_EQ(drive->name, "drive-x");
  EXPECT_EQ(drive->boot_count, 1U);
  ASSERT_TRUE(drive->boot);
  EXPECT_EQ(drive->boot->step, canopen::BootConfigEvent::Step::Done);
  ASSERT_TRUE(rig.run_until([&] { return !rig.app->cache().node(1, 5)->values.empty(); }));
  const auto& values = rig.app->cache().node(1, 5)->values;
  auto it = values.find({0x6041, 0});
  ASSERT_NE(it, values.end()) << "Statusword decoded from the drive's TPDO";
  EXPECT_EQ(it->second.name, "Statusword");
  // Every event went through the pipeline with per-network seq and a topic.
  bool saw_tpdo = false;
  std::uint64_t last = 0;
  for (const auto& ev : rig.events) {
    if (ev->network != 1) continue;
    EXPECT_EQ(ev->seq, last + 1) << "seq without gaps";
    last = ev->seq;
    saw_tpdo = saw_tpdo || ev->topic == "canopen/test/1/5/tpdo/1";
    EXPECT_FALSE(ev->json.empty());
    // MQTT off and nobody asking for protobuf: PDOs are JSON only.
    EXPECT_EQ(ev->binary.empty(), ev->kind == EventKind::Tpdo) << ev->topic;
  }
  EXPECT_TRUE(saw_tpdo);
}

// A consumer that wants protobuf (a WebSocket client with ?format=protobuf)
// gets it for PDOs from the next event on.
TEST(AppDemo, PdosCarryProtobufWhileAConsumerWantsIt) {
  bool want = false;  // before the rig: App::stop() in its destructor still asks
  DemoRig rig;
  rig.app->set_protobuf_demand([&] { return want; });
  ASSERT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 5); }));
  auto tpdos_with_binary = [&] {
    std::size_t n = 0;
    for (const auto& ev : rig.events) n += ev->kind == EventKind::Tpdo && !ev->binary.empty() ? 1 : 0;
    return n;
  };
  EXPECT_EQ(tpdos_with_binary(), 0U);
  want = true;
  const auto before = rig.events.size();
  ASSERT_TRUE(rig.run_until([&] { return tpdos_with_binary() >= 3; }));
  for (std::size_t i = before; i < rig.events.size(); ++i) {
    const auto& ev = rig.events[i];
    if (ev->kind != EventKind::Tpdo) continue;
    EXPECT_FALSE(ev->binary.empty());
    EXPECT_FALSE(ev->ws_binary.empty());
  }
}

TEST(AppDemo, SdoReadIsTypedFromTheEds) {
  DemoRig rig;
  ASSERT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 5); }));
  const auto reply = rig.request(core::Operation::sdo_read, 5, R"({"index": "0x1000", "subIndex": 0})");
  ASSERT_EQ(reply.status, 200) << reply.body;
  const auto json = boost::json::parse(reply.body).as_object();
  EXPECT_EQ(json.at("type").as_string(), "u32");
  EXPECT_EQ(json.at("value").to_number<std::uint32_t>() & 0xFFFF, 402U) << "a CiA 402 device";
}

// CiA 301 7.2.4.3.13: the gateway passes the size the EDS type implies, so
// a fixed-size object (Statusword, u16; or a ?type= given) is read with a
// normal upload initiate (ccs 2: 40h) and a device without block transfer
// costs nothing extra; only an object of unknown size (a VISIBLE_STRING)
// opens with a block initiate (A4h, pst 64).
TEST(AppDemo, SdoReadOfAFixedSizeObjectUsesANormalUpload_7_2_4_3_13) {
  DemoRig rig;
  ASSERT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 5); }));
  canopen::can::MemoryBus* bus = rig.app->simulated_bus(1);
  ASSERT_NE(bus, nullptr);
  std::vector<canopen::can::Frame> requests;  // to node 5's SDO server
  canopen::can::BusFaults watch;
  watch.verdict = [&requests](const canopen::can::Frame& f, std::uint64_t) {
    if (f.id == 0x605) requests.push_back(f);
    return canopen::can::FrameVerdict::Deliver;
  };
  bus->set_faults(watch);
  auto first_request = [&requests] {
    std::vector<unsigned> b;
    if (!requests.empty()) b.assign(requests.front().data.begin(), requests.front().data.begin() + 6);
    return b;
  };

  const auto status = rig.request(core::Operation::sdo_read, 5, R"({"index": "0x6041", "subIndex": 0})");
  ASSERT_EQ(status.status, 200) << status.body;
  EXPECT_EQ(requests.size(), 1U) << "one expedited round trip";
  EXPECT_EQ(first_request(), (std::vector<unsigned>{0x40, 0x41, 0x60, 0x00, 0x00, 0x00}));

  requests.clear();
  const auto typed = rig.request(core::Operation::sdo_read, 5, R"({"index": "0x5FFF", "subIndex": 0, "type": "u32"})");
  EXPECT_EQ(typed.status, 422) << typed.body;
  EXPECT_EQ(first_request(), (std::vector<unsigned>{0x40, 0xFF, 0x5F, 0x00, 0x00, 0x00}));

  requests.clear();
  const auto name = rig.request(core::Operation::sdo_read, 5, R"({"index": "0x1008", "subIndex": 0})");
  ASSERT_EQ(name.status, 200) << name.body;
  EXPECT_THAT(name.body, HasSubstr("SD-402"));
  EXPECT_EQ(first_request(), (std::vector<unsigned>{0xA4, 0x08, 0x10, 0x00, 0x7F, 0x40}));
}

TEST(AppDemo, SdoErrorsMapToStatusCodes) {
  DemoRig rig;
  ASSERT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 5); }));
  // Not in the EDS: 404 without ?type=.
  EXPECT_EQ(rig.request(core::Operation::sdo_read, 5, R"({"index": "0x5FFF", "subIndex": 0})").status, 404);
  // With a type the device is asked, and it aborts: 422 with the abort code.
  auto abort = rig.request(core::Operation::sdo_read, 5, R"({"index": "0x5FFF", "subIndex": 0, "type": "u8"})");
  EXPECT_EQ(abort.status, 422) << abort.body;
  EXPECT_THAT(abort.body, HasSubstr("0x06020000"));
  // A node nobody answers for: 504 after the SDO timeout.
  EXPECT_EQ(rig.request(core::Operation::sdo_read, 42, R"({"index": "0x1000", "subIndex": 0, "type": "u32"})").status, 504);
  // Out of range for the type: 400 before anything goes on the bus.
  EXPECT_EQ(rig.request(core::Operation::sdo_write, 5, R"({"index": "0x6060", "subIndex": 0, "value": 300})").status, 400);
  // Unknown network: 404.
  EXPECT_EQ(rig.request(core::Operation::sdo_read, 5, R"({"index": "0x1000", "subIndex": 0})", 9).status, 404);
  // Malformed body: 400.
  EXPECT_EQ(rig.request(core::Operation::sdo_read, 5, R"({"index": )").status, 400);
}

TEST(AppDemo, SdoWriteRoundTrip) {
  DemoRig rig;
  ASSERT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 5); }));
  auto w = rig.request(core::Operation::sdo_write, 5, R"({"index": "0x6060", "subIndex": 0, "value": 3})");
  ASSERT_EQ(w.status, 200) << w.body;
  auto r = rig.request(core::Operation::sdo_read, 5, R"({"index": "0x6060", "subIndex": 0})");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(boost::json::parse(r.body).as_object().at("value").to_number<int>(), 3);
}

TEST(AppDemo, TheGatewaysOwnNodeAnswersFromItsDictionary) {
  DemoRig rig;
  auto name = rig.request(core::Operation::sdo_read, 127, R"({"index": "0x1008", "subIndex": 0})");
  ASSERT_EQ(name.status, 200) << name.body;
  EXPECT_THAT(name.body, HasSubstr("canopen-gateway"));
  EXPECT_EQ(rig.request(core::Operation::sdo_write, 127, R"({"index": "0x1017", "subIndex": 0, "value": 250})").status, 200);
  auto hb = rig.request(core::Operation::sdo_read, 127, R"({"index": "0x1017", "subIndex": 0})");
  EXPECT_THAT(hb.body, HasSubstr("\"value\":250"));
  // The dictionary's rules hold: read-only 1018h sub 1, an object that does not exist.
  auto ro = rig.request(core::Operation::sdo_write, 127, R"({"index": "0x1018", "subIndex": 1, "value": 1})");
  EXPECT_EQ(ro.status, 422);
  EXPECT_THAT(ro.body, HasSubstr("0x06010002"));
  auto missing = rig.request(core::Operation::sdo_read, 127, R"({"index": "0x2000", "subIndex": 0})");
  EXPECT_EQ(missing.status, 422);
  EXPECT_THAT(missing.body, HasSubstr("0x06020000"));
}

// The retained bus topic (api-contract "MQTT topics") carries the state the
// interface is in from the start, not only after a change.
TEST(AppDemo, BusStateIsPublishedAtStartRetainedWithoutAChange) {
  DemoRig rig;  // the consumer was added before start()
  EncodedEventPtr bus;
  for (const auto& ev : rig.events)
    if (ev->kind == EventKind::Bus && bus == nullptr) bus = ev;
  ASSERT_NE(bus, nullptr) << "no bus event at start";
  EXPECT_EQ(bus->topic, "canopen/test/1/bus");
  EXPECT_TRUE(bus->retained);
  const auto json = boost::json::parse(bus->json).as_object();
  EXPECT_EQ(json.at("state").as_string(), "error-active");
  EXPECT_EQ(json.at("previous").as_string(), "down");
  EXPECT_EQ(json.at("cause").as_string(), "link-up");
  EXPECT_EQ(json.at("tec").to_number<int>(), 0);
  EXPECT_EQ(json.at("rec").to_number<int>(), 0);
  // REST GET /networks/{net} and the dashboard read the state cache.
  const auto* net = rig.app->cache().network(1);
  ASSERT_TRUE(net->last_bus_event);
  EXPECT_EQ(net->last_bus_event->state, canopen::can::BusState::ErrorActive);
  // And on every change.
  const auto before = rig.events.size();
  ASSERT_TRUE(rig.app->set_simulated_link(1, false));
  EXPECT_TRUE(rig.run_until([&] {
    for (std::size_t i = before; i < rig.events.size(); ++i)
      if (rig.events[i]->kind == EventKind::Bus && rig.events[i]->json.find(R"("state":"down")") != std::string::npos)
        return true;
    return false;
  }, 2s));
}

// 7.3.2.2.1: an NMT reset communication of the gateway's own node undoes a
// 1017h written since start; the REST view shows the value in force.
TEST(AppDemo, ResetCommunicationOfTheOwnNodeRestoresItsHeartbeatTime) {
  DemoRig rig;
  auto hb = [&] {
    const auto r = rig.request(core::Operation::sdo_read, 127, R"({"index": "0x1017", "subIndex": 0})");
    return boost::json::parse(r.body).as_object().at("value").to_number<int>();
  };
  ASSERT_EQ(hb(), 1000) << "heartbeat-ms default";
  ASSERT_EQ(rig.request(core::Operation::sdo_write, 127, R"({"index": "0x1017", "subIndex": 0, "value": 250})").status, 200);
  ASSERT_EQ(hb(), 250);
  ASSERT_EQ(rig.request(core::Operation::nmt, 127, R"({"command": "reset-comm"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] { return hb() == 1000; }, 2s));
  // Saved with 1010h sub 2 ("save", 7.5.2.13) it survives the reset, until
  // 1011h sub 2 ("load", 7.5.2.14) and the next reset.
  ASSERT_EQ(rig.request(core::Operation::sdo_write, 127, R"({"index": "0x1017", "subIndex": 0, "value": 250})").status, 200);
  ASSERT_EQ(rig.request(core::Operation::sdo_write, 127, R"({"index": "0x1010", "subIndex": 2, "value": 1702257011})").status,
            200);
  // Written after the save: the reset undoes it (so it did happen).
  ASSERT_EQ(rig.request(core::Operation::sdo_write, 127, R"({"index": "0x100C", "subIndex": 0, "value": 5})").status, 200);
  ASSERT_EQ(rig.request(core::Operation::nmt, 127, R"({"command": "reset-comm"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] {
    const auto r = rig.request(core::Operation::sdo_read, 127, R"({"index": "0x100C", "subIndex": 0})");
    return boost::json::parse(r.body).as_object().at("value").to_number<int>() == 0;
  }, 2s));
  EXPECT_EQ(hb(), 250);
  ASSERT_EQ(rig.request(core::Operation::sdo_write, 127, R"({"index": "0x1011", "subIndex": 2, "value": 1684107116})").status,
            200);
  ASSERT_EQ(rig.request(core::Operation::nmt, 127, R"({"command": "reset-comm"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] { return hb() == 1000; }, 2s));
}

// Issue 11, the MQTT path (requests through the request core, as the MQTT
// front end sends them): the drive's TPDO2 remapped by SDO (CiA 301
// 7.5.2.39) is published with the new mapping.
TEST(AppDemo, TpdoRemappedBySdoRequestsIsPublishedWithTheNewMapping_7_5_2_39) {
  DemoRig rig;
  ASSERT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 5); }));
  const char* writes[] = {
      R"({"index": "0x1801", "subIndex": 1, "value": 2147484293})",  // 80000285h: disable
      R"({"index": "0x1A01", "subIndex": 0, "value": 0})",
      R"({"index": "0x1A01", "subIndex": 1, "value": 1618411536})",  // 60770010h Torque actual value
      R"({"index": "0x1A01", "subIndex": 0, "value": 1})",
      R"({"index": "0x1801", "subIndex": 1, "value": 645})",  // 285h: enable
  };
  for (const char* w : writes) ASSERT_EQ(rig.request(core::Operation::sdo_write, 5, w).status, 200) << w;
  const auto mark = rig.events.size();
  auto remapped = [&] {
    for (std::size_t i = mark; i < rig.events.size(); ++i)
      if (rig.events[i]->topic == "canopen/test/1/5/tpdo/2") return i;
    return std::size_t{0};
  };
  ASSERT_TRUE(rig.run_until([&] { return remapped() != 0; }));
  const auto ev = boost::json::parse(rig.events[remapped()]->json).as_object();
  const auto& values = ev.at("values").as_array();
  ASSERT_EQ(values.size(), 1U) << rig.events[remapped()]->json;
  EXPECT_EQ(values[0].as_object().at("name"), "Torque actual value");
  EXPECT_EQ(values[0].as_object().at("type"), "i16");
  EXPECT_FALSE(ev.contains("error"));
  const auto* t2 = rig.app->pdo_config(1)->find(5, {canopen::pdo::Direction::Transmit, 2});
  ASSERT_NE(t2, nullptr);
  EXPECT_EQ(t2->source, canopen::pdo::ConfigSource::Written);
}

TEST(AppDemo, NmtStopAndStartOneNodeAndAll) {
  DemoRig rig;
  ASSERT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 10); }));
  EXPECT_EQ(rig.request(core::Operation::nmt, 10, R"({"command": "stop"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] {
    const auto* n = rig.app->cache().node(1, 10);
    return n->state == canopen::NmtState::Stopped;
  }));
  EXPECT_TRUE(operational(rig.app->cache(), 5)) << "only node 10 was addressed";
  EXPECT_EQ(rig.request(core::Operation::nmt, 0, R"({"command": "start"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] { return operational(rig.app->cache(), 10); }));
  EXPECT_EQ(rig.request(core::Operation::nmt, 10, R"({"command": "jump"})").status, 400);
}

// Contract "LSS master", config lss.assign (issue 16 item 3): at start-up
// each listed device is selected by its identity, given its node-ID and
// stored through the request core (audited); the demo's unconfigured I/O
// module then boots with it. A device that does not answer is logged, and
// the gateway runs on.
TEST(AppDemo, LssAssignFromTheConfigurationAtStartUp) {
  char* buf = nullptr;
  std::size_t len = 0;
  std::FILE* f = open_memstream(&buf, &len);
  {
    CliOptions cli;
    cli.demo = true;
    cli.gateway_id = "test";
    Config c = merge(Config{}, cli);
    c.state_dir.clear();
    // The demo's new device: the I/O module's 1018h (sub 4 made unique by the simulator).
    c.networks[0].lss_assign = {LssAssignConfig{{0x5A1, 0x8822, 0x10003, 0x55000001}, 33, true},
                                LssAssignConfig{{1, 2, 3, 4}, 34, true}};
    boost::asio::io_context io;
    Logger log(LogLevel::Info, f);
    App app(io, c, log);
    app.start();
    const auto end = std::chrono::steady_clock::now() + 10s;
    auto booted = [&] {
      const auto* n = app.cache().node(1, 33);
      return n != nullptr && n->state.has_value();
    };
    // The absent device's answer comes after the time-out is counted (the
    // devices are switched back to waiting first): wait for its log line.
    auto absent_logged = [&] {
      log.flush();
      std::fflush(f);
      return std::string_view(buf, len).find("-> node-ID 34: not assigned") != std::string_view::npos;
    };
    while (!(booted() && absent_logged()) && std::chrono::steady_clock::now() < end) io.run_for(10ms);
    EXPECT_TRUE(booted()) << "node 33 never booted";
    EXPECT_EQ(app.requests().counters().lss_assigned, 1u);
    EXPECT_EQ(app.requests().counters().lss_timeouts, 1u);
    EXPECT_TRUE(app.cache().node(1, 5) != nullptr) << "the other devices run as before";
    app.stop();
    log.flush();
  }
  std::fclose(f);
  const std::string text(buf, len);
  std::free(buf);
  EXPECT_THAT(text, HasSubstr("lss.assign vendor 0x000005A1 product 0x00008822 revision 0x00010003 serial 0x55000001 "
                              "-> node-ID 33: assigned and stored"));
  EXPECT_THAT(text, HasSubstr("-> node-ID 34: not assigned: no device with vendor 0x00000001"));
  EXPECT_THAT(text, HasSubstr("audit: LSS configure by lss.assign (configuration): net 1"));
}

}  // namespace
}  // namespace gateway
