// Run-time node configuration with the real App on the simulated demo
// network in a temporary state-dir (issue 17 item 1, contract "Remote
// configuration and maintenance"): GET shows the configuration's settings;
// a PUT applies at once (name, 1016h heartbeat consumer), an EDS upload
// makes a node's TPDOs decoded with named values; a bad value or EDS is 400
// with the parser's reason and changes nothing; what was changed survives a
// restart in the same state-dir, a broken kept file does not stop the start.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <boost/json.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/app.hpp"
#include "support/memory_log.hpp"

namespace gateway {
namespace {

namespace fs = std::filesystem;
namespace json = boost::json;
using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const fs::path kIoEds = fs::path(CANOPEN_SOURCE_DIR) / "deploy/eds/cia401-io-module.eds";

struct TempDir {
  TempDir() : path(fs::temp_directory_path() / ("app_node_config_" + std::to_string(::getpid()) + "_" +
                                                std::to_string(counter++))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  static inline int counter = 0;
  fs::path path;
};

struct Rig {
  explicit Rig(const fs::path& state_dir) {
    CliOptions cli;
    cli.demo = true;
    cli.gateway_id = "test";
    Config c = merge(Config{}, cli);
    c.state_dir = state_dir.string();
    log = std::make_unique<Logger>(LogLevel::Info, mlog.file);
    app = std::make_unique<App>(io, c, *log);
    app->add_consumer([this](const EncodedEventPtr& ev) { events.push_back(ev); });
    app->start();
  }
  ~Rig() { app->stop(); }

  template <typename Pred>
  bool run_until(Pred pred, std::chrono::milliseconds limit = 10s) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!pred() && std::chrono::steady_clock::now() < end) io.run_for(10ms);
    return pred();
  }
  core::Result run(core::Command cmd, Role role = Role::Admin) {
    core::Request r;
    r.caller.authenticated = true;
    r.caller.role = role;
    r.caller.who = "tester";
    r.caller.key = "tester";
    r.network = 1;
    r.command = std::move(cmd);
    std::optional<core::Result> out;
    app->requests().execute(std::move(r), [&out](core::Result res) { out = std::move(res); });
    EXPECT_TRUE(run_until([&] { return out.has_value(); }));
    return out.value_or(core::Result{core::Problem{}});
  }
  core::NodeConfigView view(std::uint8_t node) {
    auto r = run(core::NodeConfigRead{node}, Role::Viewer);
    EXPECT_TRUE(std::holds_alternative<core::NodeConfigView>(r));
    return std::holds_alternative<core::NodeConfigView>(r) ? std::get<core::NodeConfigView>(r) : core::NodeConfigView{};
  }
  // The values of node 10's next TPDO1 event after now ("" names when raw).
  json::array next_tpdo_values(std::uint8_t node) {
    const auto mark = events.size();
    const std::string topic = "canopen/test/1/" + std::to_string(node) + "/tpdo/1";
    std::optional<std::size_t> at;
    EXPECT_TRUE(run_until([&] {
      for (std::size_t i = mark; i < events.size() && !at; ++i)
        if (events[i]->topic == topic) at = i;
      return at.has_value();
    }));
    if (!at) return {};
    const auto ev = json::parse(events[*at]->json).as_object();
    return ev.contains("values") ? ev.at("values").as_array() : json::array{};
  }
  // PUT .../config of `node` with the JSON body `text`, decoded as REST does.
  core::NodeConfigWrite put(std::uint8_t node, std::string_view text) const;
  std::uint64_t own_1016(std::uint8_t sub) { return app->own_dictionary(1)->get_unsigned(0x1016, sub).value_or(0); }

  MemoryLog mlog;
  boost::asio::io_context io;
  std::unique_ptr<Logger> log;
  std::unique_ptr<App> app;
  std::vector<EncodedEventPtr> events;
};

const core::Problem& problem(const core::Result& r) {
  static const core::Problem none{};
  if (!std::holds_alternative<core::Problem>(r)) {
    ADD_FAILURE() << "not a problem";
    return none;
  }
  return std::get<core::Problem>(r);
}

// A PUT .../config body decoded as REST decodes it (config/: the
// configuration file's rules; what does not decode travels in `invalid`).
core::NodeConfigWrite decoded(std::uint8_t node, std::string_view text, const Config& config) {
  core::NodeConfigWrite w;
  w.node = node;
  try {
    w.settings = node_config_from_request(json::parse(text), node, config.networks.at(0), config.source);
  } catch (const ConfigError& e) {
    w.invalid = e.what();
  }
  return w;
}
core::NodeConfigWrite Rig::put(std::uint8_t node, std::string_view text) const {
  return decoded(node, text, app->config());
}
core::NodeConfigWrite revert(std::uint8_t node) {
  core::NodeConfigWrite w;
  w.node = node;
  w.revert = true;
  return w;
}
// The settings as REST answers them (the keys of a `nodes:` entry).
json::object settings_json(const core::NodeConfigView& v) {
  EXPECT_TRUE(v.settings.has_value());
  return v.settings ? node_config_json(*v.settings) : json::object{};
}

bool has_consumer(Rig& rig, std::uint64_t entry) {
  for (std::uint8_t sub = 1; sub <= rig.own_1016(0); ++sub)
    if (rig.own_1016(sub) == entry) return true;
  return false;
}

// Contract: GET .../config (viewer) shows the configuration's settings;
// PUT (admin) applies at once and keeps them in state-dir.
TEST(AppNodeConfig, GetShowsTheConfigurationAndAPutAppliesAtOnce) {
  TempDir dir;
  Rig rig(dir.path);
  const auto before = rig.view(10);
  EXPECT_EQ(before.source, "config");
  EXPECT_EQ(settings_json(before).at("name"), "io-rack-1");
  EXPECT_EQ(settings_json(before).at("eds"), "(built in)");
  EXPECT_EQ(settings_json(before).at("heartbeat-consumer-ms"), 2000);

  for (const Role r : {Role::Viewer, Role::Operator})
    EXPECT_EQ(problem(rig.run(rig.put(10, R"({"name": "x"})"), r)).status, 403);

  const auto changed = rig.run(rig.put(10, R"x({"name": "io-left", "eds": "(built in)", "heartbeat-consumer-ms": 1500})x"));
  ASSERT_TRUE(std::holds_alternative<core::NodeConfigView>(changed)) << problem(changed).detail;
  const auto& v = std::get<core::NodeConfigView>(changed);
  EXPECT_EQ(v.source, "state-dir");
  EXPECT_EQ(v.file, (dir.path / "nodes/net1-node10.yaml").string());
  EXPECT_TRUE(fs::exists(v.file));
  EXPECT_EQ(rig.app->cache().node(1, 10)->name, "io-left") << "the REST node view's name";
  // CiA 301 7.5.2.33: the consumer entry is node-ID << 16 | time in ms.
  EXPECT_TRUE(has_consumer(rig, 0x000A0000 | 1500));
  EXPECT_FALSE(has_consumer(rig, 0x000A0000 | 2000));
  const auto origins = rig.app->node_origins(1);
  ASSERT_EQ(origins.size(), 3u);
  EXPECT_EQ(origins[1].node, 10);
  EXPECT_EQ(origins[1].source, "state-dir");
  EXPECT_EQ(origins[0].source, "config");
  EXPECT_THAT(rig.mlog.text(), HasSubstr("node configuration: tester: net 1 node 10: configuration changed"));
}

// A bad value is 400 with the configuration parser's reason; nothing changes.
TEST(AppNodeConfig, AnInvalidPutIs400WithTheParsersReasonAndChangesNothing) {
  TempDir dir;
  Rig rig(dir.path);
  const auto bad = rig.run(rig.put(10, R"({"heartbeat-consumer-ms": "never"})"));
  EXPECT_EQ(problem(bad).status, 400);
  EXPECT_EQ(problem(bad).detail,
            "request body: heartbeat-consumer-ms: 'never' is not auto, 0 (not watched) or a consumer time in ms "
            "(1..65535)");
  EXPECT_EQ(problem(rig.run(rig.put(10, R"({"guarding": {"guard-time-ms": 100}})"))).detail,
            "request body: guarding: guard-time-ms and life-time-factor must both be set (or both 0)");
  EXPECT_EQ(problem(rig.run(rig.put(10, R"({"id": 11})"))).status, 400);
  EXPECT_EQ(problem(rig.run(rig.put(10, R"({"eds": "/no/such.eds"})"))).status, 400);
  EXPECT_EQ(rig.view(10).source, "config");
  EXPECT_EQ(rig.app->cache().node(1, 10)->name, "io-rack-1");
  EXPECT_TRUE(has_consumer(rig, 0x000A0000 | 2000));
  EXPECT_NE(rig.app->description(1, 10), nullptr);
  EXPECT_FALSE(fs::exists(dir.path / "nodes/net1-node10.yaml"));
}

// Without its EDS a node's TPDOs arrive raw; an EDS uploaded over REST makes
// them decoded with named values at once (CiA 306 + 7.2.2), no restart.
// A file the reader refuses is 400 "FILE:LINE: reason" and changes nothing.
TEST(AppNodeConfig, AnEdsUploadMakesTheTpdosDecodedAtOnce) {
  TempDir dir;
  Rig rig(dir.path);
  ASSERT_TRUE(rig.run_until([&] {
    const auto* n = rig.app->cache().node(1, 10);
    return n != nullptr && n->state == canopen::NmtState::Operational;
  }));
  ASSERT_TRUE(std::holds_alternative<core::NodeConfigView>(
      rig.run(rig.put(10, R"({"name": "io-rack-1"})"))));
  EXPECT_EQ(rig.app->description(1, 10), nullptr);
  // No EDS: its TPDO1 (18Ah) is a PDO nobody claims, raw bytes only.
  const auto mark = rig.events.size();
  EXPECT_TRUE(rig.run_until([&] {
    for (std::size_t i = mark; i < rig.events.size(); ++i)
      if (rig.events[i]->kind == EventKind::UnclaimedPdo && rig.events[i]->json.find("\"cobId\":394") != std::string::npos)
        return true;
    return false;
  })) << "no EDS: raw only";

  const std::string text = read_file(kIoEds);
  const auto bad = rig.run(core::NodeEdsWrite{10, text + "\n[6001]\nParameterName=X\nObjectType=0x7\nDataType=0x0005\n"
                                                         "AccessType=ro\nAccessType=rw\n", "io.eds"});
  EXPECT_EQ(problem(bad).status, 400);
  EXPECT_THAT(problem(bad).detail, StartsWith("io.eds:"));
  EXPECT_EQ(rig.app->description(1, 10), nullptr) << "nothing changed";
  EXPECT_FALSE(fs::exists(dir.path / "nodes/net1-node10.eds"));

  const auto ok = rig.run(core::NodeEdsWrite{10, text, "cia401-io-module.eds"});
  ASSERT_TRUE(std::holds_alternative<core::NodeConfigView>(ok)) << problem(ok).detail;
  EXPECT_EQ(settings_json(std::get<core::NodeConfigView>(ok)).at("eds").as_string(), (dir.path / "nodes/net1-node10.eds").string());
  EXPECT_EQ(settings_json(std::get<core::NodeConfigView>(ok)).at("name"), "io-rack-1") << "the other settings stay";
  EXPECT_EQ(read_file(dir.path / "nodes/net1-node10.eds"), text);
  ASSERT_NE(rig.app->description(1, 10), nullptr) << "OD browser and SDO typing";
  const auto values = rig.next_tpdo_values(10);
  ASSERT_FALSE(values.empty()) << "decoded";
  EXPECT_FALSE(values[0].as_object().at("name").as_string().empty());
}

// What was changed is kept in state-dir: a restart in the same directory
// starts with it (it wins over the configuration for that node); DELETE
// goes back to the configuration's settings.
TEST(AppNodeConfig, ChangesSurviveARestartAndDeleteGoesBack) {
  TempDir dir;
  {
    Rig rig(dir.path);
    ASSERT_TRUE(std::holds_alternative<core::NodeConfigView>(
        rig.run(rig.put(11, R"({"name": "io-right", "heartbeat-consumer-ms": 0})"))));
    ASSERT_TRUE(std::holds_alternative<core::NodeConfigView>(
        rig.run(core::NodeEdsWrite{11, read_file(kIoEds), "io.eds"})));
  }
  Rig rig(dir.path);
  const auto v = rig.view(11);
  EXPECT_EQ(v.source, "state-dir");
  EXPECT_EQ(settings_json(v).at("name"), "io-right");
  EXPECT_EQ(settings_json(v).at("heartbeat-consumer-ms"), 0);
  EXPECT_EQ(rig.app->cache().node(1, 11)->name, "io-right");
  EXPECT_NE(rig.app->description(1, 11), nullptr) << "the kept EDS";
  EXPECT_FALSE(has_consumer(rig, 0x000B0000 | 2000));
  EXPECT_EQ(rig.view(5).source, "config") << "the other nodes keep the configuration's";

  const auto back = rig.run(revert(11));
  ASSERT_TRUE(std::holds_alternative<core::NodeConfigView>(back));
  EXPECT_EQ(std::get<core::NodeConfigView>(back).source, "config");
  EXPECT_EQ(rig.app->cache().node(1, 11)->name, "io-rack-2");
  EXPECT_TRUE(has_consumer(rig, 0x000B0000 | 2000));
  EXPECT_FALSE(fs::exists(dir.path / "nodes/net1-node11.yaml"));
  EXPECT_FALSE(fs::exists(dir.path / "nodes/net1-node11.eds"));
}

// A node only the overlay has is added at start-up; a kept file that cannot
// be used is logged naming it and its node keeps the configuration's
// settings: the gateway starts all the same.
TEST(AppNodeConfig, ABrokenKeptFileIsLoggedAndTheConfigurationsSettingsApply) {
  TempDir dir;
  fs::create_directories(dir.path / "nodes");
  std::ofstream(dir.path / "nodes/net1-node11.yaml") << "{\"id\": 11, \"heartbeat-consumer-ms\": \"never\"}\n";
  std::ofstream(dir.path / "nodes/net1-node20.yaml") << "{\"id\": 20, \"name\": \"added\"}\n";
  Rig rig(dir.path);
  EXPECT_EQ(rig.view(11).source, "config");
  EXPECT_EQ(rig.app->cache().node(1, 11)->name, "io-rack-2");
  rig.log->flush();
  EXPECT_THAT(rig.mlog.text(), HasSubstr((dir.path / "nodes/net1-node11.yaml").string() +
                                         ": heartbeat-consumer-ms: 'never' is not auto"));
  EXPECT_THAT(rig.mlog.text(), HasSubstr("node 11 keeps the configuration file's settings"));
  const auto added = rig.view(20);
  EXPECT_EQ(added.source, "state-dir");
  EXPECT_EQ(rig.app->cache().node(1, 20)->name, "added");
}

// CiA 301 7.3.2 / 7.5.2.33: a reset communication of the gateway's own node
// returns 1016h to its power-on values; a consumer time changed at run time
// is part of the gateway's configuration and comes back with them.
TEST(AppNodeConfig, AConsumerChangedAtRunTimeSurvivesAResetCommunicationOfTheOwnNode) {
  TempDir dir;
  Rig rig(dir.path);
  ASSERT_TRUE(std::holds_alternative<core::NodeConfigView>(rig.run(rig.put(10, R"x({"name": "io-rack-1", "eds": "(built in)", "heartbeat-consumer-ms": 1500})x"))));
  ASSERT_TRUE(has_consumer(rig, 0x000A0000 | 1500));
  ASSERT_TRUE(std::holds_alternative<core::NmtSent>(rig.run(core::Nmt{127, canopen::NmtCommand::ResetCommunication})));
  rig.io.run_for(200ms);
  EXPECT_TRUE(has_consumer(rig, 0x000A0000 | 1500));
  EXPECT_FALSE(has_consumer(rig, 0x000A0000 | 2000));
  EXPECT_TRUE(has_consumer(rig, 0x00050000 | 2000)) << "the others as configured";
}

// Without a state-dir a change would be gone at the next start: refused.
TEST(AppNodeConfig, WithoutAStateDirAChangeIs409) {
  Rig rig(fs::path{});
  const auto r = rig.run(rig.put(10, R"({"name": "x"})"));
  EXPECT_EQ(problem(r).status, 409);
  EXPECT_THAT(problem(r).detail, HasSubstr("no state-dir"));
  EXPECT_EQ(rig.app->cache().node(1, 10)->name, "io-rack-1");
}

}  // namespace
}  // namespace gateway
