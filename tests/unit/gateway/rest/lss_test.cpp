// LSS over REST (contract "LSS master (CiA 305), REST (role admin)") against
// the whole gateway on the demo network, whose fourth device starts without
// a node-ID and answers only LSS until it gets one: scan, list, assign, the
// device boots with its new node-ID and is started like any node.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "auth/auth.hpp"
#include "rest_rig.hpp"

namespace gateway {
namespace {

using ::testing::HasSubstr;
using test::RestRig;
namespace json = boost::json;

const std::string kLss = "/api/v1/networks/1/lss";
// A short fastscan step window: the in-process bus answers at once, and a
// full scan is 133 windows (facts C.2).
const std::string kQuickScan = R"({"timeoutMs": 5})";

TEST(RestLss, ScanListAssignAndTheDeviceBootsWithItsNodeIdAndIsStarted) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  auto scan = rig.request("POST", kLss + "/fastscan", kQuickScan);
  ASSERT_EQ(scan.status, 200) << scan.body;
  const auto identity = scan.json().as_object().at("identity").as_object();
  EXPECT_EQ(identity.at("vendorId").as_int64(), 0x5A1) << "the demo I/O module's 1018h sub 1";
  for (const char* k : {"productCode", "revisionNumber", "serialNumber"}) EXPECT_TRUE(identity.contains(k)) << k;

  auto list = rig.request("GET", kLss + "/devices");
  ASSERT_EQ(list.status, 200);
  const auto& devices = list.json().as_object().at("devices").as_array();
  ASSERT_EQ(devices.size(), 1u);
  EXPECT_EQ(devices[0].as_object().at("identity").as_object(), identity);
  EXPECT_TRUE(devices[0].as_object().at("nodeId").is_null());

  json::object body;
  body["identity"] = identity;
  body["nodeId"] = 20;
  body["store"] = true;
  auto assign = rig.request("POST", kLss + "/configure", json::serialize(body));
  ASSERT_EQ(assign.status, 200) << assign.body;
  EXPECT_EQ(assign.json().as_object().at("nodeId").as_int64(), 20);
  EXPECT_TRUE(assign.json().as_object().at("stored").as_bool());
  // A normal boot-up at the new node-ID (CiA 305: it left configuration
  // state with a pending node-ID), then an NMT start like any node.
  ASSERT_TRUE(rig.run_until([&] { return rig.app->cache().node(1, 20) != nullptr; })) << "no boot-up of node 20";
  auto nodes = rig.request("GET", "/api/v1/networks/1/nodes/20");
  ASSERT_EQ(nodes.status, 200) << nodes.body;
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/20/nmt", R"({"command": "start"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] { return rig.operational(20); }));
  list = rig.request("GET", kLss + "/devices");
  EXPECT_EQ(list.json().as_object().at("devices").as_array().at(0).as_object().at("nodeId").as_int64(), 20);

  // Nobody is unconfigured any more: 404, and the list says so.
  auto none = rig.request("POST", kLss + "/fastscan", kQuickScan);
  EXPECT_EQ(none.status, 404) << none.body;
  EXPECT_THAT(none.body, HasSubstr("no unconfigured device answered"));
  EXPECT_TRUE(rig.request("GET", kLss + "/devices").json().as_object().at("devices").as_array().empty());
  EXPECT_TRUE(rig.all_operational()) << "the other nodes did not notice";
}

TEST(RestLss, AssignAllGivesTheNewDeviceTheFirstFreeNodeId) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  // 5 is the drive's: the next free one is 6.
  auto r = rig.request("POST", kLss + "/assign-all", R"({"firstNodeId": 5, "store": true, "timeoutMs": 5})");
  ASSERT_EQ(r.status, 200) << r.body;
  const auto& a = r.json().as_object().at("assignments").as_array();
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].as_object().at("nodeId").as_int64(), 6);
  EXPECT_TRUE(rig.run_until([&] { return rig.app->cache().node(1, 6) != nullptr; })) << "no boot-up of node 6";
}

TEST(RestLss, AnAbsentIdentityIs504AndBadBodiesAre400) {
  RestRig rig;
  auto absent = rig.request(
      "POST", kLss + "/configure",
      R"({"identity": {"vendorId": 1, "productCode": 2, "revisionNumber": 3, "serialNumber": 4}, "nodeId": 30})");
  EXPECT_EQ(absent.status, 504) << absent.body;
  EXPECT_THAT(absent.body, HasSubstr("switch state selective"));
  auto bad = rig.request("POST", kLss + "/configure", R"({"identity": {"vendorId": 1}, "nodeId": 30})");
  EXPECT_EQ(bad.status, 400);
  EXPECT_THAT(bad.body, HasSubstr("identity.productCode"));
  EXPECT_EQ(rig.request("POST", kLss + "/configure",
                        R"({"identity": {"vendorId": "0x5A1", "productCode": 1, "revisionNumber": 1,
                            "serialNumber": 1}, "nodeId": 128})")
                .status,
            400);
  auto rate = rig.request("POST", kLss + "/configure",
                          R"({"identity": {"vendorId": 1, "productCode": 2, "revisionNumber": 3, "serialNumber": 4},
                              "nodeId": 30, "bitrate": 300000})");
  EXPECT_EQ(rate.status, 400);
  EXPECT_THAT(rate.body, HasSubstr("CiA 301 table"));
  auto key = rig.request("POST", kLss + "/assign-all", R"({"firstNode": 5})");
  EXPECT_EQ(key.status, 400);
  EXPECT_THAT(key.body, HasSubstr("unknown key \\\"firstNode\\\""));
  EXPECT_EQ(rig.request("POST", kLss + "/fastscan", R"({"timeoutMs": 0})").status, 400);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/9/lss/devices").status, 404);
}

TEST(RestLss, EveryLssRouteNeedsAdmin) {
  RestRig rig({}, [](Config& c) {
    c.http.auth = true;
    c.http.tokens.push_back({"olga", Role::Operator, auth::sha256_hex("operator-secret")});
    c.http.tokens.push_back({"ada", Role::Admin, auth::sha256_hex("admin-secret")});
  });
  const std::vector<std::string> op = {"Authorization: Bearer operator-secret"};
  const std::vector<std::string> admin = {"Authorization: Bearer admin-secret"};
  EXPECT_EQ(rig.request("POST", kLss + "/fastscan", kQuickScan, op).status, 403);
  EXPECT_EQ(rig.request("POST", kLss + "/assign-all", R"({"firstNodeId": 20})", op).status, 403);
  EXPECT_EQ(rig.request("GET", kLss + "/devices", {}, op).status, 403);
  EXPECT_EQ(rig.request("GET", kLss + "/devices", {}, admin).status, 200);
}

}  // namespace
}  // namespace gateway
