// The run-time node configuration routes over real HTTP (contract "Remote
// configuration and maintenance"): GET/PUT/DELETE .../config and PUT
// .../eds with their JSON shapes, a file body as application/octet-stream
// with its name from ?name=, 400 problems with the reason, and
// GET /api/v1/gateway naming where each node's settings come from.
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "rest_rig.hpp"

namespace gateway::test {
namespace {

namespace fs = std::filesystem;

struct StateDir {
  StateDir() : path(fs::temp_directory_path() / ("rest_node_config_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~StateDir() { fs::remove_all(path); }
  fs::path path;
};

std::string io_eds() {
  std::ifstream in(fs::path(CANOPEN_SOURCE_DIR) / "deploy/eds/cia401-io-module.eds", std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(NodeConfigRest, SettingsAndEdsOverHttp) {
  StateDir dir;
  RestRig rig({}, [&](Config& c) { c.state_dir = dir.path.string(); });
  const std::string base = "/api/v1/networks/1/nodes/10";

  const auto get = rig.request("GET", base + "/config");
  ASSERT_EQ(get.status, 200) << get.body;
  EXPECT_EQ(get.json().at("source"), "config");
  EXPECT_EQ(get.json().at("settings").at("name"), "io-rack-1");

  const auto not_json = rig.request("PUT", base + "/config", "name: x");
  EXPECT_EQ(not_json.status, 400);
  const auto bad = rig.request("PUT", base + "/config", R"({"heartbeat-consumer-ms": -5})");
  EXPECT_EQ(bad.status, 400);
  EXPECT_EQ(bad.json().at("detail"),
            "request body: heartbeat-consumer-ms: '-5' is not auto, 0 (not watched) or a consumer time in ms "
            "(1..65535)");

  const auto put = rig.request("PUT", base + "/config", R"({"name": "io-left"})");
  ASSERT_EQ(put.status, 200) << put.body;
  EXPECT_EQ(put.json().at("source"), "state-dir");
  EXPECT_EQ(std::string(put.json().at("file").as_string()), (dir.path / "nodes/net1-node10.yaml").string());
  EXPECT_EQ(rig.request("GET", base).json().at("name"), "io-left");

  const auto eds_bad = rig.request("PUT", base + "/eds?name=vendor.eds",
                                   io_eds() + "\n[6001]\nParameterName=X\nObjectType=0x7\nDataType=0x0005\n"
                                              "AccessType=ro\nAccessType=rw\n",
                                   {"Content-Type: application/octet-stream"});
  EXPECT_EQ(eds_bad.status, 400);
  EXPECT_EQ(std::string(eds_bad.json().at("detail").as_string()).substr(0, 11), "vendor.eds:");
  EXPECT_FALSE(rig.request("GET", base).json().at("eds").as_bool()) << "nothing changed";

  const auto eds = rig.request("PUT", base + "/eds?name=io.eds", io_eds(), {"Content-Type: application/octet-stream"});
  ASSERT_EQ(eds.status, 200) << eds.body;
  EXPECT_TRUE(eds.json().at("warnings").is_array());
  EXPECT_EQ(eds.json().at("settings").at("name"), "io-left");
  EXPECT_EQ(rig.request("GET", base + "/od").status, 200) << "the OD browser has it at once";

  const auto gw = rig.request("GET", "/api/v1/gateway");
  const auto& nodes = gw.json().at("networks").at(0).at("nodes").as_array();
  ASSERT_EQ(nodes.size(), 3u);
  EXPECT_EQ(nodes[1].at("node"), 10);
  EXPECT_EQ(nodes[1].at("source"), "state-dir");
  EXPECT_EQ(nodes[0].at("source"), "config");

  const auto del = rig.request("DELETE", base + "/config");
  ASSERT_EQ(del.status, 200) << del.body;
  EXPECT_EQ(del.json().at("source"), "config");
  EXPECT_EQ(rig.request("GET", base).json().at("name"), "io-rack-1");
}

// A file may come as application/octet-stream; text/plain stays refused
// (a cross-site form could send it without a preflight).
TEST(NodeConfigRest, AFileBodyIsOctetStreamNotTextPlain) {
  StateDir dir;
  RestRig rig({}, [&](Config& c) { c.state_dir = dir.path.string(); });
  const auto r = rig.request("PUT", "/api/v1/networks/1/nodes/10/eds", io_eds(), {"Content-Type: text/plain"});
  EXPECT_EQ(r.status, 415);
}

}  // namespace
}  // namespace gateway::test
