// Request bodies (JSON and protobuf) -> typed params, and replies.
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <boost/json/parse.hpp>
#include <random>

#include "canopen/sdo/abort.hpp"
#include "canopen_gateway.pb.h"
#include "messages/request_codec.hpp"

namespace {

namespace pb = ::canopen::gateway::v1;
namespace json = boost::json;
using namespace gateway;
using canopen::DataType;
using canopen::Value;

TEST(ParseSdoRead, JsonForms) {
  auto r = parse_sdo_read(R"({"index": 4119, "subIndex": 0})", false);
  ASSERT_TRUE(r.ok()) << r.error().detail;
  EXPECT_EQ(r->index, 0x1017);
  EXPECT_EQ(r->sub, 0);
  EXPECT_FALSE(r->type);

  r = parse_sdo_read(R"({"index":"0x1018","sub_index":"0x04","type":"u32","replyTo":"me/reply","correlationId":"abc"})",
                     false);
  ASSERT_TRUE(r.ok()) << r.error().detail;
  EXPECT_EQ(r->index, 0x1018);
  EXPECT_EQ(r->sub, 4);
  EXPECT_EQ(r->type, DataType::Unsigned32);
  EXPECT_EQ(r->reply_to, "me/reply");
  EXPECT_EQ(r->correlation_id, "abc");

  r = parse_sdo_read(R"({"index":"6041h","subIndex":"10","type":"UNSIGNED16"})", false);
  ASSERT_TRUE(r.ok()) << r.error().detail;
  EXPECT_EQ(r->index, 0x6041);
  EXPECT_EQ(r->sub, 10);
  EXPECT_EQ(r->type, DataType::Unsigned16);

  // proto3 JSON leaves out a zero subIndex.
  r = parse_sdo_read(R"({"index":"1017"})", false);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->sub, 0);

  // REST: address from the path; the body may be empty.
  r = parse_sdo_read("", false, false);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->index);
}

TEST(ParseSdoRead, JsonErrors) {
  const std::pair<const char*, const char*> cases[] = {
      {"", "index is required"},
      {"{", "not valid JSON"},
      {"[1]", "must be a JSON object"},
      {R"({"subIndex":1})", "index is required"},
      {R"({"index":65536,"subIndex":0})", "index"},
      {R"({"index":-1,"subIndex":0})", "index"},
      {R"({"index":1.5,"subIndex":0})", "index"},
      {R"({"index":"xyz","subIndex":0})", "index"},
      {R"({"index":"1017","subIndex":256})", "subIndex"},
      {R"({"index":"1017","subIndex":"0x100"})", "subIndex"},
      {R"({"index":"1017","subIndex":true})", "subIndex"},
      {R"({"index":"1017","type":"u17"})", "unknown type \"u17\""},
      {R"({"index":"1017","type":5})", "type must be a string"},
      {R"({"index":"1017","subindex":1})", "unknown field \"subindex\""},
      {R"({"index":"1017","correlationId":5})", "correlationId must be a string"},
  };
  for (const auto& [body, expect] : cases) {
    auto r = parse_sdo_read(body, false);
    ASSERT_FALSE(r.ok()) << body;
    EXPECT_NE(r.error().detail.find(expect), std::string::npos) << body << " -> " << r.error().detail;
    const Reply reply = bad_request(r.error());
    EXPECT_EQ(reply.status, 400);
    EXPECT_EQ(reply.content_type, "application/problem+json");
    EXPECT_EQ(json::parse(reply.body).at("detail"), json::value(r.error().detail));
  }
}

TEST(ParseSdoWrite, JsonAndTypedValue) {
  auto r = parse_sdo_write(R"({"index":"1017","subIndex":0,"value":1000,"type":"u16"})", false);
  ASSERT_TRUE(r.ok()) << r.error().detail;
  EXPECT_EQ(r->type, DataType::Unsigned16);
  auto v = r->value_as(DataType::Unsigned16);
  ASSERT_TRUE(v.ok());
  EXPECT_EQ(*v, Value::of_unsigned(DataType::Unsigned16, 1000));

  // 64-bit values as strings; type from the EDS later.
  r = parse_sdo_write(R"({"index":"2000","subIndex":1,"value":"18446744073709551615"})", false);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->type);
  v = r->value_as(DataType::Unsigned64);
  ASSERT_TRUE(v.ok());
  EXPECT_EQ(std::get<std::uint64_t>(v->data), 18446744073709551615ULL);

  // REST body: value and type only.
  r = parse_sdo_write(R"({"value":"0aff","type":"os"})", false, false);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(*r->value_as(DataType::OctetString), Value::of_bytes(DataType::OctetString, {0x0A, 0xFF}));
}

TEST(ParseSdoWrite, Errors) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"index":"1017","subIndex":0})", "value is required"},
      {R"({"index":"1017","value":null})", "value is required"},
      {R"({"index":"1017","value":70000,"type":"u16"})", "1017h sub 0: 70000 is above 65535 (u16)"},
      {R"({"index":"1017","value":"abc","type":"u16"})", "1017h sub 0: \"abc\" is not an integer (u16)"},
      {R"({"value":1})", "index is required"},
      {R"({"index":"1017","value":1,"extra":2})", "unknown field \"extra\""},
  };
  for (const auto& [body, expect] : cases) {
    auto r = parse_sdo_write(body, false);
    ASSERT_FALSE(r.ok()) << body;
    EXPECT_NE(r.error().detail.find(expect), std::string::npos) << body << " -> " << r.error().detail;
  }
  // Without a type the value is only checked once the type is known.
  auto r = parse_sdo_write(R"({"index":"1017","value":[1]})", false);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->value_as(DataType::Unsigned16).ok());
}

// Issue 13: every range or type error of an SDO value names the object
// (the od's object_label) and the type, whatever the type came from (the
// request, or the EDS when App calls value_as).
TEST(ParseSdoWrite, ValueErrorsNameTheObjectAndTheType) {
  auto r = parse_sdo_write(R"({"index":"0x6040","subIndex":0,"value":70000})", false);
  ASSERT_TRUE(r.ok()) << r.error().detail;
  const std::pair<canopen::DataType, const char*> cases[] = {
      {DataType::Unsigned16, "6040h sub 0: 70000 is above 65535 (u16)"},
      {DataType::Integer8, "6040h sub 0: 70000 is above 127 (i8)"},
      {DataType::Boolean, "6040h sub 0: 70000 is not a boolean"},
  };
  for (const auto& [type, expect] : cases) {
    auto v = r->value_as(type);
    ASSERT_FALSE(v.ok());
    EXPECT_EQ(v.error().detail.rfind(expect, 0), 0U) << v.error().detail;
  }
  r = parse_sdo_write(R"({"index":"2000","subIndex":"0x1F","value":-1})", false);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->value_as(DataType::Unsigned32).error().detail, "2000h sub 31: -1 is below 0 (u32)");
  EXPECT_EQ(r->value_as(DataType::Unsigned32).error().code, canopen::make_error_code(canopen::SdoAbort::ValueTooLow));
}

TEST(ParseRequests, Protobuf) {
  pb::SdoReadRequest rd;
  rd.set_index(0x1018);
  rd.set_sub_index(1);
  rd.set_type("u32");
  rd.set_correlation_id("c1");
  auto r = parse_sdo_read(rd.SerializeAsString(), true);
  ASSERT_TRUE(r.ok()) << r.error().detail;
  EXPECT_EQ(r->index, 0x1018);
  EXPECT_EQ(r->sub, 1);
  EXPECT_EQ(r->type, DataType::Unsigned32);
  EXPECT_EQ(r->correlation_id, "c1");
  rd.set_index(0x10000);
  EXPECT_FALSE(parse_sdo_read(rd.SerializeAsString(), true).ok());
  EXPECT_FALSE(parse_sdo_read(pb::SdoReadRequest{}.SerializeAsString(), true).ok());  // no index
  EXPECT_FALSE(parse_sdo_read("\xff\xff\xff", true).ok());

  pb::SdoWriteRequest wr;
  wr.set_index(0x1017);
  wr.mutable_value()->set_number_value(1000);
  wr.set_type("u16");
  auto w = parse_sdo_write(wr.SerializeAsString(), true);
  ASSERT_TRUE(w.ok()) << w.error().detail;
  EXPECT_EQ(*w->value_as(DataType::Unsigned16), Value::of_unsigned(DataType::Unsigned16, 1000));
  wr.mutable_value()->set_string_value("-9223372036854775808");
  wr.set_type("i64");
  w = parse_sdo_write(wr.SerializeAsString(), true);
  ASSERT_TRUE(w.ok()) << w.error().detail;
  EXPECT_EQ(std::get<std::int64_t>(w->value_as(DataType::Integer64)->data), INT64_MIN);
  wr.clear_value();
  EXPECT_FALSE(parse_sdo_write(wr.SerializeAsString(), true).ok());
  wr.mutable_value()->mutable_struct_value();
  EXPECT_FALSE(parse_sdo_write(wr.SerializeAsString(), true).ok());

  pb::NmtRequest nmt;
  nmt.set_command("reset-comm");
  auto n = parse_nmt(nmt.SerializeAsString(), true);
  ASSERT_TRUE(n.ok());
  EXPECT_EQ(n->command, canopen::NmtCommand::ResetCommunication);
}

TEST(ParseNmt, Json) {
  const std::pair<const char*, canopen::NmtCommand> ok[] = {
      {"start", canopen::NmtCommand::Start},
      {"stop", canopen::NmtCommand::Stop},
      {"preop", canopen::NmtCommand::EnterPreOperational},
      {"reset-node", canopen::NmtCommand::ResetNode},
      {"reset-comm", canopen::NmtCommand::ResetCommunication},
  };
  for (const auto& [name, cmd] : ok) {
    auto r = parse_nmt(std::string(R"({"command":")") + name + R"(","correlationId":"x"})", false);
    ASSERT_TRUE(r.ok()) << name;
    EXPECT_EQ(r->command, cmd);
    EXPECT_EQ(r->correlation_id, "x");
    EXPECT_EQ(nmt_command_name(cmd), name);
  }
  EXPECT_NE(parse_nmt(R"({"command":"reboot"})", false).error().detail.find("unknown command \"reboot\""),
            std::string::npos);
  EXPECT_NE(parse_nmt("{}", false).error().detail.find("command is required"), std::string::npos);
  EXPECT_FALSE(parse_nmt(R"({"command":1})", false).ok());
}

TEST(ParseRequests, GarbageNeverCrashes) {
  std::mt19937 rng(3);
  const std::string seeds[] = {R"({"index":"1017","subIndex":0,"value":1,"type":"u16","replyTo":"a"})",
                               R"({"command":"start"})", pb::SdoWriteRequest{}.SerializeAsString()};
  for (int i = 0; i < 20000; ++i) {
    std::string s = seeds[static_cast<std::size_t>(i) % std::size(seeds)];
    const int edits = 1 + static_cast<int>(rng() % 8);
    for (int k = 0; k < edits; ++k) {
      const auto pos = s.empty() ? 0 : rng() % s.size();
      switch (rng() % 3) {
        case 0: if (!s.empty()) s[pos] = static_cast<char>(rng()); break;
        case 1: s.insert(pos, 1, static_cast<char>(rng())); break;
        default: if (!s.empty()) s.erase(pos, 1); break;
      }
    }
    for (bool proto : {false, true}) {
      auto a = parse_sdo_read(s, proto);
      auto b = parse_sdo_write(s, proto);
      auto c = parse_nmt(s, proto);
      if (b.ok() && b->type) {
        EXPECT_TRUE(b->value_as(*b->type).ok());
      }
      (void)a;
      (void)c;
    }
  }
  // Deep nesting is refused, not recursed into.
  EXPECT_FALSE(parse_sdo_write(std::string(100000, '[') + std::string(100000, ']'), false).ok());
}

TEST(Replies, SdoResponse) {
  auto r = sdo_response(Value::of_unsigned(DataType::Unsigned64, 18446744073709551615ULL));
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.content_type, "application/json");
  EXPECT_EQ(json::parse(r.body),
            json::parse(R"({"value":"18446744073709551615","type":"u64","raw":"ffffffffffffffff"})"));

  r = sdo_response(Value::of_bytes(DataType::OctetString, {0xDE, 0xAD}), {false, "corr-7"});
  EXPECT_EQ(json::parse(r.body),
            json::parse(R"({"value":"dead","type":"os","raw":"dead","correlationId":"corr-7"})"));

  r = sdo_response(Value::of_unsigned(DataType::Unsigned16, 1000));
  const auto j = json::parse(r.body);
  EXPECT_EQ(j.at("value").to_number<double>(), 1000.0);
  EXPECT_EQ(j.at("raw"), "e803");

  r = sdo_response(Value::of_unsigned(DataType::Unsigned16, 1000), {true, ""});
  EXPECT_EQ(r.content_type, "application/x-protobuf");
  pb::SdoResponse m;
  ASSERT_TRUE(m.ParseFromString(r.body));
  EXPECT_EQ(m.value().number_value(), 1000.0);
  EXPECT_EQ(m.type(), "u16");
  EXPECT_FALSE(m.has_correlation_id());
}

TEST(Replies, NmtResponse) {
  auto r = nmt_response(1, 0, canopen::NmtCommand::ResetNode);
  EXPECT_EQ(json::parse(r.body), json::parse(R"({"network":1,"node":0,"command":"reset-node"})"));
}

TEST(Replies, Problems) {
  auto r = sdo_abort_problem(0x06020000, "1234h/00");
  EXPECT_EQ(r.status, 422);
  EXPECT_EQ(r.content_type, "application/problem+json");
  auto j = json::parse(r.body);
  EXPECT_EQ(j.at("abortCode"), "0x06020000");
  EXPECT_EQ(j.at("status"), 422);
  EXPECT_EQ(j.at("type"), "about:blank");
  EXPECT_EQ(j.at("detail"), json::value(std::string(canopen::sdo_abort_text(0x06020000)) + ": 1234h/00"));

  r = sdo_error_reply(canopen::make_error_code(canopen::SdoAbort::Timeout), false);
  EXPECT_EQ(r.status, 504);
  EXPECT_EQ(json::parse(r.body).at("abortCode"), "0x05040000");
  r = sdo_error_reply(canopen::make_error_code(canopen::SdoAbort::ValueTooHigh), true);
  EXPECT_EQ(r.status, 422);
  EXPECT_EQ(json::parse(r.body).at("abortCode"), "0x06090031");
  r = sdo_error_reply(canopen::make_error_code(canopen::SdoAbort::InvalidCommand), false);
  EXPECT_EQ(r.status, 502);

  r = problem(404, "network 9 does not exist", {false, "c"});
  j = json::parse(r.body);
  EXPECT_EQ(j.at("title"), "Not Found");
  EXPECT_EQ(j.at("correlationId"), "c");
  EXPECT_FALSE(j.as_object().contains("abortCode"));

  r = problem(503, "bus-off", {true, ""});
  pb::Problem m;
  ASSERT_TRUE(m.ParseFromString(r.body));
  EXPECT_EQ(m.status(), 503u);
  EXPECT_EQ(m.detail(), "bus-off");
  EXPECT_EQ(r.content_type, "application/x-protobuf");
}

TEST(ParseText, IndexAndSub) {
  EXPECT_EQ(parse_index_text("1017"), 0x1017);
  EXPECT_EQ(parse_index_text("0x1017"), 0x1017);
  EXPECT_EQ(parse_index_text("1017h"), 0x1017);
  EXPECT_EQ(parse_index_text("ffff"), 0xFFFF);
  EXPECT_FALSE(parse_index_text("10000"));
  EXPECT_FALSE(parse_index_text(""));
  EXPECT_FALSE(parse_index_text("h"));
  EXPECT_FALSE(parse_index_text("0x"));
  EXPECT_FALSE(parse_index_text("-1"));
  EXPECT_EQ(parse_sub_index_text("10"), 10);
  EXPECT_EQ(parse_sub_index_text("0x0A"), 10);
  EXPECT_FALSE(parse_sub_index_text("256"));
  EXPECT_FALSE(parse_sub_index_text("a"));
}

// A client that builds its body with protobuf's JSON printer (defaults:
// zero fields left out, or all printed) is understood.
TEST(ParseRequests, Proto3JsonFromProtobufPrinter) {
  for (bool all : {false, true}) {
    google::protobuf::util::JsonPrintOptions po;
    po.always_print_primitive_fields = all;
    pb::SdoReadRequest rd;
    rd.set_index(0x1017);
    std::string body;
    ASSERT_TRUE(google::protobuf::util::MessageToJsonString(rd, &body, po).ok());
    auto r = parse_sdo_read(body, false);
    ASSERT_TRUE(r.ok()) << body << ": " << r.error().detail;
    EXPECT_EQ(r->index, 0x1017);
    EXPECT_EQ(r->sub, 0);

    pb::SdoWriteRequest wr;
    wr.set_index(0x2000);
    wr.set_sub_index(3);
    wr.set_type("i64");
    wr.set_reply_to("client/1/reply");
    wr.set_correlation_id("42");
    wr.mutable_value()->set_string_value("-5");
    body.clear();
    ASSERT_TRUE(google::protobuf::util::MessageToJsonString(wr, &body, po).ok());
    auto w = parse_sdo_write(body, false);
    ASSERT_TRUE(w.ok()) << body << ": " << w.error().detail;
    EXPECT_EQ(w->index, 0x2000);
    EXPECT_EQ(w->sub, 3);
    EXPECT_EQ(w->type, DataType::Integer64);
    EXPECT_EQ(w->reply_to, "client/1/reply");
    EXPECT_EQ(w->correlation_id, "42");
    EXPECT_EQ(std::get<std::int64_t>(w->value_as(DataType::Integer64)->data), -5);

    pb::NmtRequest nmt;
    nmt.set_command("preop");
    body.clear();
    ASSERT_TRUE(google::protobuf::util::MessageToJsonString(nmt, &body, po).ok());
    auto n = parse_nmt(body, false);
    ASSERT_TRUE(n.ok()) << body;
    EXPECT_EQ(n->command, canopen::NmtCommand::EnterPreOperational);
  }
}

// Replies are valid proto3 JSON of their messages.
TEST(Replies, ParseBackAsMessages) {
  pb::SdoResponse s;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(
                  sdo_response(Value::of_real32(0.1f), {false, "c"}).body, &s).ok());
  EXPECT_EQ(s.value().number_value(), 0.1);
  EXPECT_EQ(s.correlation_id(), "c");
  pb::Problem p;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(sdo_abort_problem(0x06090031).body, &p).ok());
  EXPECT_EQ(p.abort_code(), "0x06090031");
  pb::NmtResponse n;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(
                  nmt_response(2, 5, canopen::NmtCommand::Stop).body, &n).ok());
  EXPECT_EQ(n.command(), "stop");
}

}  // namespace
