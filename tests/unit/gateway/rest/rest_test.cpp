// The REST routes against the whole gateway on the simulated demo network
// (nodes 5: CiA 402 drive, 10 and 11: CiA 401 I/O), over real HTTP/1.1 on
// 127.0.0.1 (see rest_rig.hpp).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "canopen_gateway.pb.h"
#include "rest_rig.hpp"

namespace gateway {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::Not;
namespace json = boost::json;
using test::RestRig;

const std::string kNode5 = "/api/v1/networks/1/nodes/5";

TEST(Rest, GatewayAndNetwork) {
  RestRig rig;
  auto g = rig.request("GET", "/api/v1/gateway");
  ASSERT_EQ(g.status, 200) << g.body;
  EXPECT_EQ(g.content_type, "application/json");
  auto o = g.json().as_object();
  EXPECT_EQ(o.at("gatewayId").as_string(), "test");
  EXPECT_EQ(o.at("nodeId").to_number<int>(), 127);
  EXPECT_TRUE(o.at("version").is_string());
  EXPECT_TRUE(o.at("uptimeSeconds").is_number());
  ASSERT_EQ(o.at("networks").as_array().size(), 1U);
  EXPECT_EQ(o.at("networks").as_array()[0].as_object().at("bus").as_string(), "error-active");

  auto n = rig.request("GET", "/api/v1/networks/1");
  ASSERT_EQ(n.status, 200) << n.body;
  auto no = n.json().as_object();
  EXPECT_EQ(no.at("interface").as_string(), "demo");
  EXPECT_TRUE(no.at("simulated").as_bool());
  EXPECT_TRUE(no.at("counters").is_object());
  EXPECT_TRUE(no.at("sync").as_object().contains("producer"));
  EXPECT_TRUE(no.at("time").as_object().contains("producer"));
  // The bus state from the start, without a change (the demo bus has none).
  ASSERT_TRUE(no.contains("lastBusEvent")) << n.body;
  EXPECT_EQ(no.at("lastBusEvent").as_object().at("state").as_string(), "error-active");

  // The gateway's own node (node-ID 127) after start-up: pre-operational
  // (CiA 301 7.3.2.2.1) until an NMT start reaches it.
  EXPECT_EQ(no.at("nodeId").to_number<int>(), 127);
  EXPECT_EQ(no.at("nodeState").as_string(), "pre-operational") << n.body;
  ASSERT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/0/nmt", R"({"command": "start"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] {
    return rig.request("GET", "/api/v1/networks/1").json().as_object().at("nodeState").as_string() == "operational";
  }, 2s));

  auto missing = rig.request("GET", "/api/v1/networks/9");
  EXPECT_EQ(missing.status, 404);
  EXPECT_EQ(missing.content_type, "application/problem+json");
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/x").status, 400);
}

TEST(Rest, NodesAndOneNodeWithTpdoValues) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  ASSERT_TRUE(rig.run_until([&] { return !rig.app->cache().node(1, 5)->values.empty(); }));
  auto list = rig.request("GET", "/api/v1/networks/1/nodes");
  ASSERT_EQ(list.status, 200) << list.body;
  const auto& nodes = list.json().as_object().at("nodes").as_array();
  ASSERT_GE(nodes.size(), 3U);
  bool saw5 = false;
  for (const auto& v : nodes) {
    const auto& n = v.as_object();
    if (n.at("node").to_number<int>() != 5) continue;
    saw5 = true;
    EXPECT_EQ(n.at("name").as_string(), "drive-x");
    EXPECT_EQ(n.at("state").as_string(), "operational");
    EXPECT_TRUE(n.at("configured").as_bool());
    EXPECT_EQ(n.at("bootCount").to_number<int>(), 1);
    EXPECT_TRUE(n.at("lastHeartbeatAgeMs").is_number());
    // Read from the device at boot-up (1000h and 1018h; the drive is a CiA 402 servo drive).
    ASSERT_TRUE(n.at("identity").is_object()) << json::serialize(n);
    EXPECT_EQ(n.at("identity").as_object().at("deviceType").to_number<std::uint32_t>(), 0x00020192U);
    EXPECT_TRUE(n.contains("emcyCount"));
    EXPECT_TRUE(n.at("lastEmcy").is_null()) << "no EMCY since the boot-up";
  }
  EXPECT_TRUE(saw5);

  auto one = rig.request("GET", kNode5);
  ASSERT_EQ(one.status, 200) << one.body;
  bool statusword = false;
  for (const auto& v : one.json().as_object().at("values").as_array()) {
    const auto& e = v.as_object();
    if (e.at("index").to_number<int>() == 0x6041 && e.at("subIndex").to_number<int>() == 0) {
      statusword = true;
      EXPECT_EQ(e.at("name").as_string(), "Statusword");
      EXPECT_EQ(e.at("type").as_string(), "u16");
      EXPECT_TRUE(e.at("value").is_number());
      EXPECT_THAT(std::string(e.at("timestamp").as_string()), HasSubstr("T"));
    }
  }
  EXPECT_TRUE(statusword) << one.body;
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/99").status, 404);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/300").status, 400);
}

TEST(Rest, SdoReadWriteRoundTripAndErrors) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  auto w = rig.request("PUT", kNode5 + "/sdo/6060/0", R"({"value": 3})");
  ASSERT_EQ(w.status, 200) << w.body;
  auto r = rig.request("GET", kNode5 + "/sdo/0x6060/0");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.json().as_object().at("value").to_number<int>(), 3);
  EXPECT_EQ(r.json().as_object().at("type").as_string(), "i8");
  EXPECT_EQ(r.json().as_object().at("raw").as_string(), "03");
  // Below the EDS's low limit: 400, nothing sent.
  auto low = rig.request("PUT", kNode5 + "/sdo/6060/0", R"({"value": -3})");
  EXPECT_EQ(low.status, 400) << low.body;
  EXPECT_THAT(low.body, HasSubstr("low limit"));
  // 1000h with the h suffix and sub-index in 0x hex.
  auto dt = rig.request("GET", kNode5 + "/sdo/1000h/0x0");
  ASSERT_EQ(dt.status, 200) << dt.body;
  EXPECT_EQ(dt.json().as_object().at("value").to_number<std::uint32_t>() & 0xFFFF, 402U);

  // Not in the EDS: 404; with ?type= the device is asked and aborts: 422.
  EXPECT_EQ(rig.request("GET", kNode5 + "/sdo/5FFF/0").status, 404);
  auto abort = rig.request("GET", kNode5 + "/sdo/5FFF/0?type=u8");
  EXPECT_EQ(abort.status, 422) << abort.body;
  EXPECT_EQ(abort.content_type, "application/problem+json");
  EXPECT_EQ(abort.json().as_object().at("abortCode").as_string(), "0x06020000");
  // Out of range for i8: 400 before anything goes on the bus.
  EXPECT_EQ(rig.request("PUT", kNode5 + "/sdo/6060/0", R"({"value": 300})").status, 400);
  // Malformed path parts and bodies: 400.
  EXPECT_EQ(rig.request("GET", kNode5 + "/sdo/zz/0").status, 400);
  EXPECT_EQ(rig.request("GET", kNode5 + "/sdo/6060/256").status, 400);
  EXPECT_EQ(rig.request("GET", kNode5 + "/sdo/6060/0?type=u99").status, 400);
  EXPECT_EQ(rig.request("PUT", kNode5 + "/sdo/6060/0", R"({"value": )").status, 400);
  // Unknown network: 404.
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/2/nodes/5/sdo/1000/0").status, 404);
}

// Issue 13: a value refused for its type or the EDS limits names the object
// and the type, whether the type came from the EDS or the request, for SDO
// writes and RPDO values alike; nothing goes on the bus.
TEST(Rest, ValueErrorsNameTheObjectAndTheType) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  auto detail = [&](const std::string& method, const std::string& path, const std::string& body) {
    auto r = rig.request(method, path, body);
    EXPECT_EQ(r.status, 400) << r.body;
    if (r.status != 400) return std::string();
    return std::string(r.json().as_object().at("detail").as_string());
  };
  // The type from the EDS (6060h is i8 there).
  EXPECT_EQ(detail("PUT", kNode5 + "/sdo/6060/0", R"({"value": 300})"), "6060h sub 0: 300 is above 127 (i8)");
  EXPECT_THAT(detail("PUT", kNode5 + "/sdo/6060/0", R"({"value": -3})"),
              ::testing::StartsWith("6060h sub 0: -3 is below the low limit"));
  EXPECT_THAT(detail("PUT", kNode5 + "/sdo/6060/0", R"({"value": -3})"), HasSubstr("(i8)"));
  // The type from the request.
  EXPECT_EQ(detail("PUT", kNode5 + "/sdo/2000/0?type=u16", R"({"value": 70000})"),
            "2000h sub 0: 70000 is above 65535 (u16)");
  EXPECT_EQ(detail("PUT", kNode5 + "/sdo/1017/0", R"({"value": 70000, "type": "u16"})"),
            "1017h sub 0: 70000 is above 65535 (u16)");
  // An RPDO's mapped value (6040h, the Controlword, u16).
  EXPECT_EQ(detail("PUT", kNode5 + "/rpdo/1", R"({"values": [{"index": "0x6040", "value": 70000}]})"),
            "6040h sub 0: 70000 is above 65535 (u16)");
}

TEST(Rest, SdoTimeoutIs504) {
  RestRig rig;
  auto r = rig.request("GET", "/api/v1/networks/1/nodes/42/sdo/1000/0?type=u32");
  EXPECT_EQ(r.status, 504) << r.body;
  EXPECT_EQ(r.json().as_object().at("abortCode").as_string(), "0x05040000");
}

TEST(Rest, SdoReadInProtobuf) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  auto r = rig.request("GET", kNode5 + "/sdo/1000/0", {}, {"Accept: application/x-protobuf"});
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "application/x-protobuf");
  canopen::gateway::v1::SdoResponse m;
  ASSERT_TRUE(m.ParseFromString(r.body));
  EXPECT_EQ(m.type(), "u32");
  EXPECT_EQ(static_cast<std::uint32_t>(m.value().number_value()) & 0xFFFF, 402U);
  // Problems come as a protobuf Problem too.
  auto missing = rig.request("GET", kNode5 + "/sdo/5FFF/0", {}, {"Accept: application/x-protobuf"});
  EXPECT_EQ(missing.status, 404);
  EXPECT_EQ(missing.content_type, "application/x-protobuf");
  canopen::gateway::v1::Problem p;
  ASSERT_TRUE(p.ParseFromString(missing.body));
  EXPECT_EQ(p.status(), 404U);
  // A JSON body with a protobuf reply, and a protobuf body.
  auto w = rig.request("PUT", kNode5 + "/sdo/6060/0", R"({"value": 4})",
                       {"Content-Type: application/json", "Accept: application/x-protobuf"});
  ASSERT_EQ(w.status, 200) << w.body;
  EXPECT_EQ(w.content_type, "application/x-protobuf");
  canopen::gateway::v1::SdoWriteRequest req;
  req.mutable_value()->set_number_value(6);
  auto pw = rig.request("PUT", kNode5 + "/sdo/6060/0", req.SerializeAsString(),
                        {"Content-Type: application/x-protobuf"});
  ASSERT_EQ(pw.status, 200) << pw.body;
  auto back = rig.request("GET", kNode5 + "/sdo/6060/0");
  EXPECT_EQ(back.json().as_object().at("value").to_number<int>(), 6) << back.body;
}

// Content negotiation: a route with a protobuf message answers in it; one
// without answers JSON when JSON (or anything) is acceptable, else 406.
TEST(Rest, JsonOnlyRoutesRefuseAProtobufOnlyAccept) {
  RestRig rig;
  for (const char* path : {"/api/v1/gateway", "/api/v1/networks/1/nodes", "/api/v1/networks/1/nodes/5/od"}) {
    auto only = rig.request("GET", path, {}, {"Accept: application/x-protobuf"});
    EXPECT_EQ(only.status, 406) << path;
    EXPECT_EQ(only.content_type, "application/problem+json") << path;
    auto either = rig.request("GET", path, {}, {"Accept: application/x-protobuf, application/json;q=0.5"});
    EXPECT_EQ(either.status, 200) << path;
    EXPECT_EQ(either.content_type, "application/json") << path;
    EXPECT_EQ(rig.request("GET", path, {}, {"Accept: */*"}).status, 200) << path;
  }
}

TEST(Rest, NmtStopAndStartAll) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(10); }));
  auto stop = rig.request("POST", "/api/v1/networks/1/nodes/10/nmt", R"({"command": "stop"})");
  ASSERT_EQ(stop.status, 200) << stop.body;
  EXPECT_TRUE(rig.run_until([&] {
    const auto* n = rig.app->cache().node(1, 10);
    return n->state == canopen::NmtState::Stopped;
  }));
  auto list = rig.request("GET", "/api/v1/networks/1/nodes/10");
  EXPECT_EQ(list.json().as_object().at("state").as_string(), "stopped") << list.body;
  EXPECT_TRUE(rig.operational(5)) << "only node 10 was addressed";
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/0/nmt", R"({"command": "start"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] { return rig.operational(10); }));
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/10/nmt", R"({"command": "jump"})").status, 400);
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/128/nmt", R"({"command": "stop"})").status, 400);
  // A protobuf NmtRequest gets a protobuf NmtResponse.
  canopen::gateway::v1::NmtRequest req;
  req.set_command("preop");
  auto pb = rig.request("POST", "/api/v1/networks/1/nodes/11/nmt", req.SerializeAsString(),
                        {"Content-Type: application/x-protobuf"});
  ASSERT_EQ(pb.status, 200) << pb.body;
  EXPECT_EQ(pb.content_type, "application/x-protobuf");
  canopen::gateway::v1::NmtResponse resp;
  ASSERT_TRUE(resp.ParseFromString(pb.body));
  EXPECT_EQ(resp.node(), 11U);
  EXPECT_EQ(resp.command(), "preop");
  EXPECT_TRUE(rig.run_until([&] {
    return rig.app->cache().node(1, 11)->state == canopen::NmtState::PreOperational;
  }));
}

// Issue 12: in the no-token loopback mode any web page the operator opened
// could stop every node with a text/plain POST, and a DNS-rebinding page
// could read SDO values. Both are refused; the dashboard's own requests are not.
TEST(Rest, WebPagesCannotActOnTheLoopbackGateway) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  const std::string nmt = "/api/v1/networks/1/nodes/0/nmt";
  const std::string stop = R"({"command": "stop"})";
  auto r = rig.request("POST", nmt, stop, {"Content-Type: text/plain;charset=UTF-8", "Origin: https://evil.example"});
  EXPECT_EQ(r.status, 403) << r.body;
  r = rig.request("POST", nmt, stop, {"Content-Type: text/plain"});  // a browser that sends no Origin
  EXPECT_EQ(r.status, 415) << r.body;
  r = rig.request("GET", kNode5 + "/sdo/1018/1", {}, {"Host: rebind.attacker.example:" + std::to_string(rig.port)});
  EXPECT_EQ(r.status, 421) << r.body;
  EXPECT_FALSE(r.json().is_object() && r.json().as_object().contains("value")) << r.body;
  rig.io.run_for(100ms);
  EXPECT_TRUE(rig.all_operational()) << "a refused NMT stop was sent";
  const std::string own = "Origin: http://127.0.0.1:" + std::to_string(rig.port);
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/10/nmt", stop, {"Content-Type: application/json", own}).status,
            200);
  EXPECT_TRUE(rig.run_until([&] { return rig.app->cache().node(1, 10)->state == canopen::NmtState::Stopped; }));
  auto m = rig.request("GET", "/metrics");
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_http_requests_refused_total{reason=\"origin\"} 1\n"));
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_http_requests_refused_total{reason=\"media-type\"} 1\n"));
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_http_requests_refused_total{reason=\"host\"} 1\n"));
}

TEST(Rest, ObjectDictionaryFromTheEds) {
  RestRig rig;
  auto od = rig.request("GET", kNode5 + "/od");
  ASSERT_EQ(od.status, 200) << od.body.substr(0, 300);
  bool mode = false;
  for (const auto& v : od.json().as_object().at("objects").as_array()) {
    const auto& o = v.as_object();
    if (o.at("index").to_number<int>() != 0x6060) continue;
    mode = true;
    EXPECT_EQ(o.at("indexHex").as_string(), "6060");
    EXPECT_EQ(o.at("objectCode").as_string(), "VAR");
    const auto& sub = o.at("subs").as_array().at(0).as_object();
    EXPECT_EQ(sub.at("type").as_string(), "i8");
    EXPECT_TRUE(sub.contains("access"));
    EXPECT_TRUE(sub.contains("pdoMappable"));
    EXPECT_TRUE(sub.contains("default"));
  }
  EXPECT_TRUE(mode);
  EXPECT_FALSE(od.json().as_object().at("gateway").as_bool());
  auto none = rig.request("GET", "/api/v1/networks/1/nodes/42/od");
  EXPECT_EQ(none.status, 404);
  EXPECT_EQ(none.content_type, "application/problem+json");
}

// The gateway's own node (127 in the demo) has no EDS; its dictionary is the
// built-in one that SDO requests to 127 are answered from, so the dashboard
// can show and read it like any node's.
TEST(Rest, ObjectDictionaryOfTheGatewaysOwnNode) {
  RestRig rig;
  auto od = rig.request("GET", "/api/v1/networks/1/nodes/127/od");
  ASSERT_EQ(od.status, 200) << od.body.substr(0, 300);
  const auto& o = od.json().as_object();
  EXPECT_TRUE(o.at("gateway").as_bool());
  EXPECT_EQ(o.at("node").to_number<int>(), 127);
  EXPECT_EQ(o.at("productName").as_string(), "canopen-gateway");
  EXPECT_FALSE(o.at("dcf").as_bool());
  bool heartbeat = false, identity = false;
  for (const auto& v : o.at("objects").as_array()) {
    const auto& obj = v.as_object();
    const auto index = obj.at("index").to_number<int>();
    if (index == 0x1017) {
      heartbeat = true;
      const auto& sub = obj.at("subs").as_array().at(0).as_object();
      EXPECT_EQ(sub.at("type").as_string(), "u16");
      EXPECT_EQ(sub.at("access").as_string(), "rw");
    }
    if (index == 0x1018) {
      identity = true;
      EXPECT_EQ(obj.at("objectCode").as_string(), "RECORD");
      EXPECT_GE(obj.at("subs").as_array().size(), 5U);
    }
  }
  EXPECT_TRUE(heartbeat) << "1017h producer heartbeat time";
  EXPECT_TRUE(identity) << "1018h identity";
  // Every object listed can be read by SDO at that node-ID.
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/127/sdo/1017/0").status, 200);
  // Another node-ID with no EDS is still a 404.
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/nodes/126/od").status, 404);
}

TEST(Rest, EmcyListNewestFirst) {
  RestRig rig(100ms);  // the simulated devices raise and reset an EMCY every 100 ms
  ASSERT_TRUE(rig.run_until([&] {
    const auto* n = rig.app->cache().node(1, 5);
    return n != nullptr && n->emcy_count >= 2;
  }));
  auto e = rig.request("GET", kNode5 + "/emcy");
  ASSERT_EQ(e.status, 200) << e.body;
  const auto& o = e.json().as_object();
  ASSERT_GE(o.at("emcy").as_array().size(), 2U) << e.body;
  EXPECT_GE(o.at("emcyCount").to_number<int>(), 2);
  // The simulated devices alternate an error and its reset (0000h); only
  // the errors count as errors.
  const auto& list = o.at("emcy").as_array();
  int errors = 0;
  for (const auto& v : list) errors += v.as_object().at("errorCode").to_number<int>() != 0 ? 1 : 0;
  const auto error_count = o.at("emcyErrorCount").to_number<std::uint64_t>();
  EXPECT_GE(error_count, 1U);
  EXPECT_LT(error_count, o.at("emcyCount").to_number<std::uint64_t>()) << "a reset is no error";
  if (o.at("emcyCount").to_number<std::size_t>() == list.size()) {
    EXPECT_EQ(error_count, static_cast<std::uint64_t>(errors)) << e.body;
  }
  // The node list has the newest one as the node's last EMCY (or a newer one).
  auto nodes = rig.request("GET", "/api/v1/networks/1/nodes");
  for (const auto& v : nodes.json().as_object().at("nodes").as_array()) {
    const auto& n = v.as_object();
    if (n.at("node").to_number<int>() != 5) continue;
    ASSERT_TRUE(n.at("lastEmcy").is_object()) << nodes.body;
    EXPECT_GE(n.at("lastEmcy").as_object().at("seq").to_number<std::uint64_t>(),
              list[0].as_object().at("seq").to_number<std::uint64_t>());
    EXPECT_TRUE(n.at("lastEmcy").as_object().contains("errorRegister"));
  }
  const auto& first = o.at("emcy").as_array()[0].as_object();
  EXPECT_THAT(std::string(first.at("timestamp").as_string()), HasSubstr("Z"));
  EXPECT_EQ(first.at("manufacturerData").as_string().size(), 10U) << "5 bytes in hex";
  EXPECT_TRUE(first.at("description").is_string());
  std::uint64_t last = UINT64_MAX;
  for (const auto& v : o.at("emcy").as_array()) {
    const auto& m = v.as_object();
    EXPECT_TRUE(m.contains("errorCode"));
    EXPECT_TRUE(m.at("manufacturerData").is_string());
    const auto seq = m.at("seq").to_number<std::uint64_t>();
    EXPECT_LT(seq, last) << "newest first";
    last = seq;
  }
}

TEST(Rest, RpdoWrite) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  auto w = rig.request("PUT", kNode5 + "/rpdo/1", R"({"values": [{"index": "0x6040", "subIndex": 0, "value": 15}]})");
  ASSERT_EQ(w.status, 200) << w.body;
  EXPECT_EQ(w.json().as_object().at("cobId").to_number<int>(), 0x205);
  EXPECT_EQ(w.json().as_object().at("raw").as_string(), "0f00");
  // The drive got it: its Controlword reads back.
  auto r = rig.request("GET", kNode5 + "/sdo/6040/0");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.json().as_object().at("value").to_number<int>(), 15);
  auto raw = rig.request("PUT", kNode5 + "/rpdo/1", R"({"raw": "0600"})");
  EXPECT_EQ(raw.status, 200) << raw.body;
  EXPECT_EQ(rig.request("PUT", kNode5 + "/rpdo/1", R"({"raw": "06"})").status, 400);
  EXPECT_EQ(rig.request("PUT", kNode5 + "/rpdo/1", R"({"values": [{"index": "0x6040", "value": 70000}]})").status,
            400);
  EXPECT_EQ(rig.request("PUT", kNode5 + "/rpdo/1", R"({"values": [{"index": "0x6060", "value": 1}]})").status, 400);
  EXPECT_EQ(rig.request("PUT", kNode5 + "/rpdo/99", R"({"raw": "00"})").status, 404);
  EXPECT_EQ(rig.request("PUT", "/api/v1/networks/1/nodes/42/rpdo/1", R"({"raw": "00"})").status, 404);
}

TEST(Rest, Sync) {
  // The demo network produces SYNC every 100 ms; without that producer the
  // last counter seen is the one this test sent (on a slow machine a
  // periodic SYNC could come between the POST and the check).
  RestRig rig({}, [](Config& c) { c.networks.front().sync.period = {}; });
  auto s = rig.request("POST", "/api/v1/networks/1/sync");
  ASSERT_EQ(s.status, 200) << s.body;
  auto c = rig.request("POST", "/api/v1/networks/1/sync", R"({"counter": 7})");
  ASSERT_EQ(c.status, 200) << c.body;
  EXPECT_EQ(c.json().as_object().at("counter").to_number<int>(), 7);
  // The gateway's own services saw both (SYNC events in the cache).
  EXPECT_TRUE(rig.run_until([&] {
    const auto* n = rig.app->cache().network(1);
    return n->sync_count >= 2 && n->last_sync_counter == std::uint8_t{7};
  }, 2s)) << rig.app->cache().network(1)->sync_count;
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/sync", R"({"counter": 300})").status, 400);
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/3/sync").status, 404);
}

// The gateway's own node's settings as they are now: an SDO write changes
// them, an NMT reset communication of the own node (7.3.2.2.1) undoes it.
TEST(Rest, NetworkShowsTheOwnNodesSettingsAsTheyAreNow) {
  RestRig rig;
  auto heartbeat_ms = [&] {
    return rig.request("GET", "/api/v1/networks/1").json().as_object().at("heartbeatMs").to_number<int>();
  };
  EXPECT_EQ(heartbeat_ms(), 1000);
  ASSERT_EQ(rig.request("PUT", "/api/v1/networks/1/nodes/127/sdo/1017/0", R"({"value": 250})").status, 200);
  EXPECT_EQ(heartbeat_ms(), 250);
  ASSERT_EQ(rig.request("POST", "/api/v1/networks/1/nodes/127/nmt", R"({"command": "reset-comm"})").status, 200);
  EXPECT_TRUE(rig.run_until([&] { return heartbeat_ms() == 1000; }, 2s));
}

TEST(Rest, BusDownIs503) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  ASSERT_TRUE(rig.app->set_simulated_link(1, false));
  auto sdo = rig.request("GET", kNode5 + "/sdo/1000/0");
  EXPECT_EQ(sdo.status, 503) << sdo.body;
  EXPECT_EQ(sdo.content_type, "application/problem+json");
  EXPECT_EQ(rig.request("POST", kNode5 + "/nmt", R"({"command": "stop"})").status, 503);
  EXPECT_EQ(rig.request("POST", "/api/v1/networks/1/sync").status, 503);
  EXPECT_EQ(rig.request("PUT", kNode5 + "/rpdo/1", R"({"raw": "0600"})").status, 503);
  auto net = rig.request("GET", "/api/v1/networks/1");
  EXPECT_EQ(net.json().as_object().at("bus").as_string(), "down") << net.body;
  // Back up: requests work again.
  ASSERT_TRUE(rig.app->set_simulated_link(1, true));
  EXPECT_EQ(rig.request("GET", kNode5 + "/sdo/1000/0").status, 200);
}

TEST(Rest, MetricsWithSdoLatencyHistogram) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  ASSERT_EQ(rig.request("GET", kNode5 + "/sdo/1017/0").status, 200);
  auto m = rig.request("GET", "/metrics");
  ASSERT_EQ(m.status, 200);
  EXPECT_THAT(m.content_type, HasSubstr("text/plain"));
  EXPECT_THAT(m.body, HasSubstr("# TYPE canopen_gateway_sdo_latency_seconds histogram\n"));
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_sdo_latency_seconds_bucket{le=\"+Inf\"} "));
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_sdo_latency_seconds_count "));
  EXPECT_THAT(m.body, ::testing::Not(HasSubstr("canopen_gateway_sdo_latency_seconds_count 0\n")));
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_sdo_requests_total 1\n"));
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_request_auth_failures_total 0\n"));
}

// /metrics writes every family once, in the order it always has (each
// component registers its own on the App's registry; the server's and the
// uptime last), so scrapers and diffs of the text see no change.
TEST(Rest, MetricsFamiliesInTheirOrder) {
  RestRig rig;
  auto m = rig.request("GET", "/metrics");
  ASSERT_EQ(m.status, 200);
  std::vector<std::string> families;
  for (std::size_t at = m.body.find("# HELP "); at != std::string::npos; at = m.body.find("# HELP ", at + 1))
    families.push_back(m.body.substr(at + 7, m.body.find(' ', at + 7) - at - 7));
  const std::vector<std::string> expected = {
      "canopen_gateway_build_info", "canopen_gateway_can_frames_total", "canopen_gateway_can_frames_dropped_total",
      "canopen_gateway_can_error_frames_total", "canopen_gateway_can_reopens_total", "canopen_gateway_bus_state",
      "canopen_gateway_network_events_total", "canopen_gateway_bus_load_percent", "canopen_gateway_sdo_requests_total", "canopen_gateway_sdo_aborts_total",
      "canopen_gateway_sdo_timeouts_total", "canopen_gateway_nmt_commands_total", "canopen_gateway_sdo_latency_seconds",
      "canopen_gateway_request_auth_failures_total", "canopen_gateway_requests_limited_total",
      "canopen_gateway_lss_operations_total", "canopen_gateway_lss_node_ids_assigned_total",
      "canopen_gateway_maintenance_operations_total",
      "canopen_gateway_events_published_total", "canopen_gateway_mqtt_enabled",
      "canopen_gateway_history_bytes", "canopen_gateway_history_max_bytes", "canopen_gateway_history_objects",
      "canopen_gateway_history_refused_objects_total",  // issue 18: the PDO value history
      "canopen_gateway_websocket_clients",
      "canopen_gateway_websocket_messages_total", "canopen_gateway_http_responses_total",
      "canopen_gateway_http_connections", "canopen_gateway_http_connections_refused_total",
      "canopen_gateway_http_connections_evicted_total", "canopen_gateway_http_header_timeouts_total",
      "canopen_gateway_http_requests_refused_total", "canopen_gateway_uptime_seconds"};
  EXPECT_EQ(families, expected);
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_mqtt_enabled 0\n"));
  EXPECT_THAT(m.body, HasSubstr("canopen_gateway_bus_state{network=\"1\",interface=\"demo\",state=\"error-active\"} 1\n"));
}

// Issue 15 item 5: GET /api/v1/gateway carries the Sparkplug edge node's
// session when it is configured (here without a broker: offline, the bdSeq
// of its first CONNECT attempt, no birth yet), and /metrics its families.
TEST(Rest, GatewayShowsTheSparkplugSessionAndItsMetrics) {
  RestRig plain;
  EXPECT_FALSE(plain.request("GET", "/api/v1/gateway").json().as_object().contains("sparkplug"))
      << "only when configured";
  EXPECT_THAT(plain.request("GET", "/metrics").body, Not(HasSubstr("canopen_gateway_sparkplug_")));

  RestRig rig({}, [](Config& c) {
    c.sparkplug.enabled = true;
    c.sparkplug.group_id = "plant1";
    c.sparkplug.edge_node_id = "test";
    c.sparkplug.primary_host_id = "scada-1";
    c.sparkplug.mqtt.server_uri = "tcp://127.0.0.1:1";  // nobody listens
    c.sparkplug.mqtt.client_id = "test-spb";
  });
  rig.io.run_for(100ms);  // the first CONNECT attempt fails
  auto g = rig.request("GET", "/api/v1/gateway");
  ASSERT_EQ(g.status, 200) << g.body;
  const auto& sp = g.json().as_object().at("sparkplug").as_object();
  EXPECT_EQ(sp.at("groupId").as_string(), "plant1");
  EXPECT_EQ(sp.at("edgeNodeId").as_string(), "test");
  EXPECT_EQ(sp.at("state").as_string(), "offline");
  EXPECT_FALSE(sp.at("connected").as_bool());
  EXPECT_TRUE(sp.at("broker").is_null());
  EXPECT_TRUE(sp.at("mqttVersion").is_null());
  EXPECT_EQ(sp.at("bdSeq").to_number<int>(), 0) << "the first CONNECT's (no state dir: starts at 0)";
  EXPECT_TRUE(sp.at("lastRebirth").is_null());
  EXPECT_EQ(sp.at("primaryHost").as_object().at("id").as_string(), "scada-1");
  EXPECT_FALSE(sp.at("primaryHost").as_object().at("online").as_bool());
  EXPECT_EQ(sp.at("messagesPublished").to_number<int>(), 0);
  EXPECT_EQ(sp.at("commandsReceived").to_number<int>(), 0);

  const auto m = rig.request("GET", "/metrics").body;
  EXPECT_THAT(m, HasSubstr("canopen_gateway_sparkplug_connected 0\n"));
  EXPECT_THAT(m, HasSubstr("canopen_gateway_sparkplug_broker_connected{uri=\"tcp://127.0.0.1:1\"} 0\n"));
  EXPECT_THAT(m, HasSubstr("canopen_gateway_sparkplug_online 0\n"));
  EXPECT_THAT(m, HasSubstr("canopen_gateway_sparkplug_bdseq 0\n"));
  for (const char* type : {"NBIRTH", "NDEATH", "DBIRTH", "DDEATH", "NDATA", "DDATA"})
    EXPECT_THAT(m, HasSubstr(std::string("canopen_gateway_sparkplug_messages_published_total{type=\"") + type +
                             "\"} 0\n"));
  for (const char* family : {"canopen_gateway_sparkplug_rebirths_total 0\n", "canopen_gateway_sparkplug_commands_total 0\n",
                             "canopen_gateway_sparkplug_dropped_total 0\n",
                             "canopen_gateway_sparkplug_reconnects_total 0\n",
                             "canopen_gateway_sparkplug_published_bytes_total 0\n"})
    EXPECT_THAT(m, HasSubstr(family));
}

// Issue 27 item 2: GET /api/v1/gateway carries the native MQTT connection
// when MQTT is on: here a list of two brokers nobody listens on, so not
// connected and no broker; /metrics has one series per broker. (Connected,
// the broker it reached: app_mqtt_test.cpp.)
TEST(Rest, GatewayShowsTheMqttConnectionAndItsBrokers) {
  RestRig plain;
  EXPECT_FALSE(plain.request("GET", "/api/v1/gateway").json().as_object().contains("mqtt")) << "only when configured";
  const auto queue = std::filesystem::temp_directory_path() / ("rest_mqtt_" + std::to_string(::getpid()));
  {
    RestRig rig({}, [&](Config& c) {
      c.mqtt.enabled = true;
      c.mqtt.server_uri = "mqtt://127.0.0.1:1";  // nobody listens
      c.mqtt.standby_uris = {"tcp://127.0.0.1:2"};
      c.mqtt.client_id = "test-mqtt";
      c.mqtt.queue.dir = queue;
    });
    rig.io.run_for(100ms);  // the first round of attempts fails
    auto g = rig.request("GET", "/api/v1/gateway");
    ASSERT_EQ(g.status, 200) << g.body;
    const auto& m = g.json().as_object().at("mqtt").as_object();
    EXPECT_FALSE(m.at("connected").as_bool());
    EXPECT_TRUE(m.at("broker").is_null());
    EXPECT_TRUE(m.at("mqttVersion").is_null());
    EXPECT_EQ(m.at("brokers"), (json::array{"tcp://127.0.0.1:1", "tcp://127.0.0.1:2"})) << "normalized, in order";
    EXPECT_EQ(m.at("reconnects").to_number<int>(), 0);
    const auto metrics = rig.request("GET", "/metrics").body;
    EXPECT_THAT(metrics, HasSubstr("canopen_gateway_mqtt_broker_connected{uri=\"tcp://127.0.0.1:1\"} 0\n"));
    EXPECT_THAT(metrics, HasSubstr("canopen_gateway_mqtt_broker_connected{uri=\"tcp://127.0.0.1:2\"} 0\n"));
  }
  std::filesystem::remove_all(queue);
}

}  // namespace
}  // namespace gateway
