// The MQTT request unit without a broker: a request PUBLISH decoded once
// into a core::Request with its reply address, and the reply encoded with
// the correlation id (publisher_test.cpp has the same over a real broker).
#include "mqtt_requests/mqtt_requests.hpp"

#include <gtest/gtest.h>

#include <boost/json/parse.hpp>

#include "canopen_gateway.pb.h"

namespace gateway::mqtt {
namespace {

codec::Publish publish(std::string_view topic, std::string_view body) {
  codec::Publish m;
  m.topic = topic;
  m.payload = body;
  return m;
}

TEST(MqttRequestDecode, TopicGivesOperationNetworkAndNode) {
  auto d = decode_request(publish("canopen/gw/2/5/sdo/read", R"({"index":"1017","subIndex":0,"type":"u16"})"), "gw");
  ASSERT_TRUE(d.error.empty()) << d.error;
  EXPECT_EQ(d.request.network, 2u);
  EXPECT_EQ(d.request.caller.transport, core::Transport::mqtt);
  EXPECT_FALSE(d.request.caller.authenticated);
  const auto* r = std::get_if<core::SdoRead>(&d.request.command);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->node, 5);
  EXPECT_EQ(r->index, 0x1017);
  EXPECT_EQ(r->type, canopen::DataType::Unsigned16);
  EXPECT_TRUE(d.reply.topic.empty());

  EXPECT_EQ(decode_request(publish("canopen/gw/x/5/sdo/read", "{}"), "gw").error, "network must be a number from 1");
  EXPECT_EQ(decode_request(publish("canopen/gw/0/5/sdo/read", "{}"), "gw").error, "network must be a number from 1");
  EXPECT_EQ(decode_request(publish("canopen/gw/1/200/nmt", "{}"), "gw").error,
            "node must be 1..127 (0 = all nodes, NMT only)");
  EXPECT_EQ(decode_request(publish("canopen/gw/1/0/sdo/write", "{}"), "gw").error,
            "node must be 1..127 (0 = all nodes, NMT only)");
  EXPECT_EQ(decode_request(publish("canopen/gw/1/5/sdo/erase", "{}"), "gw").error, "unknown request topic");
  EXPECT_EQ(decode_request(publish("canopen/other/1/5/nmt", "{}"), "gw").error, "not this gateway's request topic");
  const auto all = decode_request(publish("canopen/gw/1/0/nmt", R"({"command":"reset-comm"})"), "gw");
  ASSERT_TRUE(std::holds_alternative<core::Nmt>(all.request.command));
  EXPECT_EQ(std::get<core::Nmt>(all.request.command).command, canopen::NmtCommand::ResetCommunication);
}

TEST(MqttRequestDecode, ReplyAddressAndTokenLeaveTheJsonBody) {
  const auto d = decode_request(
      publish("canopen/gw/1/5/sdo/write",
              R"({"value":5,"type":"u8","index":"6060","replyTo":"app/reply","correlationId":{"n":1},"token":"Bearer t"})"),
      "gw");
  ASSERT_TRUE(d.error.empty());
  EXPECT_EQ(d.reply.topic, "app/reply");
  ASSERT_TRUE(d.reply.corr_id);
  EXPECT_EQ(*d.reply.corr_id, boost::json::parse(R"({"n":1})"));
  EXPECT_EQ(d.request.caller.token, "t");
  const auto* w = std::get_if<core::SdoWrite>(&d.request.command);
  ASSERT_NE(w, nullptr) << "no unknown fields left: " << std::get<core::Undecodable>(d.request.command).detail;
  EXPECT_EQ(w->index, 0x6060);
  EXPECT_EQ(w->value, core::WriteValue{canopen::Literal(5)});
}

TEST(MqttRequestDecode, Mqtt5PropertiesWinAndProtobufBodies) {
  canopen::gateway::v1::SdoReadRequest m;
  m.set_index(0x1018);
  m.set_sub_index(1);
  m.set_correlation_id("inside");
  const std::string body = m.SerializeAsString();
  auto msg = publish("canopen/gw/1/5/sdo/read", body);
  msg.props.response_topic = "v5/reply";
  msg.props.correlation_data = std::string_view("\0c", 2);
  msg.props.content_type = "application/x-protobuf";
  msg.props.user.push_back({"authorization", "Bearer abc"});
  const auto d = decode_request(msg, "gw");
  EXPECT_TRUE(d.reply.v5);
  EXPECT_EQ(d.reply.topic, "v5/reply");
  EXPECT_EQ(d.reply.correlation, std::string("\0c", 2));
  EXPECT_TRUE(d.options.protobuf);
  EXPECT_EQ(d.options.correlation_id, "inside") << "echoed in the protobuf reply";
  EXPECT_EQ(d.request.caller.token, "abc");
  const auto* r = std::get_if<core::SdoRead>(&d.request.command);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->index, 0x1018);
  EXPECT_EQ(r->sub, 1);
}

TEST(MqttRequestDecode, ABodyThatDoesNotDecodeStillGoesToTheCore) {
  const auto d = decode_request(publish("canopen/gw/1/5/nmt", R"({"command":"jump","replyTo":"a/reply"})"), "gw");
  ASSERT_TRUE(d.error.empty());
  EXPECT_EQ(d.reply.topic, "a/reply");
  const auto* u = std::get_if<core::Undecodable>(&d.request.command);
  ASSERT_NE(u, nullptr);
  EXPECT_EQ(u->operation, core::Operation::nmt);
  EXPECT_EQ(u->node, 5);
  EXPECT_FALSE(u->in_address);
  EXPECT_NE(u->detail.find("unknown command \"jump\""), std::string::npos) << u->detail;
  const auto bad = decode_request(publish("canopen/gw/1/5/sdo/read", "[1,2]"), "gw");
  ASSERT_TRUE(std::holds_alternative<core::Undecodable>(bad.request.command));
  EXPECT_EQ(std::get<core::Undecodable>(bad.request.command).detail, "body must be a JSON object");
}

TEST(MqttReplyBody, CorrelationIdIsAddedToAJsonReply) {
  ReplyAddress addr;
  addr.corr_id = boost::json::value("c-7");
  const Reply ok = sdo_response(canopen::Value::of_unsigned(canopen::DataType::Unsigned8, 42));
  const auto body = boost::json::parse(reply_body(ok, addr)).as_object();
  EXPECT_EQ(body.at("value").as_int64(), 42);
  EXPECT_EQ(body.at("correlationId").as_string(), "c-7");
  addr.corr_id = boost::json::value(8);
  const auto problem_body = boost::json::parse(reply_body(problem(400, "bad"), addr)).as_object();
  EXPECT_EQ(problem_body.at("correlationId").as_int64(), 8);
  EXPECT_EQ(problem_body.at("status").as_int64(), 400);
  EXPECT_EQ(reply_body(Reply{200, "{}", "application/json"}, addr), R"({"correlationId":8})");
  // Protobuf replies and addresses without one stay as they are.
  ReplyOptions proto;
  proto.protobuf = true;
  const Reply binary = problem(400, "bad", proto);
  EXPECT_EQ(reply_body(binary, addr), binary.body);
  EXPECT_EQ(reply_body(ok, ReplyAddress{}), ok.body);
}

// A refusal that says when to try again (the core's rate limit: 429 with
// retry_after) carries it as an MQTT 5 user property, as HTTP's Retry-After,
// next to "status"; other replies have none.
TEST(MqttRequests, ARefusalWithRetryAfterCarriesItAsAUserProperty) {
  Logger log(LogLevel::Error);
  core::Result next;
  MqttRequests requests("gw", {}, log, [&](core::Request, MqttRequests::Done done) { done(next); });
  std::vector<std::pair<std::string, std::string>> props;
  requests.set_reply_sender([&](std::string_view, std::string_view, const codec::PublishProperties& p) {
    props.clear();
    for (const auto& u : p.user) props.emplace_back(std::string(u.name), std::string(u.value));
    return ReplyOutcome::sent;
  });
  auto msg = publish("canopen/gw/1/5/sdo/read", R"({"index":"1017","subIndex":0})");
  msg.props.response_topic = "app/reply";

  core::Problem limited;
  limited.status = 429;
  limited.detail = "too many requests";
  limited.retry_after = 1;
  next = limited;
  requests.on_publish(msg);
  using P = std::pair<std::string, std::string>;
  EXPECT_EQ(props, (std::vector<P>{{"status", "429"}, {"retry-after", "1"}}));

  next = core::SdoValue{canopen::Value::of_unsigned(canopen::DataType::Unsigned16, 100)};
  requests.on_publish(msg);
  EXPECT_EQ(props, (std::vector<P>{{"status", "200"}}));
}

}  // namespace
}  // namespace gateway::mqtt
