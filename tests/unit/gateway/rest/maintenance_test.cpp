// Remote maintenance over REST (contract "Remote configuration and
// maintenance") against the whole gateway on the demo network: the DCF
// read-back of the I/O module (node 10) equals its dictionary, a DCF apply
// changes what a read-back shows, store/restore (CiA 301 7.5.2.13/14) on
// the simulated device, and a CiA 302-3 program download with its
// `transfer` events (MQTT topic canopen/<gw>/<net>/<node>/transfer) and the
// identification the simulated device reports (CRC-32 of the image).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <boost/crc.hpp>

#include "canopen/eds/eds.hpp"
#include "messages/event_encoder.hpp"
#include "rest_rig.hpp"

namespace gateway {
namespace {

using ::testing::HasSubstr;
using test::RestRig;
namespace json = boost::json;

const std::string kNode10 = "/api/v1/networks/1/nodes/10";
const std::vector<std::string> kOctets = {"Content-Type: application/octet-stream"};

// The `transfer` events the gateway publishes, with their MQTT topic.
struct Transfers {
  void attach(App& app) {
    app.add_consumer([this](const EncodedEventPtr& ev) {
      if (ev->kind == EventKind::Transfer) seen.push_back({ev->topic, json::parse(ev->json).as_object()});
    });
  }
  std::vector<std::pair<std::string, json::object>> seen;
};

std::uint64_t sdo_read(RestRig& rig, const std::string& what) {
  auto r = rig.request("GET", kNode10 + "/sdo/" + what);
  EXPECT_EQ(r.status, 200) << what << ": " << r.body;
  return r.status == 200 ? r.json().as_object().at("value").to_number<std::uint64_t>() : 0;
}

void sdo_write(RestRig& rig, const std::string& what, std::uint64_t value) {
  auto r = rig.request("PUT", kNode10 + "/sdo/" + what, R"({"value":)" + std::to_string(value) + "}");
  ASSERT_EQ(r.status, 200) << what << ": " << r.body;
}

// The value of index/sub in a DCF text, as the gateway's EDS reader reads it.
std::uint64_t dcf_value(const std::string& dcf, std::uint16_t index, std::uint8_t sub) {
  const auto d = canopen::eds::parse_device_description(dcf, "node10.dcf");
  const auto* e = d.od.find(index, sub);
  EXPECT_NE(e, nullptr) << std::hex << index << " sub " << int(sub) << " not in the DCF";
  if (e == nullptr) return 0;
  const auto v = d.od.get_unsigned(index, sub);
  EXPECT_TRUE(v.has_value());
  return v.value_or(0);
}

// Item 2: the read-back is the device's dictionary as it is now (not the
// EDS defaults): 1017h after an SDO write, a TPDO mapping entry.
TEST(RestMaintenance, DcfReadBackEqualsTheDevicesDictionary) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  sdo_write(rig, "1017/0", 1234);
  const auto mapping = sdo_read(rig, "1A00/1");
  auto r = rig.request("GET", kNode10 + "/dcf");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_THAT(r.content_type, HasSubstr("text/plain"));
  EXPECT_TRUE(r.has_header("content-disposition: attachment; filename=\"node10.dcf\"")) << r.head;
  EXPECT_TRUE(r.head.find("x-canopen-objects-read: ") != std::string::npos);
  EXPECT_EQ(dcf_value(r.body, 0x1017, 0), 1234u);
  EXPECT_EQ(dcf_value(r.body, 0x1A00, 1), mapping);
  EXPECT_EQ(dcf_value(r.body, 0x1800, 1), sdo_read(rig, "1800/1")) << "TPDO1 COB-ID";

  auto j = rig.request("GET", kNode10 + "/dcf", {}, {"Accept: application/json"});
  ASSERT_EQ(j.status, 200) << j.body;
  const auto& o = j.json().as_object();
  EXPECT_GT(o.at("objects").to_number<int>(), 10);
  EXPECT_TRUE(o.at("failed").is_array());
  EXPECT_EQ(dcf_value(std::string(o.at("dcf").as_string()), 0x1017, 0), 1234u);
}

TEST(RestMaintenance, DcfReadOfANodeWithoutEdsIs404) {
  RestRig rig;
  auto r = rig.request("GET", "/api/v1/networks/1/nodes/42/dcf");
  EXPECT_EQ(r.status, 404) << r.body;
  EXPECT_THAT(r.body, HasSubstr("has no EDS/DCF"));
}

// Item 3: read back, change one value, apply, read back shows it; one
// result per object.
TEST(RestMaintenance, DcfApplyRoundTrip) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  auto read = rig.request("GET", kNode10 + "/dcf");
  ASSERT_EQ(read.status, 200) << read.body;
  const auto before = dcf_value(read.body, 0x1017, 0);
  const std::uint64_t changed = before == 700 ? 800 : 700;
  // The [1017] section's ParameterValue line.
  std::string dcf = read.body;
  const auto section = dcf.find("[1017]");
  ASSERT_NE(section, std::string::npos);
  const auto line = dcf.find("ParameterValue=", section);
  ASSERT_LT(line, dcf.find("\n[", section + 1));
  dcf.replace(line, dcf.find('\n', line) - line, "ParameterValue=" + std::to_string(changed));

  auto applied = rig.request("POST", kNode10 + "/dcf", dcf, kOctets);
  ASSERT_EQ(applied.status, 200) << applied.body;
  const auto& a = applied.json().as_object();
  EXPECT_GT(a.at("written").to_number<int>(), 10);
  bool seen_1017 = false;
  for (const auto& v : a.at("objects").as_array()) {
    const auto& obj = v.as_object();
    if (obj.at("index") == 0x1017 && obj.at("subIndex") == 0) seen_1017 = obj.at("ok").as_bool();
  }
  EXPECT_TRUE(seen_1017) << "1017h listed as written";
  EXPECT_FALSE(a.at("stored").as_bool());
  EXPECT_FALSE(a.at("reset").as_bool());
  EXPECT_EQ(sdo_read(rig, "1017/0"), changed);
  auto again = rig.request("GET", kNode10 + "/dcf");
  ASSERT_EQ(again.status, 200);
  EXPECT_EQ(dcf_value(again.body, 0x1017, 0), changed);
}

TEST(RestMaintenance, ABadDcfIs400WithFileAndLineAndAPlainTextBodyIs415) {
  RestRig rig;
  auto bad = rig.request("POST", kNode10 + "/dcf", "[1017]\nParameterName=x\nObjectType=0x7\nDataType=0x0006\n"
                                                   "AccessType=rw\nParameterValue=1\nParameterValue=2\n", kOctets);
  EXPECT_EQ(bad.status, 400) << bad.body;
  EXPECT_THAT(bad.body, HasSubstr("node10.dcf:7: "));
  // A text/plain body is what a cross-site form can send: refused before the route.
  auto text = rig.request("POST", kNode10 + "/dcf", "[1017]\n", {"Content-Type: text/plain"});
  EXPECT_EQ(text.status, 415);
  EXPECT_EQ(rig.request("POST", kNode10 + "/dcf?store=maybe", "x", kOctets).status, 400);
}

// Item 4: CiA 301 7.5.2.13/14 on the simulated device: a stored value
// survives a reset; restore brings the EDS default back (after its reset).
TEST(RestMaintenance, StoreKeepsAValueAcrossAResetAndRestoreBringsTheDefault) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  // An application parameter (a reset application brings back the power-on values).
  const std::string limit = "6424/1";
  const auto factory = sdo_read(rig, limit);
  sdo_write(rig, limit, 1500);
  auto store = rig.request("POST", kNode10 + "/store");
  ASSERT_EQ(store.status, 200) << store.body;
  EXPECT_EQ(store.json().as_object().at("operation"), "store");
  EXPECT_FALSE(store.json().as_object().at("reset").as_bool());
  sdo_write(rig, limit, 1700);  // not stored
  const auto boots = rig.app->cache().node(1, 10)->boot_count;
  ASSERT_EQ(rig.request("POST", kNode10 + "/nmt", R"({"command":"reset-node"})").status, 200);
  ASSERT_TRUE(rig.run_until([&] { return rig.app->cache().node(1, 10)->boot_count > boots && rig.operational(10); }));
  EXPECT_EQ(sdo_read(rig, limit), 1500u) << "the stored value, not the later one";

  const auto boots2 = rig.app->cache().node(1, 10)->boot_count;
  auto restore = rig.request("POST", kNode10 + "/restore");
  ASSERT_EQ(restore.status, 200) << restore.body;
  EXPECT_TRUE(restore.json().as_object().at("reset").as_bool());
  ASSERT_TRUE(rig.run_until([&] { return rig.app->cache().node(1, 10)->boot_count > boots2 && rig.operational(10); }))
      << "the restore resets the node";
  EXPECT_EQ(sdo_read(rig, limit), factory) << "the EDS default again";
}

// Item 5: CiA 302-3 download of a 64 KiB image: transfer events in order
// (running with bytes, then done) on canopen/<gw>/<net>/<node>/transfer;
// the device's 1F56h is the CRC-32 of the image (the simulator's rule).
TEST(RestMaintenance, ProgramDownloadWithProgressAndIdentification) {
  RestRig rig;
  Transfers transfers;
  transfers.attach(*rig.app);
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  std::string image(64 * 1024, '\0');
  for (std::size_t i = 0; i < image.size(); ++i) image[i] = static_cast<char>((i * 7 + i / 251) & 0xFF);
  boost::crc_32_type crc;
  crc.process_bytes(image.data(), image.size());

  auto r = rig.request("PUT", kNode10 + "/program/1", image, kOctets);
  ASSERT_EQ(r.status, 200) << r.body;
  const auto& o = r.json().as_object();
  EXPECT_EQ(o.at("bytes").to_number<std::size_t>(), image.size());
  EXPECT_EQ(o.at("identification").to_number<std::uint32_t>(), crc.checksum());
  EXPECT_TRUE(o.at("started").as_bool());
  EXPECT_EQ(sdo_read(rig, "1F56/1"), crc.checksum());
  EXPECT_EQ(sdo_read(rig, "1F51/1"), 1u) << "running";

  ASSERT_GE(transfers.seen.size(), 3u);
  std::uint64_t last_done = 0;
  bool progress = false;
  for (std::size_t i = 0; i < transfers.seen.size(); ++i) {
    const auto& [topic, ev] = transfers.seen[i];
    EXPECT_EQ(topic, "canopen/test/1/10/transfer");
    EXPECT_EQ(ev.at("operation"), "program-download");
    const bool last = i + 1 == transfers.seen.size();
    EXPECT_EQ(ev.at("status"), last ? "done" : "running") << json::serialize(ev);
    if (ev.contains("unit") && ev.at("unit") == "bytes" && ev.contains("done")) {
      const auto done = std::stoull(std::string(ev.at("done").as_string()));
      EXPECT_GE(done, last_done) << "bytes only go up";
      last_done = done;
      progress = progress || (done > 0 && done < image.size());
    }
  }
  EXPECT_TRUE(progress) << "bytes done reported during the download";
  EXPECT_EQ(last_done, image.size());
}

// A download the device refuses (an image above its 4 MiB limit): the
// problem names the step and the abort code, and the program is not started.
TEST(RestMaintenance, ARefusedDownloadIsAProblemAndTheProgramIsNotStarted) {
  RestRig rig;
  Transfers transfers;
  transfers.attach(*rig.app);
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  std::string image((std::size_t{4} << 20) + 1, 'x');
  // 4 MiB go over the in-process bus before the device refuses: minutes of
  // patience under ASan on a loaded 2-core machine.
  auto r = rig.request("PUT", kNode10 + "/program/1", image, kOctets, std::chrono::minutes(3));
  EXPECT_EQ(r.status, 422) << r.body;
  EXPECT_THAT(r.body, HasSubstr("\"abortCode\":\"0x05040005\""));
  EXPECT_THAT(r.body, HasSubstr("1F50h"));
  EXPECT_EQ(sdo_read(rig, "1F51/1"), 3u) << "no program: not started";
  ASSERT_FALSE(transfers.seen.empty());
  EXPECT_EQ(transfers.seen.back().second.at("status"), "failed");
  EXPECT_EQ(rig.request("PUT", kNode10 + "/program/0", "x", kOctets).status, 400);
}

TEST(RestMaintenance, AProgramAboveTheConfiguredLimitIs413) {
  RestRig rig({}, [](Config& c) { c.http.max_program_bytes = 2048; });
  auto r = rig.request("PUT", kNode10 + "/program/1", std::string(4096, 'x'), kOctets);
  EXPECT_EQ(r.status, 413) << r.body;
  EXPECT_THAT(r.body, HasSubstr("2048"));
}

}  // namespace
}  // namespace gateway
