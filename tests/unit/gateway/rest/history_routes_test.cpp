// GET /api/v1/networks/{net}/nodes/{node}/history on the demo gateway
// (issue 18; docs/reference/rest.md "PDO value history"): the I/O module's
// (node 10) analog inputs 6401h sub 1-4 arrive in its TPDO every 100 ms
// and come back as series with ascending bucket times; a bad window or
// object list is 400 problem+json; an NMT stop (CiA 301 7.2.8.3.1.2) ends
// each series with a null entry (a gap) and the samples after the restart
// follow it.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <filesystem>

#include "rest/history_routes.hpp"
#include "rest_rig.hpp"

namespace gateway::test {
namespace {

using ::testing::HasSubstr;

const std::string kNode10 = "/api/v1/networks/1/nodes/10";

// Buckets of 6401h sub 1 in the last 10 minutes.
std::size_t points(const RestRig& rig, std::uint8_t sub = 1) {
  const history::ObjectId id{0x6401, sub};
  const auto r = rig.app->value_history()->query(1, 10, std::span(&id, 1), 600, std::chrono::system_clock::now());
  return r.series.empty() ? 0 : r.series[0].points.size();
}

json::object get_json(RestRig& rig, const std::string& target) {
  auto r = rig.request("GET", target);
  EXPECT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "application/json");
  return json::parse(r.body).as_object();
}

const json::object* series_of(const json::object& body, const std::string& object) {
  for (const auto& s : body.at("series").as_array())
    if (s.as_object().at("object").as_string() == object) return &s.as_object();
  return nullptr;
}

TEST(HistoryRoute, AnalogInputsOfTheDemoIoModuleAsSeriesWithAscendingTimes) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return points(rig) >= 3; }, 20s)) << "no TPDO values of node 10 recorded";
  const auto body = get_json(rig, kNode10 + "/history");
  EXPECT_EQ(body.at("network").to_number<int>(), 1);
  EXPECT_EQ(body.at("node").to_number<int>(), 10);
  EXPECT_EQ(body.at("window").to_number<int>(), 600);  // the default
  EXPECT_EQ(body.at("resolution").to_number<int>(), 1);
  EXPECT_THAT(std::string(body.at("from").as_string()), ::testing::MatchesRegex("[0-9-]+T[0-9:]+Z"));
  for (std::uint8_t sub = 1; sub <= 4; ++sub) {
    const std::string object = "6401:0" + std::to_string(sub);
    const auto* s = series_of(body, object);
    ASSERT_NE(s, nullptr) << object << " missing: " << json::serialize(body);
    EXPECT_EQ(s->at("index").to_number<int>(), 0x6401);
    EXPECT_EQ(s->at("sub").to_number<int>(), sub);
    EXPECT_EQ(s->at("name").as_string(), "Analogue input " + std::to_string(sub));  // the EDS's [6401Name]
    EXPECT_EQ(s->at("type").as_string(), "INTEGER16");
    EXPECT_EQ(s->at("unit").as_string(), "mV");  // Unit=mV in the I/O module's EDS
    EXPECT_TRUE(s->at("factor").is_null());       // no Factor=: the values are in mV as they are
    const auto& t = s->at("t").as_array();
    const auto& mean = s->at("mean").as_array();
    const auto& min = s->at("min").as_array();
    const auto& max = s->at("max").as_array();
    ASSERT_GE(t.size(), 2U);
    ASSERT_EQ(mean.size(), t.size());
    ASSERT_EQ(min.size(), t.size());
    ASSERT_EQ(max.size(), t.size());
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (i > 0) {
        EXPECT_LT(t[i - 1].to_number<std::int64_t>(), t[i].to_number<std::int64_t>());
      }
      ASSERT_FALSE(mean[i].is_null());  // running, never stopped
      // The simulator's sine stays within +-10000; min <= mean <= max.
      EXPECT_LE(min[i].to_number<double>(), mean[i].to_number<double>());
      EXPECT_LE(mean[i].to_number<double>(), max[i].to_number<double>());
      EXPECT_LE(std::abs(max[i].to_number<double>()), 10000.0);
    }
  }
  const auto& memory = body.at("memory").as_object();
  EXPECT_GT(memory.at("bytes").to_number<std::uint64_t>(), 0U);
  EXPECT_EQ(memory.at("maxBytes").to_number<std::uint64_t>(), history::kDefaultMaxBytes);
  EXPECT_GE(memory.at("objects").to_number<std::uint64_t>(), 4U);
  EXPECT_EQ(memory.at("refusedObjects").to_number<std::uint64_t>(), 0U);

  // Chosen objects only, in the tier the window asks for; one without
  // history is simply absent.
  // (percent-encoded, as a browser's URLSearchParams writes it)
  const auto two = get_json(rig, kNode10 + "/history?window=3600&objects=6401%3A02%2C2000%3A00");
  EXPECT_EQ(two.at("resolution").to_number<int>(), 10);
  ASSERT_EQ(two.at("series").as_array().size(), 1U) << json::serialize(two);
  EXPECT_EQ(two.at("series").as_array()[0].as_object().at("object").as_string(), "6401:02");
  EXPECT_EQ(get_json(rig, kNode10 + "/history?window=86400").at("resolution").to_number<int>(), 60);
  EXPECT_EQ(get_json(rig, kNode10 + "/history?window=601").at("resolution").to_number<int>(), 10);
  // /metrics: what the history holds, its cap, nothing refused.
  const auto m = rig.request("GET", "/metrics").body;
  EXPECT_THAT(m, HasSubstr("canopen_gateway_history_max_bytes 67108864\n"));
  EXPECT_THAT(m, HasSubstr("canopen_gateway_history_refused_objects_total 0\n"));
  EXPECT_THAT(m, ::testing::ContainsRegex("canopen_gateway_history_objects [1-9][0-9]*\n"));
  EXPECT_THAT(m, ::testing::ContainsRegex("canopen_gateway_history_bytes [1-9][0-9]*\n"));
  // A node without TPDOs recorded: no series.
  EXPECT_TRUE(get_json(rig, "/api/v1/networks/1/nodes/99/history").at("series").as_array().empty());
}

TEST(HistoryRoute, BadWindowOrObjectListIs400AndUnknownNetwork404) {
  RestRig rig;
  for (const std::string q : {"window=59", "window=86401", "window=ten", "window=", "objects=6401-01",
                              "objects=640:01", "objects=6401:1", "objects=6401:01,", "objects=", "objects=64G1:01"}) {
    SCOPED_TRACE(q);
    auto r = rig.request("GET", kNode10 + "/history?" + q);
    EXPECT_EQ(r.status, 400) << r.body;
    EXPECT_EQ(r.content_type, "application/problem+json");
  }
  EXPECT_THAT(rig.request("GET", kNode10 + "/history?window=59").body, HasSubstr("60..86400"));
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/0/history").status, 400);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/128/history").status, 400);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/9/nodes/10/history").status, 404);
}

TEST(HistoryRoute, NmtStopEndsTheSeriesWithAGapAndTheRestartContinuesIt) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return points(rig) >= 2; }, 20s));
  ASSERT_EQ(rig.request("POST", kNode10 + "/nmt", R"({"command":"stop"})").status, 200);
  ASSERT_TRUE(rig.run_until([&] {
    const auto* n = rig.app->cache().node(1, 10);
    return n != nullptr && n->state == canopen::NmtState::Stopped;
  }));
  auto body = get_json(rig, kNode10 + "/history?objects=6401:01");
  const auto* s = series_of(body, "6401:01");
  ASSERT_NE(s, nullptr);
  const auto& mean = s->at("mean").as_array();
  ASSERT_GE(mean.size(), 2U);
  EXPECT_TRUE(mean.back().is_null()) << "no gap after the stop: " << json::serialize(*s);
  EXPECT_TRUE(s->at("min").as_array().back().is_null());
  EXPECT_TRUE(s->at("max").as_array().back().is_null());
  EXPECT_FALSE(mean[mean.size() - 2].is_null());
  const std::size_t before = mean.size();

  // Started again: the next samples follow the gap.
  ASSERT_EQ(rig.request("POST", kNode10 + "/nmt", R"({"command":"start"})").status, 200);
  ASSERT_TRUE(rig.run_until([&] { return points(rig) >= before + 2; }, 20s));
  body = get_json(rig, kNode10 + "/history?objects=6401:01");
  s = series_of(body, "6401:01");
  ASSERT_NE(s, nullptr);
  const auto& after = s->at("mean").as_array();
  ASSERT_GT(after.size(), before);
  EXPECT_TRUE(after[before - 1].is_null()) << json::serialize(*s);
  EXPECT_FALSE(after.back().is_null());
}

// Contract "Remote configuration and maintenance": a node's settings
// changed at run time may be another device or mapping, so its old values
// are dropped; what comes after is recorded afresh.
TEST(HistoryRoute, ANodeConfiguredAnewAtRunTimeStartsItsHistoryAfresh) {
  const auto dir = std::filesystem::temp_directory_path() / ("rest_history_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    RestRig rig({}, [&](Config& c) { c.state_dir = dir.string(); });
    ASSERT_TRUE(rig.run_until([&] { return points(rig) >= 3; }, 20s));
    const auto before = std::chrono::floor<std::chrono::seconds>(std::chrono::system_clock::now());
    const auto put = rig.request("PUT", kNode10 + "/config", R"x({"name": "io-left", "eds": "(built in)"})x");
    ASSERT_EQ(put.status, 200) << put.body;
    const auto r = rig.app->value_history()->query(1, 10, {}, 600, std::chrono::system_clock::now());
    for (const auto& s : r.series) {
      ASSERT_FALSE(s.points.empty());
      EXPECT_GE(s.points.front().t, before.time_since_epoch().count()) << "a bucket from before the change survived";
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(HistoryRoute, HistoryOffIs404) {
  RestRig rig({}, [](Config& c) { c.history.max_bytes = 0; });
  auto r = rig.request("GET", kNode10 + "/history");
  EXPECT_EQ(r.status, 404) << r.body;
  EXPECT_THAT(r.body, HasSubstr("history is off"));
  EXPECT_EQ(rig.app->value_history(), nullptr);
}

TEST(HistoryRoute, ObjectListParser) {
  std::string error;
  auto ids = parse_history_objects("6401:01,6000:0A", error);
  ASSERT_TRUE(ids.has_value()) << error;
  ASSERT_EQ(ids->size(), 2U);
  EXPECT_EQ((*ids)[0], (history::ObjectId{0x6401, 1}));
  EXPECT_EQ((*ids)[1], (history::ObjectId{0x6000, 0x0A}));
  EXPECT_FALSE(parse_history_objects("6401:01,,6000:01", error).has_value());
  EXPECT_THAT(error, HasSubstr("IIII:SS"));
}

}  // namespace
}  // namespace gateway::test
