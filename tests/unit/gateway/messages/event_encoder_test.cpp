// encode_event / encode_status: topics, retained flags, contract field
// names, and for every kind: our direct JSON == protobuf's own JSON of the
// binary message (by value), and JSON -> message == the binary message.
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <google/protobuf/util/time_util.h>
#include <gtest/gtest.h>

#include <boost/json/parse.hpp>
#include <boost/json/serialize.hpp>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "canopen/json_value.hpp"
#include "canopen/sdo/abort.hpp"
#include "canopen_gateway.pb.h"
#include "messages/event_encoder.hpp"
#include "messages/json_text.hpp"

namespace {

namespace pb = ::canopen::gateway::v1;
namespace json = boost::json;
using namespace gateway;
using canopen::DataType;
using canopen::Value;

// JSON equality where numbers compare by value (1591 == 1591.0 == 1.591E3).
bool json_equal(const json::value& a, const json::value& b) {
  if (a.is_number() && b.is_number()) {
    if (a.is_int64() && b.is_int64()) return a.get_int64() == b.get_int64();
    if (a.is_uint64() && b.is_uint64()) return a.get_uint64() == b.get_uint64();
    return a.to_number<double>() == b.to_number<double>();
  }
  if (a.kind() != b.kind()) return false;
  if (a.is_object()) {
    const auto& oa = a.get_object();
    const auto& ob = b.get_object();
    if (oa.size() != ob.size()) return false;
    for (const auto& kv : oa) {
      const auto* other = ob.if_contains(kv.key());
      if (!other || !json_equal(kv.value(), *other)) return false;
    }
    return true;
  }
  if (a.is_array()) {
    const auto& xa = a.get_array();
    const auto& xb = b.get_array();
    if (xa.size() != xb.size()) return false;
    for (std::size_t i = 0; i < xa.size(); ++i) {
      if (!json_equal(xa[i], xb[i])) return false;
    }
    return true;
  }
  return a == b;
}

std::string protobuf_json(const google::protobuf::Message& m) {
  google::protobuf::util::JsonPrintOptions po;
  po.always_print_primitive_fields = true;
  std::string s;
  EXPECT_TRUE(google::protobuf::util::MessageToJsonString(m, &s, po).ok());
  return s;
}

// The checks every encoded event must pass; returns the decoded message.
template <typename M>
M check_consistent(const EncodedEvent& e) {
  M m;
  EXPECT_TRUE(m.ParseFromString(e.binary));
  const std::string theirs = protobuf_json(m);
  std::error_code ec;
  const json::value mine_v = json::parse(e.json, ec);
  EXPECT_FALSE(ec) << e.json;
  EXPECT_TRUE(json_equal(mine_v, json::parse(theirs))) << "ours:     " << e.json << "\nprotobuf: " << theirs;
  M back;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(e.json, &back).ok()) << e.json;
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(m, back)) << e.json;
  // The binary is exactly what protobuf serializes for it.
  std::string again;
  EXPECT_TRUE(back.SerializeToString(&again));
  EXPECT_EQ(again, e.binary);
  // And the envelope of it, in both encodings.
  pb::EventEnvelope env;
  EXPECT_TRUE(env.ParseFromString(envelope_binary(e)));
  EXPECT_EQ(env.kind(), std::string(to_string(e.kind)));
  EXPECT_EQ(env.topic(), e.topic);
  const std::string env_json = envelope_json(e);
  // The WebSocket frames are built once, with the event.
  EXPECT_EQ(e.ws_json, env_json);
  EXPECT_EQ(e.ws_binary, envelope_binary(e));
  EXPECT_TRUE(json_equal(json::parse(env_json), json::parse(protobuf_json(env)))) << env_json;
  pb::EventEnvelope env_back;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(env_json, &env_back).ok());
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(env, env_back));
  return m;
}

json::object parse_obj(const std::string& s) { return json::parse(s).as_object(); }

const EncodeContext kCtx{"gw1"};
// 2026-11-22T10:15:30.123456Z
const auto kTime = std::chrono::system_clock::time_point{std::chrono::microseconds{1795342530123456LL}};

canopen::Event event(canopen::EventBody body, std::uint64_t seq = 42) {
  canopen::Event ev;
  ev.seq = seq;
  ev.timestamp = kTime;
  ev.body = std::move(body);
  return ev;
}

canopen::PdoEvent two_value_pdo() {
  canopen::PdoEvent p;
  p.node = 5;
  p.number = 3;
  p.cob_id = 0x385;
  p.raw = {0x37, 0x06, 0xB8, 0x0B, 0x00, 0x00};
  p.values.push_back({0x6041, 0, "Statusword", Value::of_unsigned(DataType::Unsigned16, 1591)});
  p.values.push_back({0x6064, 0, "Position actual value", Value::of_signed(DataType::Integer32, 3000)});
  return p;
}

TEST(EncodeEvent, TpdoTopicAndFields) {
  const auto e = encode_event(event(two_value_pdo()), 1, kCtx);
  EXPECT_EQ(e->kind, EventKind::Tpdo);
  EXPECT_EQ(e->topic, "canopen/gw1/1/5/tpdo/3");
  EXPECT_FALSE(e->retained);
  EXPECT_EQ(e->network, 1u);
  EXPECT_EQ(e->node, 5);
  EXPECT_EQ(e->seq, 42u);
  const auto m = check_consistent<pb::PdoEvent>(*e);
  EXPECT_EQ(m.values_size(), 2);
  const auto j = parse_obj(e->json);
  EXPECT_EQ(j.at("seq"), "42");
  EXPECT_EQ(j.at("timestamp"), "2026-11-22T10:15:30.123456Z");
  EXPECT_EQ(j.at("network"), 1);
  EXPECT_EQ(j.at("node"), 5);
  EXPECT_EQ(j.at("tpdo"), 3);
  EXPECT_EQ(j.at("cobId"), 0x385);
  EXPECT_EQ(j.at("raw"), "3706b80b0000");
  EXPECT_FALSE(j.contains("error"));
  EXPECT_FALSE(j.contains("mpdo"));
  const auto& v0 = j.at("values").as_array().at(0).as_object();
  EXPECT_EQ(v0.at("index"), 0x6041);
  EXPECT_EQ(v0.at("subIndex"), 0);
  EXPECT_EQ(v0.at("name"), "Statusword");
  EXPECT_EQ(v0.at("type"), "u16");
  EXPECT_EQ(v0.at("value"), 1591);
  EXPECT_EQ(j.at("values").as_array().at(1).as_object().at("value"), 3000);
}

// Without protobuf (nobody wants it) a PDO's JSON and WebSocket JSON
// envelope are exactly the same; only the binary forms are left out.
TEST(EncodeEvent, TpdoWithoutProtobufHasTheSameJson) {
  std::vector<canopen::PdoEvent> cases(4, two_value_pdo());
  cases[1].error = "length 1 does not match the mapping (8 bytes)";
  cases[1].values.push_back({0x2100, 1, std::string("na\xFFme"), Value::of_real64(std::nan(""))});
  cases[1].values.push_back({0x2101, 0, "s", Value::of_string("tab\t\"q\"")});
  cases[2].mpdo = canopen::MpdoInfo{false, 5, 0x6041, 0, 0x2000, 1};
  cases[3].mpdo = canopen::MpdoInfo{true, 0, 0x6200, 1, std::nullopt, std::nullopt};
  EncodeContext json_only = kCtx;
  json_only.protobuf = false;
  for (const auto& p : cases) {
    const auto full = encode_event(event(p), 1, kCtx);
    const auto lean = encode_event(event(p), 1, json_only);
    EXPECT_EQ(lean->json, full->json);
    EXPECT_EQ(lean->ws_json, full->ws_json);
    EXPECT_EQ(lean->topic, full->topic);
    EXPECT_TRUE(lean->binary.empty());
    EXPECT_TRUE(lean->ws_binary.empty());
    check_consistent<pb::PdoEvent>(*full);
  }
}

TEST(EncodeEvent, TpdoEveryValueShape) {
  canopen::PdoEvent p;
  p.node = 127;
  p.number = 512;
  p.cob_id = 0x1FF;
  p.raw = {0x01};
  p.error = "length 1 does not match the mapping (8 bytes)";
  std::vector<Value> vals = {
      Value::of_bool(true),
      Value::of_signed(DataType::Integer64, std::numeric_limits<std::int64_t>::min()),
      Value::of_unsigned(DataType::Unsigned64, std::numeric_limits<std::uint64_t>::max()),
      Value::of_signed(DataType::Integer56, -36028797018963968LL),
      Value::of_unsigned(DataType::Unsigned48, 0xFFFFFFFFFFFFULL),
      Value::of_signed(DataType::Integer48, -140737488355328LL),
      Value::of_real32(0.1f),
      Value::of_real32(std::numeric_limits<float>::infinity()),
      Value::of_real64(-1e300),
      Value::of_real64(std::nan("")),
      Value::of_string("tab\t\"quoted\" \x01 \xC3\xA9"),
      Value::of_string(std::string("latin1 \xE9")),
      Value::of_bytes(DataType::OctetString, {0x0A, 0xFF}),
      Value::of_bytes(DataType::Domain, {}),
      Value{DataType::UnicodeString, std::u16string(u"\u00e9t\u00e9")},
      Value{DataType::TimeOfDay, canopen::TimeOfDay{36930123, 15296}},
      Value{DataType::TimeDifference, canopen::TimeOfDay{5, 2}},
  };
  for (std::size_t i = 0; i < vals.size(); ++i) {
    p.values.push_back({static_cast<std::uint16_t>(0x2000 + i), static_cast<std::uint8_t>(i), "v", vals[i]});
  }
  p.values.push_back({0x2100, 1, std::string("na\xFFme"), Value::of_bool(false)});
  const auto e = encode_event(event(p, 18446744073709551615ULL), 65535, kCtx);
  EXPECT_EQ(e->topic, "canopen/gw1/65535/127/tpdo/512");
  check_consistent<pb::PdoEvent>(*e);
  const auto j = parse_obj(e->json);
  EXPECT_EQ(j.at("seq"), "18446744073709551615");
  EXPECT_EQ(j.at("error"), "length 1 does not match the mapping (8 bytes)");
  const auto& values = j.at("values").as_array();
  ASSERT_EQ(values.size(), vals.size() + 1);
  // Each value has exactly the shape of value_to_json (the contract's rules).
  for (std::size_t i = 0; i < vals.size(); ++i) {
    const auto& vj = values[i].as_object();
    EXPECT_EQ(vj.at("type"), json::value(canopen::cia309_name(vals[i].type)));
    EXPECT_TRUE(json_equal(vj.at("value"), canopen::value_to_json(vals[i])))
        << i << ": " << json::serialize(vj.at("value")) << " vs " << json::serialize(canopen::value_to_json(vals[i]));
  }
  EXPECT_EQ(values[1].at("value"), "-9223372036854775808");
  EXPECT_EQ(values[2].at("value"), "18446744073709551615");
  EXPECT_EQ(values[4].at("value"), 281474976710655);
  EXPECT_EQ(values[6].at("value").as_double(), 0.1);
  EXPECT_EQ(values[7].at("value"), "inf");
  EXPECT_EQ(values[9].at("value"), "nan");
  EXPECT_EQ(values[12].at("value"), "0aff");
  EXPECT_EQ(values[13].at("value"), "");
  EXPECT_EQ(values[vals.size()].at("name"), "na\xC3\xBFme");  // Latin-1 read as such
}

TEST(EncodeEvent, Mpdo) {
  auto p = two_value_pdo();
  p.values.resize(1);
  p.mpdo = canopen::MpdoInfo{false, 5, 0x6041, 0, 0x2000, 1};
  auto e = encode_event(event(p), 2, kCtx);
  check_consistent<pb::PdoEvent>(*e);
  auto j = parse_obj(e->json);
  EXPECT_EQ(j.at("mpdo"), json::parse(R"({"mode":"sam","address":5,"index":24641,"subIndex":0,
                                          "localIndex":8192,"localSubIndex":1})"));
  p.mpdo = canopen::MpdoInfo{true, 0, 0x6200, 1, std::nullopt, std::nullopt};
  e = encode_event(event(p), 2, kCtx);
  check_consistent<pb::PdoEvent>(*e);
  j = parse_obj(e->json);
  EXPECT_EQ(j.at("mpdo"), json::parse(R"({"mode":"dam","address":0,"index":25088,"subIndex":1})"));
}

TEST(EncodeEvent, UnclaimedPdo) {
  canopen::PdoEvent p;
  p.cob_id = 0x1A5;
  p.raw = {0xDE, 0xAD};
  auto e = encode_event(event(p), 3, kCtx);
  EXPECT_EQ(e->kind, EventKind::UnclaimedPdo);
  EXPECT_EQ(e->topic, "canopen/gw1/3/pdo/1A5");
  EXPECT_FALSE(e->retained);
  EXPECT_EQ(e->node, 0);
  check_consistent<pb::UnclaimedPdo>(*e);
  EXPECT_EQ(parse_obj(e->json), json::parse(R"({"seq":"42","timestamp":"2026-11-22T10:15:30.123456Z",
      "network":3,"node":0,"cobId":421,"raw":"dead"})"));
  p.cob_id = 0x5;
  EXPECT_EQ(encode_event(event(p), 3, kCtx)->topic, "canopen/gw1/3/pdo/005");
  p.cob_id = 0x80000000u | 0x1ABCDEF0u;  // 29-bit, with a flag bit
  e = encode_event(event(p), 3, kCtx);
  EXPECT_EQ(e->topic, "canopen/gw1/3/pdo/1ABCDEF0");
  check_consistent<pb::UnclaimedPdo>(*e);
}

TEST(EncodeEvent, Emcy) {
  canopen::EmcyEvent em;
  em.node = 10;
  em.error_code = 0x8110;
  em.error_register = 0x11;
  em.manufacturer = {0x01, 0x02, 0x03, 0xAB, 0xCD};
  em.description = "CAN overrun (objects lost)";
  const auto e = encode_event(event(em), 1, kCtx);
  EXPECT_EQ(e->kind, EventKind::Emcy);
  EXPECT_EQ(e->topic, "canopen/gw1/1/10/emcy");
  EXPECT_FALSE(e->retained);
  check_consistent<pb::EmcyEvent>(*e);
  const auto j = parse_obj(e->json);
  EXPECT_EQ(j.at("errorCode"), 0x8110);
  EXPECT_EQ(j.at("errorRegister"), 0x11);
  EXPECT_EQ(j.at("manufacturerData"), "010203abcd");
  EXPECT_EQ(j.at("description"), "CAN overrun (objects lost)");
}

TEST(EncodeEvent, HeartbeatAndState) {
  const auto hb = encode_event(event(canopen::HeartbeatEvent{7, canopen::NmtState::Operational}), 1, kCtx);
  EXPECT_EQ(hb->kind, EventKind::Heartbeat);
  EXPECT_EQ(hb->topic, "canopen/gw1/1/7/heartbeat");
  EXPECT_FALSE(hb->retained);
  check_consistent<pb::HeartbeatEvent>(*hb);
  EXPECT_EQ(parse_obj(hb->json).at("state"), "operational");

  using C = canopen::NodeStateEvent::Cause;
  using S = canopen::NmtState;
  struct Case {
    canopen::NodeStateEvent ev;
    const char* state;
    const char* previous;  // nullptr: absent
    const char* cause;
  };
  const Case cases[] = {
      {{7, S::Initialising, std::nullopt, C::BootUp}, "initialising", nullptr, "boot-up"},
      {{7, S::PreOperational, S::Initialising, C::Heartbeat}, "pre-operational", "initialising", "heartbeat"},
      {{7, S::Operational, S::PreOperational, C::NodeGuarding}, "operational", "pre-operational", "node-guarding"},
      {{7, std::nullopt, S::Operational, C::Lost}, "lost", "operational", "lost"},
      {{7, S::Stopped, std::nullopt, C::Recovered}, "stopped", nullptr, "recovered"},
  };
  for (const auto& c : cases) {
    const auto e = encode_event(event(c.ev), 1, kCtx);
    EXPECT_EQ(e->kind, EventKind::State);
    EXPECT_EQ(e->topic, "canopen/gw1/1/7/state");
    EXPECT_TRUE(e->retained);
    check_consistent<pb::NodeStateEvent>(*e);
    const auto j = parse_obj(e->json);
    EXPECT_EQ(j.at("state"), c.state);
    EXPECT_EQ(j.at("cause"), c.cause);
    if (c.previous) {
      EXPECT_EQ(j.at("previous"), c.previous);
    } else {
      EXPECT_FALSE(j.contains("previous"));
    }
  }
}

TEST(EncodeEvent, Bus) {
  canopen::can::BusEvent b;
  b.state = canopen::can::BusState::ErrorPassive;
  b.previous = canopen::can::BusState::ErrorWarning;
  b.cause = canopen::can::BusEventCause::ErrorFrame;
  b.tx_error_counter = 130;
  b.rx_error_counter = 7;
  b.dropped = 12;
  const auto e = encode_event(event(b), 2, kCtx);
  EXPECT_EQ(e->kind, EventKind::Bus);
  EXPECT_EQ(e->topic, "canopen/gw1/2/bus");
  EXPECT_TRUE(e->retained);
  EXPECT_EQ(e->node, 0);
  check_consistent<pb::BusStateEvent>(*e);
  EXPECT_EQ(parse_obj(e->json), json::parse(R"({"seq":"42","timestamp":"2026-11-22T10:15:30.123456Z",
      "network":2,"node":0,"state":"error-passive","previous":"error-warning","cause":"error-frame",
      "tec":130,"rec":7,"dropped":"12"})"));
}

TEST(EncodeEvent, SyncAndTime) {
  auto e = encode_event(event(canopen::SyncEvent{}), 1, kCtx);
  EXPECT_EQ(e->kind, EventKind::Sync);
  EXPECT_EQ(e->topic, "canopen/gw1/1/sync");
  EXPECT_FALSE(e->retained);
  check_consistent<pb::SyncEvent>(*e);
  EXPECT_FALSE(parse_obj(e->json).contains("counter"));
  e = encode_event(event(canopen::SyncEvent{0}), 1, kCtx);
  check_consistent<pb::SyncEvent>(*e);
  EXPECT_EQ(parse_obj(e->json).at("counter"), 0);

  // 2026-11-22 = day 15666 after 1984-01-01; 10:15:30.123
  canopen::TimeEvent t;
  t.time = canopen::time_of_day_from_unix_ms(1795342530123LL);
  e = encode_event(event(t), 1, kCtx);
  EXPECT_EQ(e->kind, EventKind::Time);
  EXPECT_EQ(e->topic, "canopen/gw1/1/time");
  check_consistent<pb::TimeEvent>(*e);
  EXPECT_EQ(parse_obj(e->json).at("time"), "2026-11-22T10:15:30.123Z");
}

// Contract "Remote configuration and maintenance": progress of a long
// transfer as events of kind `transfer`, bytes done and total, then the result.
TEST(EncodeEvent, TransferProgressThenResult) {
  canopen::TransferEvent t;
  t.node = 5;
  t.operation = canopen::TransferEvent::Operation::ProgramDownload;
  t.done = 4096;
  t.total = 262144;
  t.detail = "1F50h sub 1";
  auto e = encode_event(event(t), 1, kCtx);
  EXPECT_EQ(e->kind, EventKind::Transfer);
  EXPECT_EQ(e->topic, "canopen/gw1/1/5/transfer");
  EXPECT_FALSE(e->retained);
  check_consistent<pb::TransferEvent>(*e);
  auto j = parse_obj(e->json);
  EXPECT_EQ(j.at("operation"), "program-download");
  EXPECT_EQ(j.at("status"), "running");
  EXPECT_EQ(j.at("done"), "4096");
  EXPECT_EQ(j.at("total"), "262144");
  EXPECT_EQ(j.at("unit"), "bytes");
  EXPECT_FALSE(j.contains("error"));

  t.operation = canopen::TransferEvent::Operation::DcfApply;
  t.status = canopen::TransferEvent::Status::Failed;
  t.error = canopen::make_error_code(canopen::SdoAbort::NoSuchObject);
  e = encode_event(event(t), 1, kCtx);
  check_consistent<pb::TransferEvent>(*e);
  j = parse_obj(e->json);
  EXPECT_EQ(j.at("operation"), "dcf-apply");
  EXPECT_EQ(j.at("status"), "failed");
  EXPECT_EQ(j.at("unit"), "objects");
  EXPECT_EQ(j.at("abortCode"), "0x06020000");
}

TEST(EncodeEvent, BootConfig) {
  canopen::BootConfigEvent b;
  b.node = 5;
  b.step = canopen::BootConfigEvent::Step::Failed;
  b.error = canopen::make_error_code(canopen::SdoAbort::NoSuchObject);
  b.detail = "writing 1017h";
  auto e = encode_event(event(b), 1, kCtx);
  EXPECT_EQ(e->kind, EventKind::BootConfig);
  EXPECT_EQ(e->topic, "canopen/gw1/1/5/boot");
  EXPECT_FALSE(e->retained);
  check_consistent<pb::BootConfigEvent>(*e);
  auto j = parse_obj(e->json);
  EXPECT_EQ(j.at("step"), "failed");
  EXPECT_EQ(j.at("abortCode"), "0x06020000");
  EXPECT_EQ(j.at("error"), json::value(canopen::make_error_code(canopen::SdoAbort::NoSuchObject).message()));
  EXPECT_EQ(j.at("detail"), "writing 1017h");

  b.step = canopen::BootConfigEvent::Step::CheckIdentity;
  b.error = std::make_error_code(std::errc::timed_out);  // not an SDO abort: no abortCode
  e = encode_event(event(b), 1, kCtx);
  check_consistent<pb::BootConfigEvent>(*e);
  j = parse_obj(e->json);
  EXPECT_EQ(j.at("step"), "check-identity");
  EXPECT_TRUE(j.contains("error"));
  EXPECT_FALSE(j.contains("abortCode"));

  b.step = canopen::BootConfigEvent::Step::Done;
  b.error = {};
  b.detail = "";
  e = encode_event(event(b), 1, kCtx);
  check_consistent<pb::BootConfigEvent>(*e);
  j = parse_obj(e->json);
  EXPECT_EQ(j.at("step"), "done");
  EXPECT_FALSE(j.contains("error"));
  EXPECT_EQ(j.at("detail"), "");
}

TEST(EncodeEvent, Status) {
  GatewayStatusInfo s;
  s.online = true;
  s.version = "0.1.0";
  s.uptime_ms = 123456;
  s.node_id = 127;
  s.networks = {1, 2};
  s.timestamp = kTime;
  auto e = encode_status(s, kCtx);
  EXPECT_EQ(e->kind, EventKind::Status);
  EXPECT_EQ(e->topic, "canopen/gw1/status");
  EXPECT_TRUE(e->retained);
  EXPECT_EQ(e->network, 0u);
  check_consistent<pb::GatewayStatus>(*e);
  EXPECT_EQ(parse_obj(e->json), json::parse(R"({"seq":"0","timestamp":"2026-11-22T10:15:30.123456Z",
      "network":0,"node":0,"state":"online","version":"0.1.0","gatewayId":"gw1","uptimeMs":"123456",
      "nodeId":127,"networks":[1,2]})"));
  s.online = false;
  s.networks.clear();
  e = encode_status(s, kCtx);
  check_consistent<pb::GatewayStatus>(*e);
  EXPECT_EQ(parse_obj(e->json).at("state"), "offline");
}

TEST(EncodeEvent, GatewayIdEscapedAndValidated) {
  EXPECT_TRUE(valid_gateway_id("gw-1.example"));
  EXPECT_FALSE(valid_gateway_id(""));
  EXPECT_FALSE(valid_gateway_id("a/b"));
  EXPECT_FALSE(valid_gateway_id("a+"));
  EXPECT_FALSE(valid_gateway_id("#"));
  const EncodeContext odd{"g\"w"};
  GatewayStatusInfo s;
  const auto e = encode_status(s, odd);
  check_consistent<pb::GatewayStatus>(*e);
  EXPECT_EQ(parse_obj(e->json).at("gatewayId"), "g\"w");
}

TEST(EncodeEvent, PdoWithoutValuesOrRaw) {
  canopen::PdoEvent p;
  p.node = 1;
  p.number = 1;
  p.cob_id = 0x181;
  const auto e = encode_event(event(p), 1, kCtx);
  check_consistent<pb::PdoEvent>(*e);
  const auto j = parse_obj(e->json);
  EXPECT_EQ(j.at("values"), json::array{});
  EXPECT_EQ(j.at("raw"), "");
}

TEST(JsonText, TimestampMatchesProtobuf) {
  std::mt19937_64 rng(1);
  std::vector<detail::UnixTime> times = {{0, 0}, {0, 1}, {0, 999999999}, {1, 1000}, {1, 1000000},
                                         {-1, 500000000}, {253402300799, 999999999}, {951782400, 0}};
  for (int i = 0; i < 2000; ++i) {
    const auto s = static_cast<std::int64_t>(rng() % 253402300800ULL);
    const auto scale = std::array<std::int32_t, 4>{1, 1000, 1000000, 1000000000}[rng() % 4];
    const auto n = static_cast<std::int32_t>(rng() % 1000000000ULL) / scale * scale % 1000000000;
    times.push_back({s, n});
  }
  for (const auto& t : times) {
    google::protobuf::Timestamp ts;
    ts.set_seconds(t.seconds);
    ts.set_nanos(t.nanos);
    std::string mine;
    detail::append_timestamp(mine, t);
    EXPECT_EQ(mine, "\"" + google::protobuf::util::TimeUtil::ToString(ts) + "\"");
  }
}

TEST(JsonText, ValueJsonMatchesValueToJson) {
  std::mt19937_64 rng(2);
  const DataType ints[] = {DataType::Integer8,  DataType::Integer16,  DataType::Integer24,  DataType::Integer32,
                           DataType::Integer40, DataType::Integer48,  DataType::Integer56,  DataType::Integer64,
                           DataType::Unsigned8, DataType::Unsigned16, DataType::Unsigned24, DataType::Unsigned32,
                           DataType::Unsigned40, DataType::Unsigned48, DataType::Unsigned56, DataType::Unsigned64};
  for (int i = 0; i < 5000; ++i) {
    const DataType t = ints[rng() % std::size(ints)];
    Value v;
    if (canopen::is_signed_integer(t)) {
      const auto span = static_cast<std::uint64_t>(canopen::signed_max(t)) -
                        static_cast<std::uint64_t>(canopen::signed_min(t));
      v = Value::of_signed(t, static_cast<std::int64_t>(static_cast<std::uint64_t>(canopen::signed_min(t)) +
                                                        (span == UINT64_MAX ? rng() : rng() % (span + 1))));
    } else {
      const auto max = canopen::unsigned_max(t);
      v = Value::of_unsigned(t, max == UINT64_MAX ? rng() : rng() % (max + 1));
    }
    std::string s;
    detail::append_value_json(s, v);
    EXPECT_EQ(json::parse(s), canopen::value_to_json(v)) << s;
  }
  for (int i = 0; i < 5000; ++i) {
    std::uint64_t bits = rng();
    double d = 0;
    std::memcpy(&d, &bits, sizeof d);
    const auto b32 = static_cast<std::uint32_t>(bits);
    float f = 0;
    std::memcpy(&f, &b32, sizeof f);
    for (const Value& v : {Value::of_real64(d), Value::of_real32(f)}) {
      std::string s;
      detail::append_value_json(s, v);
      const auto ref = canopen::value_to_json(v);
      if (ref.is_double()) {
        // Read back with from_chars: exact, unlike some JSON parsers' fast paths.
        double back = 0;
        const auto r = std::from_chars(s.data(), s.data() + s.size(), back);
        EXPECT_TRUE(r.ec == std::errc{} && r.ptr == s.data() + s.size()) << s;
        EXPECT_EQ(back, ref.get_double()) << s;
      } else {
        EXPECT_EQ(json::parse(s), ref) << s << " vs " << json::serialize(ref);
      }
    }
  }
}

TEST(JsonText, StringsAndHex) {
  std::string s;
  detail::append_json_string(s, std::string("a\"\\\n\x1f\x7f b", 9));
  EXPECT_EQ(json::parse(s), json::value(std::string("a\"\\\n\x1f\x7f b", 9)));
  EXPECT_TRUE(detail::is_utf8("\xE2\x82\xAC"));
  EXPECT_FALSE(detail::is_utf8("\xC0\x80"));          // overlong
  EXPECT_FALSE(detail::is_utf8("\xED\xA0\x80"));      // surrogate
  EXPECT_FALSE(detail::is_utf8("\xF4\x90\x80\x80"));  // > U+10FFFF
  EXPECT_FALSE(detail::is_utf8("\xE2\x82"));          // truncated
  EXPECT_EQ(detail::to_utf8("\xE9"), "\xC3\xA9");
  EXPECT_EQ(detail::abort_code_text(0x060A0023), "0x060A0023");
  EXPECT_EQ(cob_id_topic_level(0x7FF), "7FF");
  EXPECT_EQ(cob_id_topic_level(0x800), "00000800");
}

}  // namespace
