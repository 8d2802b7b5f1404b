// MqttPublisher against a real mosquitto started by the fixture; requests
// through the MqttRequests unit it hands them to (a fake request core).
#include "mqtt/publisher.hpp"

#include "mqtt/client.hpp"
#include "mqtt_requests/mqtt_requests.hpp"
#include "support/memory_log.hpp"

#include <gtest/gtest.h>

#include <boost/json.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>

#include "mqtt_support.hpp"

using namespace mqtt_test;
using gateway::EncodedEvent;
using gateway::EncodedEventPtr;
using gateway::EventKind;
using gateway::mqtt::MqttConfig;
using gateway::mqtt::MqttPublisher;

namespace {

constexpr const char* kGw = "gw1";

EncodedEventPtr make_event(EventKind k, std::string topic, std::string json, bool retained) {
  auto e = std::make_shared<EncodedEvent>();
  e->kind = k;
  e->topic = std::move(topic);
  e->json = std::move(json);
  e->binary = "\x08\x01";
  e->retained = retained;
  return e;
}

class MqttPublisherTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_mosquitto()) GTEST_SKIP() << "no " << kMosquitto;
  }

  void start_broker(bool persistence = false) {
    broker_.emplace(persistence);
    ASSERT_TRUE(broker_->start()) << broker_->log();
  }

  MqttConfig config() {
    MqttConfig c;
    c.server_uri = "mqtt://127.0.0.1:" + std::to_string(broker_->port());
    c.client_id = "gateway-under-test";
    c.gateway_id = kGw;
    c.queue.dir = queue_dir_.path() / "q";
    c.reconnect_min = 100ms;
    c.reconnect_max = 500ms;
    return c;
  }

  // `log` (default: the fixture's, warnings to stderr) MUST outlive the publisher.
  void start_publisher(MqttConfig c, gateway::Logger* log = nullptr) {
    io_.call([&] {
      // The request core's stand-in: records the request, answers value 42.
      requests_unit_ = std::make_unique<gateway::mqtt::MqttRequests>(
          c.gateway_id, c.reply_topics, log != nullptr ? *log : log_,
          [this](gateway::core::Request r, gateway::mqtt::MqttRequests::Done done) {
            requests_.push_back(std::move(r));
            ++request_count_;
            done(gateway::core::SdoValue{canopen::Value::of_unsigned(canopen::DataType::Unsigned8, 42)});
          });
      auto* unit = requests_unit_.get();
      pub_ = std::make_unique<MqttPublisher>(io_.io(), c, log != nullptr ? *log : log_,
                                             [unit](const gateway::mqtt::codec::Publish& m) { unit->on_publish(m); });
      requests_unit_->set_reply_sender(pub_->reply_sender());
      pub_->start();
    });
    ASSERT_TRUE(eventually([&] { return counters().connected; })) << broker_->log();
  }

  MqttPublisher::Counters counters() {
    return io_.call([&] { return pub_->counters(); });
  }
  gateway::mqtt::MqttRequests::Counters request_counters() {
    return io_.call([&] { return requests_unit_->counters(); });
  }

  void publish(EncodedEventPtr e) {
    io_.call([&] { pub_->publish(e); });
  }

  void TearDown() override {
    if (pub_) io_.call([&] {
      pub_.reset();
      requests_unit_.reset();
    });
  }

  TempDir queue_dir_;
  std::optional<Broker> broker_;
  gateway::Logger log_{gateway::LogLevel::Warn};
  MemoryLog captured_;  // for tests that read the log: start_publisher(c, &captured_log_)
  gateway::Logger captured_log_{gateway::LogLevel::Warn, captured_.file};
  IoThread io_;
  std::unique_ptr<gateway::mqtt::MqttRequests> requests_unit_;  // before pub_: replies go through it
  std::unique_ptr<MqttPublisher> pub_;
  std::vector<gateway::core::Request> requests_;  // io thread
  std::atomic<int> request_count_{0};
};

std::vector<std::string> payloads(const std::vector<::mqtt::const_message_ptr>& msgs) {
  std::vector<std::string> out;
  for (auto& m : msgs) out.push_back(m->get_payload_str());
  return out;
}

std::vector<std::string> numbers(int from, int to) {
  std::vector<std::string> out;
  for (int i = from; i < to; ++i) out.push_back(std::to_string(i));
  return out;
}

// "" when got is exactly "0".."n-1"; else where it first differs, and how
// many duplicates and gaps there are.
std::string sequence_problem(const std::vector<std::string>& got, int n) {
  if (got == numbers(0, n)) return "";
  std::string out = "received " + std::to_string(got.size()) + " of " + std::to_string(n);
  for (std::size_t i = 0; i < got.size(); ++i) {
    if (got[i] != std::to_string(i)) {
      out += "; first difference at " + std::to_string(i) + ": " + got[i];
      for (std::size_t j = i; j < std::min(got.size(), i + 8); ++j) out += " " + got[j];
      break;
    }
  }
  std::vector<int> seen(static_cast<std::size_t>(n), 0);
  int dups = 0, bad = 0;
  for (auto& g : got) {
    int v = std::atoi(g.c_str());
    if (v < 0 || v >= n) { ++bad; continue; }
    if (seen[static_cast<std::size_t>(v)]++ > 0) ++dups;
  }
  out += "; duplicates " + std::to_string(dups) + ", missing " +
         std::to_string(std::count(seen.begin(), seen.end(), 0)) + ", unexpected " + std::to_string(bad);
  return out;
}

}  // namespace

TEST_F(MqttPublisherTest, NormalizesUris) {
  EXPECT_EQ(gateway::mqtt::normalize_server_uri("mqtt://h:1883"), "tcp://h:1883");
  EXPECT_EQ(gateway::mqtt::normalize_server_uri("mqtts://h"), "ssl://h");
  EXPECT_EQ(gateway::mqtt::normalize_server_uri("ssl://h:8883"), "ssl://h:8883");
  EXPECT_THROW(gateway::mqtt::normalize_server_uri("http://h"), std::invalid_argument);
  EXPECT_THROW(gateway::mqtt::normalize_server_uri("tcp://"), std::invalid_argument);
}

TEST_F(MqttPublisherTest, EventsArriveInOrderWithTopicsAndRetainedFlags) {
  start_broker();
  Subscriber live(broker_->uri(), "live", {"canopen/gw1/#"}, {});
  ASSERT_TRUE(live.connect());
  start_publisher(config());
  EXPECT_EQ(counters().mqtt_version, 5);

  publish(make_event(EventKind::State, "canopen/gw1/1/5/state", R"({"state":"operational"})", true));
  for (int i = 0; i < 300; ++i)
    publish(make_event(EventKind::Tpdo, "canopen/gw1/1/5/tpdo/1", std::to_string(i), false));
  publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", R"({"errorCode":4096})", false));
  ASSERT_TRUE(live.wait_topic("canopen/gw1/1/5/emcy", 15s));
  EXPECT_EQ(payloads(live.on_topic("canopen/gw1/1/5/tpdo/1")), numbers(0, 300));
  ASSERT_EQ(live.on_topic("canopen/gw1/1/5/state").size(), 1u);
  EXPECT_TRUE(eventually([&] { return counters().queue_depth == 0; }));

  // A late subscriber gets the retained state (flag set) and the online
  // status, but none of the non-retained events.
  Subscriber late(broker_->uri(), "late", {"canopen/gw1/#"}, {});
  ASSERT_TRUE(late.connect());
  ASSERT_TRUE(late.wait_topic("canopen/gw1/1/5/state", 5s));
  ASSERT_TRUE(late.wait_topic("canopen/gw1/status", 5s));
  for (auto& m : late.messages()) {
    EXPECT_TRUE(m->is_retained()) << m->get_topic();
    EXPECT_NE(m->get_topic(), "canopen/gw1/1/5/tpdo/1");
  }
  EXPECT_EQ(late.on_topic("canopen/gw1/status").at(0)->get_payload_str(), R"({"state":"online"})");
  auto c = counters();
  EXPECT_EQ(c.published, 302u);
  EXPECT_EQ(c.acked, 302u);
  EXPECT_EQ(c.dropped, 0u);
}

TEST_F(MqttPublisherTest, ProtobufPayloadWhenAsked) {
  start_broker();
  Subscriber live(broker_->uri(), "live", {"canopen/gw1/#"}, {});
  ASSERT_TRUE(live.connect());
  auto c = config();
  c.format = gateway::mqtt::PayloadFormat::Protobuf;
  start_publisher(c);
  publish(make_event(EventKind::Heartbeat, "canopen/gw1/1/5/heartbeat", "{}", false));
  ASSERT_TRUE(live.wait_topic("canopen/gw1/1/5/heartbeat", 10s));
  EXPECT_EQ(live.on_topic("canopen/gw1/1/5/heartbeat").at(0)->get_payload_str(), "\x08\x01");
}

TEST_F(MqttPublisherTest, CleanStopPublishesOfflineStatus) {
  start_broker();
  start_publisher(config());
  Subscriber sub(broker_->uri(), "watch", {"canopen/gw1/status"}, {});
  ASSERT_TRUE(sub.connect());
  ASSERT_TRUE(sub.wait_count(1, 5s));
  EXPECT_EQ(sub.messages().at(0)->get_payload_str(), R"({"state":"online"})");
  io_.call([&] { pub_->stop(); });
  ASSERT_TRUE(sub.wait_count(2, 5s));
  EXPECT_EQ(sub.messages().at(1)->get_payload_str(), R"({"state":"offline"})");
}

TEST_F(MqttPublisherTest, RequestOverMqtt5WithResponseTopicAndCorrelationData) {
  start_broker();
  start_publisher(config());
  Subscriber client(broker_->uri(), "requester5", {"replies/me"}, {MQTTVERSION_5, true});
  ASSERT_TRUE(client.connect());

  auto msg = ::mqtt::make_message("canopen/gw1/2/5/sdo/read", R"({"index":"1017","subIndex":0})", 1, false);
  msg->set_properties({::mqtt::property(::mqtt::property::RESPONSE_TOPIC, "replies/me"),
                       ::mqtt::property(::mqtt::property::CORRELATION_DATA, std::string("corr\0-1", 7))});
  client.client().publish(msg)->wait_for(5s);
  ASSERT_TRUE(client.wait_count(1, 10s));
  auto reply = client.messages().at(0);
  const auto& props = reply->get_properties();
  ASSERT_TRUE(props.contains(::mqtt::property::CORRELATION_DATA));
  EXPECT_EQ(::mqtt::get<std::string>(props, ::mqtt::property::CORRELATION_DATA), std::string("corr\0-1", 7));
  ASSERT_TRUE(props.contains(::mqtt::property::USER_PROPERTY));
  auto status = ::mqtt::get<::mqtt::string_pair>(props, ::mqtt::property::USER_PROPERTY);
  EXPECT_EQ(std::get<0>(status), "status");
  EXPECT_EQ(std::get<1>(status), "200");
  auto body = boost::json::parse(reply->get_payload_str()).as_object();
  EXPECT_EQ(body.at("value").as_int64(), 42);

  auto reqs = io_.call([&] { return requests_; });
  ASSERT_EQ(reqs.size(), 1u);
  const auto* read = std::get_if<gateway::core::SdoRead>(&reqs[0].command);
  ASSERT_NE(read, nullptr);
  EXPECT_EQ(reqs[0].network, 2u);
  EXPECT_EQ(read->node, 5);
  // {"index":"1017","subIndex":0}, decoded
  EXPECT_EQ(read->index, 0x1017);
  EXPECT_EQ(read->sub, 0);
  EXPECT_FALSE(read->type);
}

TEST_F(MqttPublisherTest, RequestOverMqtt311WithReplyToInBody) {
  start_broker();
  start_publisher(config());
  Subscriber client(broker_->uri(), "requester3", {"replies/v3"}, {});
  ASSERT_TRUE(client.connect());

  client.client()
      .publish(::mqtt::make_message("canopen/gw1/1/0/nmt",
                                    R"({"command":"start","replyTo":"replies/v3","correlationId":"c-7"})", 1, false))
      ->wait_for(5s);
  client.client()
      .publish(::mqtt::make_message("canopen/gw1/1/9/sdo/write",
                                    R"({"value":5,"type":"u8","replyTo":"replies/v3","correlationId":8})", 1, false))
      ->wait_for(5s);
  ASSERT_TRUE(client.wait_count(2, 10s));
  auto r0 = boost::json::parse(client.messages().at(0)->get_payload_str()).as_object();
  EXPECT_EQ(r0.at("correlationId").as_string(), "c-7");
  EXPECT_EQ(r0.at("value").as_int64(), 42);
  auto r1 = boost::json::parse(client.messages().at(1)->get_payload_str()).as_object();
  EXPECT_EQ(r1.at("correlationId").as_int64(), 8);

  auto reqs = io_.call([&] { return requests_; });
  ASSERT_EQ(reqs.size(), 2u);
  const auto* nmt = std::get_if<gateway::core::Nmt>(&reqs[0].command);
  ASSERT_NE(nmt, nullptr) << "reply fields removed, the rest decoded";
  EXPECT_EQ(nmt->node, 0);
  EXPECT_EQ(nmt->command, canopen::NmtCommand::Start);  // {"command":"start"}
  // An SDO write to node 9; without an index its body does not decode, so
  // the core gets it as undecodable (and answers 400 once it has checked the caller).
  const auto* write = std::get_if<gateway::core::Undecodable>(&reqs[1].command);
  ASSERT_NE(write, nullptr);
  EXPECT_EQ(write->operation, gateway::core::Operation::sdo_write);
  EXPECT_EQ(write->node, 9);
}

// The request's token reaches the handler (which checks it, see
// gateway/auth) and leaves the body: MQTT 5 user property "authorization",
// or "token" in a JSON body (3.1.1).
TEST_F(MqttPublisherTest, RequestTokenFromUserPropertyOrBody) {
  start_broker();
  start_publisher(config());
  Subscriber v5(broker_->uri(), "token5", {"replies/t5"}, {MQTTVERSION_5, true});
  ASSERT_TRUE(v5.connect());
  auto msg = ::mqtt::make_message("canopen/gw1/1/5/sdo/read", R"({"index":"1017","subIndex":0})", 1, false);
  msg->set_properties({::mqtt::property(::mqtt::property::RESPONSE_TOPIC, "replies/t5"),
                       ::mqtt::property(::mqtt::property::USER_PROPERTY, "authorization", "Bearer s3cret")});
  v5.client().publish(msg)->wait_for(5s);
  ASSERT_TRUE(v5.wait_count(1, 10s));

  Subscriber v3(broker_->uri(), "token3", {"replies/t3"}, {});
  ASSERT_TRUE(v3.connect());
  v3.client()
      .publish(::mqtt::make_message("canopen/gw1/1/5/nmt", R"({"command":"stop","token":"other","replyTo":"replies/t3"})",
                                    1, false))
      ->wait_for(5s);
  ASSERT_TRUE(v3.wait_count(1, 10s));

  auto reqs = io_.call([&] { return requests_; });
  ASSERT_EQ(reqs.size(), 2u);
  EXPECT_EQ(reqs[0].caller.token, "s3cret");
  EXPECT_FALSE(reqs[0].caller.authenticated);  // the core must check it
  EXPECT_EQ(reqs[1].caller.token, "other");
  const auto* stop = std::get_if<gateway::core::Nmt>(&reqs[1].command);
  ASSERT_NE(stop, nullptr) << "the token left the body: {\"command\":\"stop\"} decodes";
  EXPECT_EQ(stop->command, canopen::NmtCommand::Stop);
}

TEST_F(MqttPublisherTest, BadRequestsAreAnsweredOrLoggedNeverCrash) {
  start_broker();
  start_publisher(config());
  Subscriber client(broker_->uri(), "bad", {"replies/bad"}, {});
  ASSERT_TRUE(client.connect());
  auto send = [&](const std::string& topic, const std::string& body) {
    client.client().publish(::mqtt::make_message(topic, body, 1, false))->wait_for(5s);
  };
  const std::string rt = R"({"replyTo":"replies/bad","correlationId":1})";
  send("canopen/gw1/x/5/sdo/read", rt);       // bad network
  send("canopen/gw1/1/200/nmt", rt);          // node out of range
  send("canopen/gw1/1/0/sdo/read", rt);       // node 0 only for nmt
  send("canopen/gw1/1/5/sdo/read", "\xff\xfe not json");  // no reply address: executed, logged
  send("canopen/gw1/1/5/nmt", R"({"replyTo":"canopen/gw1/1/5/nmt"})");  // loop: dropped, not executed
  send("canopen/gw1/1/5/nmt", R"({"replyTo":"a/+/reply"})");  // wildcard: dropped, not executed
  send("canopen/gw1/1/5/nmt", "[1,2]");
  ASSERT_TRUE(client.wait_count(3, 10s));
  for (auto& m : client.messages()) {
    auto o = boost::json::parse(m->get_payload_str()).as_object();
    EXPECT_EQ(o.at("status").as_int64(), 400);
    EXPECT_EQ(o.at("title").as_string(), "Bad Request");
  }
  // The handler saw the two without a reply address.
  EXPECT_TRUE(eventually([&] { return request_count_ == 2; }, 10s));
  // Still serving.
  send("canopen/gw1/1/5/nmt", R"({"command":"stop","replyTo":"replies/bad","correlationId":"ok"})");
  ASSERT_TRUE(client.wait_count(4, 10s));
  EXPECT_EQ(boost::json::parse(client.messages().at(3)->get_payload_str()).as_object().at("correlationId").as_string(),
            "ok");
  EXPECT_GE(request_counters().bad_requests, 5u);
  EXPECT_EQ(request_counters().replies_refused, 2u);
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

// Issue 12, item 8: a requester (with or without a token) cannot make the
// gateway publish into its own topics, another gateway's or another
// system's, nor have it echo huge correlation data. Such a request is not
// executed and gets no reply anywhere; a flood of them is logged once.
TEST_F(MqttPublisherTest, RepliesGoOnlyToAllowedTopicsWithSmallCorrelationData) {
  start_broker();
  start_publisher(config(), &captured_log_);
  // One client sees every topic a refused reply could go to, and the fence.
  Subscriber watch(broker_->uri(), "watch",
                   {"canopen/gw1/status", "canopen/gw2/reply/x", "spBv1.0/g/NCMD/reply", "other/topic",
                    "myapp/reply/big", "myapp/reply/ok"},
                   {MQTTVERSION_5, true});
  ASSERT_TRUE(watch.connect());
  ASSERT_TRUE(watch.wait_topic("canopen/gw1/status", 10s));  // the retained online status
  Subscriber client(broker_->uri(), "requester", {}, {MQTTVERSION_5, true});
  ASSERT_TRUE(client.connect());
  auto v311 = [&](const std::string& topic, const std::string& body) {
    client.client().publish(::mqtt::make_message(topic, body, 1, false))->wait_for(5s);
  };
  auto v5 = [&](const std::string& reply_to, const std::string& correlation) {
    auto msg = ::mqtt::make_message("canopen/gw1/1/5/sdo/read", R"({"index":"1017","subIndex":0})", 1, false);
    msg->set_properties({::mqtt::property(::mqtt::property::RESPONSE_TOPIC, reply_to),
                         ::mqtt::property(::mqtt::property::CORRELATION_DATA, correlation)});
    client.client().publish(msg)->wait_for(5s);
  };
  const std::string read = R"({"index":"1017","subIndex":0,"replyTo":")";
  v311("canopen/gw1/1/5/sdo/read", read + R"(canopen/gw1/status"})");  // its own status
  v311("canopen/gw1/1/5/sdo/read", read + R"(canopen/gw2/reply/x"})");  // another gateway's
  v311("canopen/gw1/1/5/sdo/read", read + R"(spBv1.0/g/NCMD/reply"})");  // Sparkplug
  v311("canopen/gw1/1/5/sdo/read", read + R"(other/topic"})");  // no reply level
  v311("canopen/gw1/1/5/sdo/read", read + R"(myapp/reply/big","correlationId":")" + std::string(1100, 'x') + R"("})");
  v5("canopen/gw1/status", "c1");
  v5("myapp/reply/big", std::string(1025, 'x'));  // correlation data over 1 KiB
  const int refused = 7;
  // 1 KiB exactly is fine; the reply comes after any the refused ones would have caused.
  v5("myapp/reply/ok", std::string(1024, 'y'));
  ASSERT_TRUE(watch.wait_topic("myapp/reply/ok", 10s));

  const auto got = watch.messages();
  ASSERT_EQ(got.size(), 2u) << "only the online status and the allowed reply: " << got.back()->get_topic();
  EXPECT_EQ(got[1]->get_topic(), "myapp/reply/ok");
  EXPECT_EQ(::mqtt::get<std::string>(got[1]->get_properties(), ::mqtt::property::CORRELATION_DATA),
            std::string(1024, 'y'));
  EXPECT_EQ(request_count_, 1) << "a request whose reply is refused is not executed";
  const auto c = request_counters();
  EXPECT_EQ(c.replies_refused, static_cast<std::uint64_t>(refused));
  EXPECT_EQ(c.bad_requests, static_cast<std::uint64_t>(refused));
  EXPECT_EQ(c.replies, 1u);
  // Logged, but not once per request: a flood does not fill the journal.
  const auto text = io_.call([&] {
    captured_log_.flush();
    return captured_.text();
  });
  EXPECT_EQ(count_of(text, "dropped unanswered"), 1u) << text;
  EXPECT_NE(text.find("reply topic 'canopen/gw1/status'"), std::string::npos) << text;
}

// mqtt.reply-topics replaces the default rule.
TEST_F(MqttPublisherTest, ConfiguredReplyTopicsReplaceTheDefault) {
  start_broker();
  auto cfg = config();
  cfg.reply_topics = {"plant/+/answers"};
  start_publisher(cfg);
  Subscriber client(broker_->uri(), "requester", {"plant/7/answers", "myapp/reply/1"}, {});
  ASSERT_TRUE(client.connect());
  auto send = [&](const std::string& reply_to) {
    const std::string body = R"({"command":"start","replyTo":")" + reply_to + R"("})";
    client.client().publish(::mqtt::make_message("canopen/gw1/1/0/nmt", body, 1, false))->wait_for(5s);
  };
  send("myapp/reply/1");  // allowed by the default only
  send("plant/7/answers");
  ASSERT_TRUE(client.wait_count(1, 10s));
  EXPECT_EQ(client.messages().at(0)->get_topic(), "plant/7/answers");
  EXPECT_EQ(request_count_, 1);
  EXPECT_EQ(request_counters().replies_refused, 1u);
}

// Messages published while the broker is down are held by the publisher's
// DiskQueue and arrive exactly once, in order, after the broker is back.
// The subscriber has a persistent session on a broker with persistence, so
// its subscription exists as soon as the broker restarts.
TEST_F(MqttPublisherTest, BrokerOutageLosesNothingAndKeepsOrder) {
  start_broker(true);
  Subscriber sub(broker_->uri(), "outage-sub", {"canopen/gw1/1/5/tpdo/1"}, {MQTTVERSION_3_1_1, false});
  ASSERT_TRUE(sub.connect());
  start_publisher(config());

  for (int i = 0; i < 100; ++i) publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/tpdo/1", std::to_string(i), false));
  ASSERT_TRUE(sub.wait_count(100, 10s));
  // Every PUBACK in, so a resend after the outage would be a real duplicate.
  ASSERT_TRUE(eventually([&] { return counters().queue_depth == 0; }, 10s));

  broker_->stop();
  ASSERT_TRUE(eventually([&] { return !counters().connected; }, 10s));
  // 3000 QoS 1 messages at ~1000/s while the broker is down.
  constexpr int kN = 3100;
  for (int i = 100; i < kN; i += 10) {
    io_.call([&] {
      for (int j = i; j < i + 10; ++j)
        pub_->publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/tpdo/1", std::to_string(j), false));
    });
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_GE(counters().queue_depth, static_cast<std::uint64_t>(kN - 100));
  ASSERT_TRUE(broker_->start()) << broker_->log();

  ASSERT_TRUE(sub.wait_count(kN, 25s)) << "got " << sub.messages().size();
  std::this_thread::sleep_for(300ms);  // a duplicate would show up now
  EXPECT_EQ(sequence_problem(payloads(sub.messages()), kN), "");
  auto c = counters();
  EXPECT_EQ(c.in_flight, 0u);
  EXPECT_EQ(c.queue_depth, 0u);
  EXPECT_EQ(c.dropped, 0u);
  EXPECT_GE(c.reconnects, 1u);
}

// Issue 12, item 1: while the broker is connected, events of `outage` kinds
// (the QoS 0 ones by default: tpdo, heartbeat ...) never touch storage, not
// even an fdatasync; `disk` kinds still go to disk.
TEST_F(MqttPublisherTest, OutageEventsCostNoStorageWhileConnected) {
  start_broker();
  Subscriber live(broker_->uri(), "nowear", {"canopen/gw1/#"}, {});
  ASSERT_TRUE(live.connect());
  auto c = config();
  c.sync_interval = 10ms;
  start_publisher(c);
  for (int i = 0; i < 2000; ++i)
    publish(make_event(EventKind::Tpdo, "canopen/gw1/1/5/tpdo/1", std::to_string(i), false));
  ASSERT_TRUE(live.wait_count(2000 + 1, 10s)) << "got " << live.messages().size();  // + the status
  std::this_thread::sleep_for(100ms);  // several sync ticks
  EXPECT_EQ(payloads(live.on_topic("canopen/gw1/1/5/tpdo/1")), numbers(0, 2000));
  auto q = io_.call([&] { return pub_->queue_counters(); });
  EXPECT_EQ(q.written, 0u);
  EXPECT_EQ(q.storage_bytes, 0u);
  EXPECT_EQ(q.syncs, 0u);

  publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", "{}", false));  // a `disk` kind
  ASSERT_TRUE(live.wait_topic("canopen/gw1/1/5/emcy", 5s));
  ASSERT_TRUE(eventually([&] { return io_.call([&] { return pub_->queue_counters().syncs; }) > 0; }));
  q = io_.call([&] { return pub_->queue_counters(); });
  EXPECT_EQ(q.written, 1u);
  EXPECT_GT(q.storage_bytes, 0u);
}

// Events of `outage` kinds published while the broker is away go to disk
// (without fdatasync) and arrive, once and in order, when it is back.
TEST_F(MqttPublisherTest, OutageEventsDuringABrokerOutageArriveAfterIt) {
  broker_.emplace(true);
  broker_->extra_conf = "queue_qos0_messages true\n";  // for the subscriber's offline spell
  ASSERT_TRUE(broker_->start()) << broker_->log();
  Subscriber sub(broker_->uri(), "outage-q0", {"canopen/gw1/1/5/tpdo/1"}, {MQTTVERSION_3_1_1, false});
  ASSERT_TRUE(sub.connect());
  start_publisher(config());
  for (int i = 0; i < 100; ++i) publish(make_event(EventKind::Tpdo, "canopen/gw1/1/5/tpdo/1", std::to_string(i), false));
  ASSERT_TRUE(sub.wait_count(100, 10s));
  broker_->stop();
  ASSERT_TRUE(eventually([&] { return !counters().connected; }, 10s));
  constexpr int kN = 2100;
  io_.call([&] {
    for (int i = 100; i < kN; ++i)
      pub_->publish(make_event(EventKind::Tpdo, "canopen/gw1/1/5/tpdo/1", std::to_string(i), false));
  });
  auto q = io_.call([&] { return pub_->queue_counters(); });
  EXPECT_EQ(q.depth, static_cast<std::uint64_t>(kN - 100));
  ASSERT_TRUE(broker_->start()) << broker_->log();
  ASSERT_TRUE(sub.wait_count(kN, 25s)) << "got " << sub.messages().size();
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(sequence_problem(payloads(sub.messages()), kN), "");
  q = io_.call([&] { return pub_->queue_counters(); });
  EXPECT_EQ(q.syncs, 0u);  // nothing durable: never synced
  EXPECT_EQ(counters().dropped, 0u);
}

// Issue 12, item 5: the sync timer running between a publish and its send
// (here every millisecond) is not a stall: no restart, no duplicates.
TEST_F(MqttPublisherTest, SyncTimerBetweenPublishAndSendIsNoStall) {
  start_broker();
  Subscriber live(broker_->uri(), "race", {"canopen/gw1/1/5/emcy"}, {});
  ASSERT_TRUE(live.connect());
  auto c = config();
  c.sync_interval = 1ms;
  start_publisher(c);
  constexpr int kN = 3000;
  for (int i = 0; i < kN; i += 10) {
    io_.call([&] {
      for (int j = i; j < i + 10; ++j)
        pub_->publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", std::to_string(j), false));
    });
    if (i % 300 == 0) std::this_thread::sleep_for(2ms);
  }
  ASSERT_TRUE(live.wait_count(kN, 20s)) << "got " << live.messages().size();
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(sequence_problem(payloads(live.messages()), kN), "");
  EXPECT_EQ(counters().stalls, 0u);
}

// kill -9 of a publisher process while the broker is down loses nothing:
// a new process on the same queue directory delivers all, in order.
TEST_F(MqttPublisherTest, KillDash9WhileBrokerDownLosesNothing) {
  start_broker(true);
  Subscriber sub(broker_->uri(), "kill-sub", {"canopen/gwk/test/seq"}, {MQTTVERSION_3_1_1, false});
  ASSERT_TRUE(sub.connect());
  const std::string uri = broker_->uri();
  broker_->stop();

  const auto qdir = (queue_dir_.path() / "tool-q").string();
  constexpr int kN = 2000;
  auto run_tool = [&](int count, const char* extra) {
    std::string cmd = std::string(MQTT_PUBLISH_TOOL) + " " + uri + " " + qdir + " gwk " + std::to_string(count) + " 0 " +
                      extra + " 2>&1";
    return ::popen(cmd.c_str(), "r");
  };
  // First run: queue everything, then SIGKILL.
  {
    const auto pidfile = (queue_dir_.path() / "pid").string();
    std::string cmd = std::string("exec ") + MQTT_PUBLISH_TOOL + " " + uri + " " + qdir + " gwk " + std::to_string(kN) +
                      " 0 hold";
    pid_t pid = ::fork();
    if (pid == 0) {
      int fd = ::open(pidfile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ASSERT_TRUE(eventually([&] {
      std::ifstream f(pidfile);
      std::string s;
      return std::getline(f, s) && s == "queued";
    }, 20s));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status));
  }
  ASSERT_TRUE(broker_->start()) << broker_->log();
  ASSERT_TRUE(eventually([&] { return sub.connects() >= 2; }, 15s));
  // Second run: drain what the first one queued.
  FILE* p = run_tool(0, "");
  ASSERT_NE(p, nullptr);
  char line[256];
  std::string out;
  while (std::fgets(line, sizeof line, p) != nullptr) out += line;
  EXPECT_EQ(::pclose(p), 0) << out;
  EXPECT_NE(out.find("drained"), std::string::npos) << out;
  ASSERT_TRUE(sub.wait_count(kN, 20s)) << "got " << sub.messages().size();
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(sequence_problem(payloads(sub.messages()), kN), "");
}

// The Will: when the publisher's process dies, the broker publishes the
// offline status (retained).
TEST_F(MqttPublisherTest, WillOfflineWhenPublisherIsKilled) {
  start_broker();
  Subscriber sub(broker_->uri(), "will-sub", {"canopen/gww/status"}, {});
  ASSERT_TRUE(sub.connect());
  const auto outfile = (queue_dir_.path() / "out").string();
  std::string cmd = std::string("exec ") + MQTT_PUBLISH_TOOL + " " + broker_->uri() + " " +
                    (queue_dir_.path() / "will-q").string() + " gww 1 0 hold";
  pid_t pid = ::fork();
  if (pid == 0) {
    int fd = ::open(outfile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_TRUE(sub.wait_count(1, 15s));
  EXPECT_EQ(sub.messages().at(0)->get_payload_str(), R"({"state":"online"})");
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(sub.wait_count(2, 15s));
  EXPECT_EQ(sub.messages().at(1)->get_payload_str(), R"({"state":"offline"})");
  // Retained: a new subscriber sees offline.
  Subscriber late(broker_->uri(), "will-late", {"canopen/gww/status"}, {});
  ASSERT_TRUE(late.connect());
  ASSERT_TRUE(late.wait_count(1, 5s));
  EXPECT_EQ(late.messages().at(0)->get_payload_str(), R"({"state":"offline"})");
  EXPECT_TRUE(late.messages().at(0)->is_retained());
}

// A broker that refuses MQTT 5: the publisher falls back to 3.1.1, and
// events and requests (replyTo in the body) still work.
TEST_F(MqttPublisherTest, FallsBackTo311WhenBrokerRefuses5) {
  start_broker();
  V311OnlyProxy proxy(broker_->port());
  Subscriber sub(broker_->uri(), "fallback-sub", {"canopen/gw1/#", "replies/fb"}, {});
  ASSERT_TRUE(sub.connect());
  auto c = config();
  c.server_uri = "tcp://127.0.0.1:" + std::to_string(proxy.port());
  start_publisher(c);
  EXPECT_EQ(counters().mqtt_version, 4);
  EXPECT_GE(proxy.refused_v5(), 1);
  publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", "{}", false));
  ASSERT_TRUE(sub.wait_topic("canopen/gw1/1/5/emcy", 10s));
  sub.client()
      .publish(::mqtt::make_message("canopen/gw1/1/5/nmt", R"({"command":"start","replyTo":"replies/fb","correlationId":3})",
                                    1, false))
      ->wait_for(5s);
  ASSERT_TRUE(sub.wait_topic("replies/fb", 10s));
  auto r = boost::json::parse(sub.on_topic("replies/fb").at(0)->get_payload_str()).as_object();
  EXPECT_EQ(r.at("correlationId").as_int64(), 3);
  io_.call([&] { pub_.reset(); });  // before the proxy goes
}

// Issue 27 item 1 (contract "Brokers"): a broker that closes the
// connection at an MQTT 5 CONNECT without a CONNACK (RabbitMQ's MQTT
// plugin) is tried again with 3.1.1 at once, and the log says so.
TEST_F(MqttPublisherTest, FallsBackTo311WhenTheBrokerClosesAtMqtt5) {
  start_broker();
  V311OnlyProxy proxy(broker_->port(), V311OnlyProxy::Refusal::Close);
  Subscriber sub(broker_->uri(), "fallback-close-sub", {"canopen/gw1/#"}, {});
  ASSERT_TRUE(sub.connect());
  auto c = config();
  c.server_uri = "tcp://127.0.0.1:" + std::to_string(proxy.port());
  c.reconnect_min = 10s;  // "at once": not after the backoff
  start_publisher(c, &captured_log_);
  EXPECT_EQ(counters().mqtt_version, 4);
  EXPECT_EQ(proxy.refused_v5(), 1);
  publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", "{}", false));
  ASSERT_TRUE(sub.wait_topic("canopen/gw1/1/5/emcy", 10s));
  const auto text = captured_.text();
  EXPECT_NE(text.find("without a CONNACK to an MQTT 5 CONNECT"), std::string::npos) << text;
  io_.call([&] { pub_.reset(); });  // before the proxy goes
}

// Issue 27 item 3 (contract "Brokers"): a broker restarted without
// persistence has lost the retained topics (status, bus, node states);
// they are published again on the new connection, each its latest value.
TEST_F(MqttPublisherTest, RetainedTopicsArePublishedAgainOnANewConnection) {
  start_broker(false);
  start_publisher(config());
  publish(make_event(EventKind::Bus, "canopen/gw1/1/bus", "error-passive", true));
  publish(make_event(EventKind::State, "canopen/gw1/1/5/state", "pre-operational", true));
  publish(make_event(EventKind::State, "canopen/gw1/1/5/state", "operational", true));
  publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", "not retained", false));
  ASSERT_TRUE(eventually([&] { return counters().queue_depth == 0; }, 10s));

  broker_->stop();  // no persistence: the retained messages are gone
  ASSERT_TRUE(eventually([&] { return !counters().connected; }, 10s));
  ASSERT_TRUE(broker_->start()) << broker_->log();
  ASSERT_TRUE(eventually([&] { return counters().connected; }, 20s));
  ASSERT_TRUE(eventually([&] { return counters().queue_depth == 0; }, 10s));

  // A client that comes afterwards gets them from the broker.
  Subscriber late(broker_->uri(), "late-sub", {"canopen/gw1/#"}, {});
  ASSERT_TRUE(late.connect());
  ASSERT_TRUE(late.wait_topic("canopen/gw1/1/5/state", 10s));
  ASSERT_TRUE(late.wait_topic("canopen/gw1/1/bus", 10s));
  std::this_thread::sleep_for(300ms);
  const auto state = late.on_topic("canopen/gw1/1/5/state");
  ASSERT_EQ(state.size(), 1u);
  EXPECT_EQ(state[0]->get_payload_str(), "operational") << "the latest value";
  EXPECT_TRUE(state[0]->is_retained());
  EXPECT_EQ(late.on_topic("canopen/gw1/1/bus").at(0)->get_payload_str(), "error-passive");
  EXPECT_TRUE(late.on_topic("canopen/gw1/1/5/emcy").empty()) << "only retained topics";
  EXPECT_FALSE(late.on_topic("canopen/gw1/status").empty()) << "the status too";
}

// Issue 27 item 2 (contract "Brokers"): with a list of brokers, a lost
// connection is followed by the next broker; what the disk queue took
// meanwhile drains to whichever is reached, in order, nothing lost; the
// connected broker is in the counters (GET /api/v1/gateway, /metrics). It
// stays there until that one goes, then the next in turn (here the first
// again).
TEST_F(MqttPublisherTest, FailsOverToTheNextBrokerAndLosesNothing) {
  start_broker();
  Broker standby;
  ASSERT_TRUE(standby.start()) << standby.log();
  Subscriber on_a(broker_->uri(), "failover-a", {"canopen/gw1/1/5/emcy"}, {});
  Subscriber on_b(standby.uri(), "failover-b", {"canopen/gw1/1/5/emcy"}, {});
  ASSERT_TRUE(on_a.connect());
  ASSERT_TRUE(on_b.connect());
  auto c = config();
  c.standby_uris = {"mqtt://127.0.0.1:" + std::to_string(standby.port())};
  start_publisher(c);
  EXPECT_EQ(counters().broker, broker_->uri()) << "the first of the list first";

  for (int i = 0; i < 100; ++i) publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", std::to_string(i), false));
  ASSERT_TRUE(on_a.wait_count(100, 10s));
  ASSERT_TRUE(eventually([&] { return counters().queue_depth == 0; }, 10s));

  broker_->stop();
  ASSERT_TRUE(eventually([&] { return counters().broker != broker_->uri(); }, 10s));
  // While it switches (disconnected, then on the standby): QoS 1 messages
  // to the disk queue, then straight out.
  constexpr int kN = 1100;
  for (int i = 100; i < kN; i += 10) {
    io_.call([&] {
      for (int j = i; j < i + 10; ++j)
        pub_->publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", std::to_string(j), false));
    });
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_TRUE(eventually([&] { return counters().broker == standby.uri(); }, 10s)) << standby.log();
  ASSERT_TRUE(on_b.wait_count(kN - 100, 20s)) << "got " << on_b.messages().size();
  std::this_thread::sleep_for(300ms);  // a duplicate would show up now
  auto got = payloads(on_b.messages());
  EXPECT_EQ(got, numbers(100, kN)) << "every message published after the switch began, once, in order";
  auto k = counters();
  EXPECT_EQ(k.dropped, 0u);
  EXPECT_EQ(k.queue_depth, 0u);
  EXPECT_EQ(k.reconnects, 1u);

  // The first broker back, the standby gone: back to the first.
  ASSERT_TRUE(broker_->start()) << broker_->log();
  Subscriber on_a_again(broker_->uri(), "failover-a2", {"canopen/gw1/1/5/emcy"}, {});
  ASSERT_TRUE(on_a_again.connect());
  standby.stop();
  ASSERT_TRUE(eventually([&] { return counters().broker == broker_->uri(); }, 20s));
  publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", "after", false));
  ASSERT_TRUE(on_a_again.wait_topic("canopen/gw1/1/5/emcy", 10s));
  EXPECT_EQ(payloads(on_a_again.messages()), std::vector<std::string>{"after"});
  EXPECT_EQ(counters().dropped, 0u);
}

// Issue 27 item 2: at start, a broker of the list that does not answer is
// followed by the next at once (not after the reconnect delay), and the log
// says so; a whole round without an answer waits the delay.
TEST_F(MqttPublisherTest, AtStartABrokerThatDoesNotAnswerIsFollowedByTheNextAtOnce) {
  start_broker();
  const int dead = free_port();  // nothing listens
  auto c = config();
  c.server_uri = "tcp://127.0.0.1:" + std::to_string(dead);
  c.standby_uris = {"tcp://127.0.0.1:" + std::to_string(broker_->port())};
  c.reconnect_min = 10s;  // "at once": well before the delay
  const auto t0 = std::chrono::steady_clock::now();
  start_publisher(c, &captured_log_);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s);
  EXPECT_EQ(counters().broker, broker_->uri());
  EXPECT_EQ(counters().mqtt_version, 5);
  const auto text = captured_.text();
  EXPECT_NE(text.find("connect to tcp://127.0.0.1:" + std::to_string(dead) + " failed: "), std::string::npos) << text;
  EXPECT_NE(text.find("trying " + broker_->uri()), std::string::npos) << text;
}

// Batching: every PUBLISH ready in one io loop turn goes to the socket in
// one write (QoS 0: the messages leave the queue once written).
TEST_F(MqttPublisherTest, OneWriteCarriesEveryPublishOfALoopTurn) {
  start_broker();
  Subscriber live(broker_->uri(), "batch", {"canopen/gw1/1/5/tpdo/1"}, {});
  ASSERT_TRUE(live.connect());
  auto c = config();
  c.qos.fill(0);
  start_publisher(c);
  ASSERT_TRUE(eventually([&] { return counters().queue_depth == 0 && counters().in_flight == 0; }));
  const auto before = counters();
  constexpr int kN = 500;
  io_.call([&] {
    for (int i = 0; i < kN; ++i)
      pub_->publish(make_event(EventKind::Tpdo, "canopen/gw1/1/5/tpdo/1", std::to_string(i), false));
  });
  ASSERT_TRUE(live.wait_count(kN, 10s)) << "got " << live.messages().size();
  EXPECT_EQ(payloads(live.messages()), numbers(0, kN));
  const auto after = counters();
  EXPECT_EQ(after.acked - before.acked, static_cast<std::uint64_t>(kN));
  EXPECT_EQ(after.queue_depth, 0u);
  // One write; a keepalive PINGREQ could add one.
  EXPECT_LE(after.socket_writes - before.socket_writes, 2u);
}

// QoS 1: the window (mosquitto's Receive Maximum 20, less 4: 16) is
// refilled once at most half of it is in flight, so each write carries at
// least 8 messages while the queue has them, and never more than 16.
TEST_F(MqttPublisherTest, Qos1RefillsTheWindowOncePerBatchOfAcks) {
  start_broker();
  Subscriber live(broker_->uri(), "batch1", {"canopen/gw1/1/5/emcy"}, {});
  ASSERT_TRUE(live.connect());
  start_publisher(config());
  ASSERT_TRUE(eventually([&] { return counters().queue_depth == 0 && counters().in_flight == 0; }));
  const auto before = counters();
  constexpr int kN = 2000;
  io_.call([&] {
    for (int i = 0; i < kN; ++i)
      pub_->publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", std::to_string(i), false));
  });
  ASSERT_TRUE(live.wait_count(kN, 20s)) << "got " << live.messages().size();
  EXPECT_EQ(payloads(live.messages()), numbers(0, kN));
  ASSERT_TRUE(eventually([&] { return counters().queue_depth == 0; }));
  const auto after = counters();
  EXPECT_EQ(after.acked - before.acked, static_cast<std::uint64_t>(kN));
  EXPECT_LE(after.in_flight, 0u);
  const auto writes = after.socket_writes - before.socket_writes;
  EXPECT_GE(writes, static_cast<std::uint64_t>(kN / 16));  // never more than the window per write
  EXPECT_LE(writes, static_cast<std::uint64_t>(kN / 8 + 8));
  std::printf("QoS 1: %d messages in %llu writes\n", kN, static_cast<unsigned long long>(writes));
}

// Keepalive: an idle connection stays up (PINGREQs), and a broker that
// stops answering is noticed within 1.5 keepalives and reconnected.
TEST_F(MqttPublisherTest, KeepalivePingsAndNoticesASilentBroker) {
  start_broker();
  auto c = config();
  c.keepalive = 1s;
  start_publisher(c);
  const auto w0 = counters().socket_writes;
  std::this_thread::sleep_for(3500ms);  // mosquitto drops a client silent for 1.5 s
  auto k = counters();
  EXPECT_TRUE(k.connected);
  EXPECT_EQ(k.reconnects, 0u);
  EXPECT_GE(k.socket_writes - w0, 3u);  // PINGREQs
  io_.call([&] { pub_.reset(); });

  // A fake broker: CONNACK, then silence (reads everything, answers nothing).
  FakeBroker fake([](int fd) {
    char buf[512];
    (void)!::read(fd, buf, sizeof buf);  // CONNECT
    const char connack[] = {0x20, 0x03, 0x00, 0x00, 0x00};
    (void)!::write(fd, connack, sizeof connack);
  });
  c.server_uri = fake.uri();
  start_publisher(c);
  EXPECT_TRUE(eventually([&] { return fake.accepted() >= 2; }, 6s)) << "no reconnect after the broker went silent";
  EXPECT_GE(counters().connects, 1u);
  io_.call([&] { pub_.reset(); });
}

// TLS (mqtts://): a CA-signed server certificate for 127.0.0.1 is
// verified (name included); with another CA the connection is refused.
TEST_F(MqttPublisherTest, TlsWithServerVerification) {
  if (std::system("command -v openssl >/dev/null 2>&1") != 0) GTEST_SKIP() << "no openssl";
  const auto d = queue_dir_.path() / "tls";
  fs::create_directories(d);
  const std::string D = d.string();
  const std::string gen =
      "cd " + D + " && exec >openssl.log 2>&1 && "
      "openssl req -x509 -newkey rsa:2048 -nodes -keyout ca.key -out ca.pem -days 2 -subj /CN=test-ca && "
      "openssl req -newkey rsa:2048 -nodes -keyout server.key -out server.csr -subj /CN=127.0.0.1 && "
      "printf 'subjectAltName=IP:127.0.0.1\\n' > san.ext && "
      "openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out server.pem -days 2 "
      "-extfile san.ext && "
      "openssl req -x509 -newkey rsa:2048 -nodes -keyout other.key -out other.pem -days 2 -subj /CN=other-ca && "
      "chmod 644 *.key";
  ASSERT_EQ(std::system(gen.c_str()), 0) << "openssl failed, see " << D << "/openssl.log";
  broker_.emplace(false);
  const int tls_port = free_port();
  broker_->extra_conf = "listener " + std::to_string(tls_port) + " 127.0.0.1\ncafile " + D + "/ca.pem\ncertfile " +
                          D + "/server.pem\nkeyfile " + D + "/server.key\n";
  ASSERT_TRUE(broker_->start()) << broker_->log();
  ASSERT_TRUE(eventually([&] { return port_open(tls_port); }, 5s));
  Subscriber live(broker_->uri(), "tls-sub", {"canopen/gw1/#"}, {});
  ASSERT_TRUE(live.connect());

  auto c = config();
  c.server_uri = "mqtts://127.0.0.1:" + std::to_string(tls_port);
  c.ca_file = D + "/ca.pem";
  start_publisher(c);
  EXPECT_EQ(counters().mqtt_version, 5);
  for (int i = 0; i < 50; ++i) publish(make_event(EventKind::Emcy, "canopen/gw1/1/5/emcy", std::to_string(i), false));
  ASSERT_TRUE(eventually([&] { return live.on_topic("canopen/gw1/1/5/emcy").size() == 50; }, 10s));
  EXPECT_EQ(payloads(live.on_topic("canopen/gw1/1/5/emcy")), numbers(0, 50));
  io_.call([&] { pub_->stop(); });
  ASSERT_TRUE(eventually([&] {
    auto st = live.on_topic("canopen/gw1/status");
    return !st.empty() && st.back()->get_payload_str() == R"({"state":"offline"})";
  }, 5s));
  io_.call([&] { pub_.reset(); });

  // The wrong CA: never connects.
  c.ca_file = D + "/other.pem";
  c.queue.dir = queue_dir_.path() / "q2";
  io_.call([&] {
    pub_ = std::make_unique<MqttPublisher>(io_.io(), c, captured_log_);
    pub_->start();
  });
  // Waits for the failed handshake itself (logged once), not for a time.
  const auto log_text = [&] { return io_.call([&] { return captured_.text(); }); };
  EXPECT_TRUE(eventually([&] { return log_text().find("failed: ") != std::string::npos; }, 10s)) << log_text();
  EXPECT_FALSE(counters().connected);
  EXPECT_EQ(counters().connects, 0u);
}

// connect_timeout covers the CONNACK: a server that accepts TCP but never
// answers is given up on and tried again with backoff.
TEST_F(MqttPublisherTest, ConnectTimeoutWithoutConnack) {
  FakeBroker mute;  // accepts TCP, never answers
  MqttConfig c;
  c.server_uri = mute.uri();
  c.client_id = "timeout-test";
  c.gateway_id = kGw;
  c.queue.dir = queue_dir_.path() / "q";
  c.connect_timeout = 1s;
  c.reconnect_min = 100ms;
  c.reconnect_max = 200ms;
  io_.call([&] {
    pub_ = std::make_unique<MqttPublisher>(io_.io(), c, log_);
    pub_->start();
  });
  EXPECT_TRUE(eventually([&] { return mute.accepted() >= 2; }, 5s)) << "no second attempt after the timeout";
  EXPECT_FALSE(counters().connected);
  EXPECT_EQ(counters().connects, 0u);
  io_.call([&] { pub_.reset(); });
}
