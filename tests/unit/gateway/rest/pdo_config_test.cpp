// Issue 11: PDO decoding follows the device, end to end - the whole gateway
// on the simulated demo network (whose devices rebuild their PDOs when
// their 1400h-1BFFh change), driven over REST: remapping by SDO, RPDO
// writes after a remap, the boot-up read of the devices' real PDO
// configuration, and GET/POST .../pdo (CiA 301 7.2.2, 7.5.2.35-7.5.2.39).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <mutex>

#include "auth/auth.hpp"
#include "rest_rig.hpp"
#include "sim/simulator.hpp"

namespace gateway {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
namespace json = boost::json;
using test::RestRig;

const std::string kNode10 = "/api/v1/networks/1/nodes/10";

// The TPDO events the gateway publishes, as their JSON.
struct Tpdos {
  void attach(App& app) {
    app.add_consumer([this](const EncodedEventPtr& ev) {
      if (ev->kind == EventKind::Tpdo) seen.push_back({ev->topic, json::parse(ev->json).as_object()});
    });
  }
  std::vector<json::object> of(const std::string& topic, std::size_t from = 0) const {
    std::vector<json::object> out;
    for (std::size_t i = from; i < seen.size(); ++i)
      if (seen[i].first == topic) out.push_back(seen[i].second);
    return out;
  }
  std::vector<std::pair<std::string, json::object>> seen;
};

const json::object* find_pdo(const json::object& body, const char* direction, int number) {
  for (const auto& v : body.at("pdos").as_array()) {
    const auto& p = v.as_object();
    if (p.at("direction").as_string() == direction && p.at("number").to_number<int>() == number) return &p;
  }
  return nullptr;
}

void sdo_write(RestRig& rig, const std::string& node, const char* index, int sub, std::uint64_t value) {
  auto r = rig.request("PUT", node + "/sdo/" + index + "/" + std::to_string(sub),
                       R"({"value":)" + std::to_string(value) + "}");
  ASSERT_EQ(r.status, 200) << index << " sub " << sub << ": " << r.body;
}

// The io module's TPDO1 as the EDS has it (6000h sub 1, one byte) vs. the
// remapped one (6401h sub 1 Analogue input 1 i16, then 6000h sub 1).
void expect_remapped_tpdo1(const json::object& ev) {
  const auto& values = ev.at("values").as_array();
  ASSERT_EQ(values.size(), 2U) << json::serialize(ev);
  const auto& v0 = values[0].as_object();
  EXPECT_EQ(v0.at("index"), 0x6401);
  EXPECT_EQ(v0.at("subIndex"), 1);
  EXPECT_EQ(v0.at("name"), "Analogue input 1");
  EXPECT_EQ(v0.at("type"), "i16");
  const auto& v1 = values[1].as_object();
  EXPECT_EQ(v1.at("index"), 0x6000);
  EXPECT_EQ(v1.at("type"), "u8");
  EXPECT_EQ(ev.at("raw").as_string().size(), 6U);  // 3 bytes
  EXPECT_FALSE(ev.contains("error"));
}

// 7.5.2.39 with the sequence of 7.5.2.38/39, every step a REST SDO write.
TEST(PdoRest, PdoRest_7_5_2_39_TpdoRemappedOverRestIsPublishedWithTheNewMapping) {
  RestRig rig;
  Tpdos tpdos;
  tpdos.attach(*rig.app);
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(10); }));
  const std::string topic = "canopen/test/1/10/tpdo/1";
  ASSERT_TRUE(rig.run_until([&] { return !tpdos.of(topic).empty(); }));
  EXPECT_EQ(tpdos.of(topic).back().at("values").as_array().size(), 1U) << "the EDS mapping first";

  sdo_write(rig, kNode10, "1800", 1, 0x8000018A);  // disable
  sdo_write(rig, kNode10, "1A00", 0, 0);
  sdo_write(rig, kNode10, "1A00", 1, 0x64010110);
  sdo_write(rig, kNode10, "1A00", 2, 0x60000108);
  sdo_write(rig, kNode10, "1A00", 0, 2);
  sdo_write(rig, kNode10, "1800", 1, 0x18A);  // enable
  const std::size_t mark = tpdos.seen.size();

  auto got = rig.request("GET", kNode10 + "/pdo");
  ASSERT_EQ(got.status, 200) << got.body;
  const auto* t1 = find_pdo(got.json().as_object(), "tpdo", 1);
  ASSERT_NE(t1, nullptr);
  EXPECT_EQ(t1->at("source"), "written");
  EXPECT_EQ(t1->at("enabled"), true);
  EXPECT_EQ(t1->at("cobId"), 0x18A);
  ASSERT_EQ(t1->at("mapping").as_array().size(), 2U);
  EXPECT_EQ(t1->at("mapping").as_array()[0].as_object().at("name"), "Analogue input 1");
  EXPECT_EQ(t1->at("mapping").as_array()[0].as_object().at("bits"), 16);
  EXPECT_EQ(find_pdo(got.json().as_object(), "tpdo", 2)->at("source"), "eds");

  ASSERT_TRUE(rig.run_until([&] { return tpdos.of(topic, mark).size() >= 3; }))
      << "the device keeps sending its remapped TPDO1";
  for (const auto& ev : tpdos.of(topic, mark)) expect_remapped_tpdo1(ev);
  // Nothing went unclaimed on 18Ah (the old mapping is gone, not misread).
  EXPECT_TRUE(tpdos.of("canopen/test/1/pdo/18A", mark).empty());
  EXPECT_TRUE(tpdos.of("canopen/test/1/pdo/394", mark).empty());
}

// 7.5.2.38: after the gateway remapped the drive's RPDO1 over REST, a REST
// RPDO write is sent with the new layout and the device applies it.
TEST(PdoRest, PdoRest_7_5_2_38_RpdoWriteAfterRemapUsesTheNewMapping) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  const std::string node5 = "/api/v1/networks/1/nodes/5";
  sdo_write(rig, node5, "1400", 1, 0x80000205);
  sdo_write(rig, node5, "1600", 0, 0);
  sdo_write(rig, node5, "1600", 1, 0x60600008);  // Modes of operation (i8)
  sdo_write(rig, node5, "1600", 2, 0x60400010);  // Controlword (u16)
  sdo_write(rig, node5, "1600", 0, 2);
  // Disabled mid-sequence: the gateway produces nothing for it.
  auto off = rig.request("PUT", node5 + "/rpdo/1", R"({"raw":"030f00"})");
  EXPECT_EQ(off.status, 404) << off.body;
  sdo_write(rig, node5, "1400", 1, 0x205);

  auto r = rig.request("PUT", node5 + "/rpdo/1",
                       R"({"values":[{"index":"6060","subIndex":0,"value":3},{"index":"6040","value":15}]})");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.json().as_object().at("raw"), "030f00");
  ASSERT_TRUE(rig.run_until([&] {
    auto v = rig.request("GET", node5 + "/sdo/6060/0");
    return v.status == 200 && v.json().as_object().at("value") == 3;
  })) << "the drive received Modes of operation through its remapped RPDO1";
  // The EDS layout (Controlword only, 2 bytes) no longer fits.
  auto old = rig.request("PUT", node5 + "/rpdo/1", R"({"raw":"0f00"})");
  EXPECT_EQ(old.status, 400) << old.body;
  EXPECT_THAT(old.body, HasSubstr("carries 3 bytes"));
  auto got = rig.request("GET", node5 + "/pdo");
  EXPECT_EQ(find_pdo(got.json().as_object(), "rpdo", 1)->at("source"), "written");
}

// Boot-up with read-pdo-config: the io module's stored mapping differs from
// its EDS. The gateway reads it before starting the node, so every TPDO1 it
// publishes has the device's layout.
TEST(PdoRest, PdoRest_7_2_2_ReadPdoConfigAtBootWinsOverTheEds) {
  Tpdos tpdos;
  RestRig rig(
      {}, [](Config& c) { c.networks.at(0).read_pdo_config = true; }, nullptr, {},
      [&](App& app) {
        tpdos.attach(app);
        auto* sim = app.simulator(1);
        ASSERT_NE(sim, nullptr);
        auto& od = sim->device(10)->dictionary();
        using canopen::DataType;
        using canopen::Value;
        ASSERT_FALSE(od.set(0x1A00, 0, Value::of_unsigned(DataType::Unsigned8, 2)));
        ASSERT_FALSE(od.set(0x1A00, 1, Value::of_unsigned(DataType::Unsigned32, 0x64010110)));
        ASSERT_FALSE(od.set(0x1A00, 2, Value::of_unsigned(DataType::Unsigned32, 0x60000108)));
        ASSERT_TRUE(sim->store(10));  // what it boots with
      });
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  const auto* n10 = rig.app->cache().node(1, 10);
  ASSERT_TRUE(n10->boot);
  EXPECT_EQ(n10->boot->step, canopen::BootConfigEvent::Step::Done);
  EXPECT_THAT(n10->boot->detail, HasSubstr("8 of 8 PDOs read from the device"));

  const std::string topic = "canopen/test/1/10/tpdo/1";
  ASSERT_TRUE(rig.run_until([&] { return tpdos.of(topic).size() >= 2; }));
  for (const auto& ev : tpdos.of(topic)) expect_remapped_tpdo1(ev);
  auto got = rig.request("GET", kNode10 + "/pdo");
  ASSERT_EQ(got.status, 200) << got.body;
  EXPECT_EQ(find_pdo(got.json().as_object(), "tpdo", 1)->at("source"), "device");
  // Node 11 has the EDS mapping on the device too: read, and the same.
  auto n11 = rig.request("GET", "/api/v1/networks/1/nodes/11/pdo");
  const auto* t11 = find_pdo(n11.json().as_object(), "tpdo", 1);
  EXPECT_EQ(t11->at("source"), "device");
  EXPECT_EQ(t11->at("mapping").as_array().size(), 1U);
}

// POST .../pdo/read on demand: the outcome per PDO (a PDO the device lacks
// is an abort that keeps the EDS's) and the configuration in effect.
TEST(PdoRest, PdoRest_7_2_2_ReadOnDemandReportsEachPdo) {
  RestRig rig({}, {}, nullptr, {}, [](App& app) {
    ASSERT_TRUE(app.simulator(1)->device(10)->dictionary().erase(0x1803));  // only three TPDOs
  });
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(10); }));
  auto before = rig.request("GET", kNode10 + "/pdo");
  ASSERT_EQ(before.status, 200) << before.body;
  EXPECT_EQ(before.json().as_object().at("pdos").as_array().size(), 8U);
  EXPECT_EQ(find_pdo(before.json().as_object(), "tpdo", 2)->at("transmissionType"), 255);

  auto r = rig.request("POST", kNode10 + "/pdo/read");
  ASSERT_EQ(r.status, 200) << r.body;
  const auto& o = r.json().as_object();
  EXPECT_THAT(std::string(o.at("summary").as_string()), HasSubstr("7 of 8 PDOs read from the device"));
  bool saw_abort = false;
  for (const auto& v : o.at("read").as_array()) {
    const auto& p = v.as_object();
    if (p.at("direction") == "tpdo" && p.at("number") == 4) {
      saw_abort = true;
      EXPECT_EQ(p.at("ok"), false);
      EXPECT_EQ(p.at("abortCode"), "0x06020000");
    } else {
      EXPECT_EQ(p.at("ok"), true) << json::serialize(p);
    }
  }
  EXPECT_TRUE(saw_abort);
  EXPECT_EQ(find_pdo(o, "tpdo", 1)->at("source"), "device");
  const auto* t4 = find_pdo(o, "tpdo", 4);
  EXPECT_EQ(t4->at("source"), "eds");
  EXPECT_THAT(std::string(t4->at("readError").as_string()), HasSubstr("1803h sub 1"));

  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/99/pdo/read").status, 404);  // no EDS
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/99/pdo").status, 404);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/2/nodes/10/pdo").status, 404);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/0/pdo").status, 400);
}

// Roles: viewers see the configuration, reading it from the device (which
// changes the decoding) needs operator; the read is audited.
TEST(PdoRest, PdoRest_ReadNeedsOperatorAndIsAudited) {
  char* buf = nullptr;
  std::size_t len = 0;
  std::FILE* log = open_memstream(&buf, &len);
  {
    RestRig rig(
        {},
        [](Config& c) {
          c.http.auth = true;
          c.http.tokens.push_back({"eve", Role::Viewer, auth::sha256_hex("viewer-secret")});
          c.http.tokens.push_back({"olga", Role::Operator, auth::sha256_hex("operator-secret")});
        },
        log);
    ASSERT_TRUE(rig.run_until([&] { return rig.operational(10); }));
    const std::vector<std::string> viewer = {"Authorization: Bearer viewer-secret"};
    const std::vector<std::string> op = {"Authorization: Bearer operator-secret"};
    EXPECT_EQ(rig.request("GET", kNode10 + "/pdo").status, 401);
    EXPECT_EQ(rig.request("GET", kNode10 + "/pdo", {}, viewer).status, 200);
    auto refused = rig.request("POST", kNode10 + "/pdo/read", {}, viewer);
    EXPECT_EQ(refused.status, 403);
    EXPECT_THAT(refused.body, HasSubstr("needs operator"));
    EXPECT_EQ(rig.request("POST", kNode10 + "/pdo/read", {}, op).status, 200);
    rig.log->flush();
  }
  std::fflush(log);
  const std::string text(buf, len);
  std::fclose(log);
  std::free(buf);
  EXPECT_THAT(text, HasSubstr("audit: PDO configuration read by olga@127.0.0.1: net 1 node 10: 8 of 8 PDOs read from the device"));
}

}  // namespace
}  // namespace gateway
