// The MQTT session without a broker or a socket: the test plays the broker
// (bytes in), reads what the session writes (decoded with mqtt_codec) and
// moves a fake clock.
#include "mqtt/session.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "canopen/clock.hpp"
#include "mqtt/mqtt_codec.hpp"

namespace {

using namespace std::chrono_literals;
using gateway::mqtt::BrokerLimits;
using gateway::mqtt::Session;
using gateway::mqtt::SessionEvents;
namespace codec = gateway::mqtt::codec;

struct Recorder : SessionEvents {
  std::vector<BrokerLimits> connected;
  std::vector<std::pair<int, bool>> refused;
  std::vector<std::uint64_t> acked;
  std::vector<std::pair<std::uint64_t, int>> rejected;
  std::vector<std::string> incoming;  // topics
  std::vector<std::pair<std::string, bool>> lost;
  std::vector<bool> lost_fell_back;
  int deadline_changes = 0;
  int batches = 0;
  void on_connected(const BrokerLimits& l) override { connected.push_back(l); }
  void on_refused(std::uint8_t code, bool fell_back) override { refused.emplace_back(code, fell_back); }
  void on_acked(std::uint64_t t) override { acked.push_back(t); }
  void on_rejected(std::uint64_t t, std::uint8_t reason) override { rejected.emplace_back(t, reason); }
  void on_publish(const codec::Publish& p) override { incoming.emplace_back(p.topic); }
  void on_subscribe_refused(std::uint8_t) override {}
  void on_batch_end(bool) override { ++batches; }
  void on_lost(const std::string& why, bool was_up, bool fell_back) override {
    lost.emplace_back(why, was_up);
    lost_fell_back.push_back(fell_back);
  }
  void on_deadline_changed() override { ++deadline_changes; }
};

std::string bytes(std::initializer_list<int> b) {
  std::string s;
  for (int v : b) s.push_back(static_cast<char>(v));
  return s;
}

// A v5 CONNACK with the given properties (already encoded).
std::string connack5(int code, const std::string& props = {}) {
  std::string s = bytes({0x20});
  codec::put_varint(s, static_cast<std::uint32_t>(3 + props.size()));
  s += bytes({0x00, code, static_cast<int>(props.size())});
  return s + props;
}

std::string puback(std::uint16_t pid, std::uint8_t reason = 0, std::uint8_t version = codec::kMqtt5) {
  std::string s;
  codec::encode_puback(s, version, pid, reason);
  return s;
}

// The packets the session wrote, one string per packet (type + body kept).
struct Written {
  codec::PacketType type;
  std::uint8_t flags;
  std::string body;
};
std::vector<Written> packets(const std::string& out) {
  codec::Decoder dec;
  dec.feed(out);
  std::vector<Written> r;
  codec::Packet p;
  while (dec.next(p)) r.push_back({p.type, p.flags, std::string(p.body)});
  EXPECT_EQ(dec.error(), codec::Error::None);
  EXPECT_EQ(dec.buffered(), 0u);
  return r;
}

codec::Publish as_publish(const Written& w, std::uint8_t version = codec::kMqtt5) {
  codec::Packet p{w.type, w.flags, w.body};
  codec::Publish pub;
  EXPECT_EQ(codec::parse_publish(p, version, pub), codec::Error::None);
  return pub;
}

class SessionTest : public ::testing::Test {
 protected:
  Session::Options options() {
    Session::Options o;
    o.client_id = "gw-1";
    o.username = "user";
    o.password = "secret";
    o.will_topic = "canopen/gw/status";
    o.will_payload = "offline";
    o.keepalive = 10s;
    o.inflight_window = 256;
    return o;
  }
  void make(Session::Options o) { s = std::make_unique<Session>(std::move(o), ev); }

  // open + transport + CONNACK accepted (props: the broker's limits).
  void connect(const std::string& connack = connack5(0)) {
    ASSERT_EQ(s->open(clock.now()), codec::Error::None);
    out.clear();
    s->transport_connected(out, clock.now());
    s->received(out, connack, clock.now());
    ASSERT_TRUE(s->up());
    out.clear();
  }

  std::uint16_t pid_of(const std::string& wire) {
    auto ps = packets(wire);
    EXPECT_EQ(ps.size(), 1u);
    return as_publish(ps.at(0)).packet_id;
  }

  canopen::FakeClock clock;
  Recorder ev;
  std::unique_ptr<Session> s;
  std::string out;
};

// MQTT 3.1.2: CONNECT carries clean start (the queue holds the backlog,
// not the broker), the Will (the retained offline status, QoS 1), user and
// password, keepalive; under MQTT 5 Session Expiry 0, Receive Maximum and
// Maximum Packet Size.
TEST_F(SessionTest, ConnectCarriesCleanStartWillKeepaliveAndV5Properties) {
  make(options());
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  EXPECT_EQ(s->state(), Session::State::Connecting);
  s->transport_connected(out, clock.now());
  EXPECT_EQ(s->state(), Session::State::AwaitConnack);
  const auto ps = packets(out);
  ASSERT_EQ(ps.size(), 1u);
  ASSERT_EQ(ps[0].type, codec::PacketType::Connect);
  const std::string& b = ps[0].body;
  ASSERT_GE(b.size(), 10u);
  EXPECT_EQ(b.substr(0, 6), bytes({0x00, 0x04, 'M', 'Q', 'T', 'T'}));
  EXPECT_EQ(b[6], 5);  // protocol level
  const auto flags = static_cast<std::uint8_t>(b[7]);
  EXPECT_EQ(flags & 0x02, 0x02);  // clean start
  EXPECT_EQ(flags & 0x04, 0x04);  // Will
  EXPECT_EQ(flags & 0x18, 0x08);  // Will QoS 1
  EXPECT_EQ(flags & 0x20, 0x20);  // Will retained
  EXPECT_EQ(flags & 0xC0, 0xC0);  // user name and password
  EXPECT_EQ((static_cast<std::uint8_t>(b[8]) << 8) | static_cast<std::uint8_t>(b[9]), 10);  // keepalive s
  const auto props_len = static_cast<std::size_t>(b[10]);
  const std::string props = b.substr(11, props_len);
  EXPECT_NE(props.find(bytes({0x11, 0, 0, 0, 0})), std::string::npos);  // Session Expiry 0
  EXPECT_NE(props.find(bytes({0x21, 0x00, 64})), std::string::npos);    // Receive Maximum 64
  EXPECT_NE(props.find(bytes({0x27, 0x00, 0x40, 0x00, 0x00})), std::string::npos);  // Maximum Packet Size 4 MiB
  const std::string rest = b.substr(11 + props_len);
  for (const char* field : {"gw-1", "canopen/gw/status", "offline", "user", "secret"})
    EXPECT_NE(rest.find(field), std::string::npos) << field;
}

// A Sparkplug edge node's CONNECT (facts A.4.1, A.4.2): clean session /
// clean start with Session Expiry 0, and the Will (NDEATH) at QoS 1 NOT
// retained; under MQTT 3.1.1 as under 5.
TEST_F(SessionTest, WillQosAndRetainAreOptionsAndTheSessionIsClean) {
  for (int version : {5, 4}) {
    SCOPED_TRACE(version);
    auto o = options();
    o.mqtt_version = version;
    o.will_topic = "spBv1.0/G/NDEATH/E";
    o.will_qos = 1;
    o.will_retain = false;
    make(o);
    out.clear();
    ASSERT_EQ(s->open(clock.now()), codec::Error::None);
    s->transport_connected(out, clock.now());
    const auto ps = packets(out);
    ASSERT_EQ(ps.size(), 1u);
    const std::string& b = ps[0].body;
    EXPECT_EQ(b[6], version);
    const auto flags = static_cast<std::uint8_t>(b[7]);
    EXPECT_EQ(flags & 0x02, 0x02);  // clean session / clean start
    EXPECT_EQ(flags & 0x04, 0x04);  // Will
    EXPECT_EQ(flags & 0x18, 0x08);  // Will QoS 1
    EXPECT_EQ(flags & 0x20, 0x00);  // Will not retained
    if (version == 5) {
      const std::string props = b.substr(11, static_cast<std::size_t>(b[10]));
      EXPECT_NE(props.find(bytes({0x11, 0, 0, 0, 0})), std::string::npos);  // Session Expiry 0
    }
    EXPECT_NE(b.find("spBv1.0/G/NDEATH/E"), std::string::npos);
  }
}

// An intentional disconnect (facts A.4.6): under MQTT 5 DISCONNECT carries
// reason 0x04 "Disconnect with Will Message" when asked (the broker then
// publishes the Will); 0 is the normal one; 3.1.1 has no reason byte at all.
TEST_F(SessionTest, DisconnectCarriesItsReasonUnderMqtt5Only) {
  make(options());
  connect();
  s->disconnect(out, Session::kDisconnectWithWill);
  auto ps = packets(out);
  ASSERT_EQ(ps.size(), 1u);
  ASSERT_EQ(ps[0].type, codec::PacketType::Disconnect);
  std::uint8_t reason = 0xFF;
  ASSERT_EQ(codec::parse_disconnect({ps[0].type, ps[0].flags, ps[0].body}, codec::kMqtt5, reason), codec::Error::None);
  EXPECT_EQ(reason, 0x04);
  out.clear();
  s->disconnect(out);
  ps = packets(out);
  ASSERT_EQ(ps.size(), 1u);
  ASSERT_EQ(codec::parse_disconnect({ps[0].type, ps[0].flags, ps[0].body}, codec::kMqtt5, reason), codec::Error::None);
  EXPECT_EQ(reason, 0x00);

  auto o = options();
  o.mqtt_version = 4;
  make(o);
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  out.clear();
  s->transport_connected(out, clock.now());
  s->received(out, bytes({0x20, 0x02, 0x00, 0x00}), clock.now());
  ASSERT_TRUE(s->up());
  out.clear();
  s->disconnect(out, Session::kDisconnectWithWill);
  EXPECT_EQ(out, bytes({0xE0, 0x00}));  // 3.1.1: no reason, the broker drops the Will
}

TEST_F(SessionTest, ConnackAcceptedReportsTheBrokersLimits) {
  make(options());
  connect(connack5(0, bytes({0x21, 0x00, 20,              // Receive Maximum 20
                             0x24, 0x00,                  // Maximum QoS 0
                             0x25, 0x00,                  // Retain Available 0
                             0x27, 0x00, 0x00, 0x01, 0x00  // Maximum Packet Size 256
                             })));
  ASSERT_EQ(ev.connected.size(), 1u);
  const BrokerLimits& l = ev.connected[0];
  EXPECT_EQ(l.version, codec::kMqtt5);
  EXPECT_EQ(l.receive_maximum, 20u);
  EXPECT_EQ(l.maximum_qos, 0);
  EXPECT_FALSE(l.retain_available);
  EXPECT_EQ(l.maximum_packet_size, 256u);
  EXPECT_EQ(l.keepalive, 10s);

  // Maximum QoS 0: a QoS 1 message goes out as QoS 0; Retain Available 0:
  // without retain; Maximum Packet Size: a larger one is refused unsent.
  ASSERT_TRUE(s->publish(out, 1, "t", "v", 1, true).ok());
  const auto pub = as_publish(packets(out).at(0));
  EXPECT_EQ(pub.qos, 0);
  EXPECT_FALSE(pub.retain);
  out.clear();
  EXPECT_EQ(s->publish(out, 2, "t", std::string(300, 'x'), 0, false).error, codec::Error::PacketTooLarge);
  EXPECT_TRUE(out.empty());
}

TEST_F(SessionTest, ConnackRefusedEndsTheAttemptWithItsCode) {
  make(options());
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  s->received(out, connack5(0x87), clock.now());  // not authorized
  ASSERT_EQ(ev.refused.size(), 1u);
  EXPECT_EQ(ev.refused[0], std::make_pair(0x87, false));
  EXPECT_EQ(s->state(), Session::State::Idle);
  EXPECT_FALSE(s->deadline());
  EXPECT_EQ(s->version(), codec::kMqtt5);  // not a reason to fall back
  EXPECT_TRUE(ev.connected.empty());
}

// A broker that refuses MQTT 5 (v5 reason 0x84, or a 3.1.1 broker's
// return code 1): the next CONNECT is 3.1.1.
TEST_F(SessionTest, FallsBackTo311WhenTheBrokerRefuses5) {
  for (int code : {0x84, 0x01}) {
    SCOPED_TRACE(code);
    ev = Recorder{};
    make(options());
    ASSERT_EQ(s->open(clock.now()), codec::Error::None);
    s->transport_connected(out, clock.now());
    s->received(out, code == 0x84 ? connack5(0x84) : bytes({0x20, 0x02, 0x00, 0x01}), clock.now());
    ASSERT_EQ(ev.refused.size(), 1u);
    EXPECT_EQ(ev.refused[0], std::make_pair(code, true));
    EXPECT_EQ(s->version(), codec::kMqtt311);
    out.clear();
    ASSERT_EQ(s->open(clock.now()), codec::Error::None);
    s->transport_connected(out, clock.now());
    EXPECT_EQ(packets(out).at(0).body[6], 4);  // protocol level 3.1.1
    s->received(out, bytes({0x20, 0x02, 0x00, 0x00}), clock.now());
    ASSERT_EQ(ev.connected.size(), 1u);
    EXPECT_EQ(ev.connected[0].version, codec::kMqtt311);
  }
  // Configured for 3.1.1 only: a refusal is just a refusal.
  ev = Recorder{};
  auto o = options();
  o.mqtt_version = 4;
  make(o);
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  s->received(out, bytes({0x20, 0x02, 0x00, 0x01}), clock.now());
  EXPECT_EQ(ev.refused.at(0), std::make_pair(1, false));
}

// Issue 27 item 1 (contract "Brokers"): a broker that closes the
// connection without a CONNACK to an MQTT 5 CONNECT (RabbitMQ's MQTT
// plugin) gets 3.1.1 next, at once; if that fails as well (a broker that
// was only restarting), the attempt after it is 5 again. Closes before the
// transport was up, or after a CONNACK, change nothing; neither does one
// when configured for 3.1.1 only.
TEST_F(SessionTest, FallsBackTo311WhenTheBrokerClosesWithoutAConnack) {
  make(options());
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  s->transport_closed("connection closed by the broker");
  ASSERT_EQ(ev.lost_fell_back, std::vector<bool>{true});
  EXPECT_FALSE(ev.lost.at(0).second);
  EXPECT_EQ(s->version(), codec::kMqtt311);
  out.clear();
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  EXPECT_EQ(packets(out).at(0).body[6], 4) << "protocol level 3.1.1";
  s->received(out, bytes({0x20, 0x02, 0x00, 0x00}), clock.now());
  ASSERT_EQ(ev.connected.size(), 1u);
  EXPECT_EQ(ev.connected[0].version, codec::kMqtt311);
  s->transport_closed("reset");
  EXPECT_EQ(ev.lost_fell_back.back(), false) << "after a CONNACK: a lost connection, not a refusal of 5";
  EXPECT_EQ(s->version(), codec::kMqtt311) << "the broker took 3.1.1: kept";

  // The 3.1.1 attempt fails too: 5 again for the next.
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_closed("connection refused");  // before the transport was up
  EXPECT_EQ(s->version(), codec::kMqtt5);
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_closed("connection refused");
  EXPECT_EQ(ev.lost_fell_back.back(), false) << "no CONNECT reached the broker";
  EXPECT_EQ(s->version(), codec::kMqtt5);

  // 3.1.1 only: a close is just a close.
  ev = Recorder{};
  auto o = options();
  o.mqtt_version = 4;
  make(o);
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  s->transport_closed("connection closed by the broker");
  EXPECT_EQ(ev.lost_fell_back, std::vector<bool>{false});
  EXPECT_EQ(s->version(), codec::kMqtt311);
}

// Issue 27 item 2: a broker that refused MQTT 5 fixes 3.1.1 for itself
// only; the client moving on to the next broker of its list resets the
// version (reset_version), so that one is asked for 5 first. Not while an
// attempt is under way; never above what is configured.
TEST_F(SessionTest, ResetVersionForgetsAFallbackForTheNextBroker) {
  make(options());
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  s->received(out, connack5(0x84), clock.now());  // "unsupported protocol version"
  ASSERT_EQ(s->version(), codec::kMqtt311);
  out.clear();
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->reset_version();  // Connecting: ignored
  EXPECT_EQ(s->version(), codec::kMqtt311);
  s->transport_closed("connection refused");  // before the transport: no fallback logic
  ASSERT_EQ(s->version(), codec::kMqtt311) << "refused 5 in so many words: kept for this broker";
  s->reset_version();
  EXPECT_EQ(s->version(), codec::kMqtt5);
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  EXPECT_EQ(packets(out).at(0).body[6], 5) << "protocol level 5 for the next broker";

  auto o = options();
  o.mqtt_version = 4;
  make(o);
  s->reset_version();
  EXPECT_EQ(s->version(), codec::kMqtt311) << "3.1.1 only stays 3.1.1";
}

TEST_F(SessionTest, WindowFillsAndPubacksRefillIt) {
  auto o = options();
  o.inflight_window = 3;
  make(o);
  connect();
  std::vector<std::uint16_t> pids;
  for (std::uint64_t t = 100; t < 103; ++t) {
    ASSERT_TRUE(s->window_open());
    ASSERT_TRUE(s->publish(out, t, "t", "v", 1, false).ok());
    pids.push_back(pid_of(out));
    out.clear();
  }
  EXPECT_FALSE(s->window_open());
  EXPECT_EQ(s->inflight_qos1(), 3u);
  // QoS 0 is not windowed; it leaves when written.
  ASSERT_TRUE(s->publish(out, 200, "t", "v", 0, false).ok());
  EXPECT_EQ(s->in_flight(), 4u);
  EXPECT_EQ(s->wrote(clock.now()), 1u);
  EXPECT_EQ(ev.acked, (std::vector<std::uint64_t>{200}));

  const int batches = ev.batches;
  s->received(out, puback(pids[1]) + puback(pids[0]), clock.now());
  EXPECT_EQ(ev.acked, (std::vector<std::uint64_t>{200, 101, 100}));
  EXPECT_EQ(s->inflight_qos1(), 1u);
  EXPECT_TRUE(s->window_open());
  EXPECT_EQ(ev.batches, batches + 1);  // one refill per read, not per PUBACK
  // A second PUBACK for the same id changes nothing.
  s->received(out, puback(pids[0]), clock.now());
  EXPECT_EQ(ev.acked.size(), 3u);
  EXPECT_EQ(s->inflight_qos1(), 1u);
}

// MQTT 5 Receive Maximum caps the window, less 4 for status and replies
// (a Receive Maximum of 8 or less is taken whole).
TEST_F(SessionTest, ReceiveMaximumCapsTheWindow) {
  make(options());
  connect(connack5(0, bytes({0x21, 0x00, 20})));
  EXPECT_EQ(s->window(), 16u);
  for (std::uint64_t t = 1; t <= 16; ++t) ASSERT_TRUE(s->publish(out, t, "t", "v", 1, false).ok());
  EXPECT_FALSE(s->window_open());

  ev = Recorder{};
  make(options());
  connect(connack5(0, bytes({0x21, 0x00, 6})));
  EXPECT_EQ(s->window(), 6u);
  ev = Recorder{};
  make(options());
  connect(connack5(0));  // none: the configured window
  EXPECT_EQ(s->window(), 256u);
}

// What was in flight when the connection was lost is sent again after the
// reconnect, oldest first, with DUP; new messages go without.
TEST_F(SessionTest, ResendAfterReconnectOldestFirstWithDup) {
  make(options());
  connect();
  std::vector<std::uint16_t> pids;
  for (std::uint64_t t = 10; t <= 13; ++t) {
    ASSERT_TRUE(s->publish(out, t, "t", "v", 1, false).ok());
    EXPECT_FALSE(as_publish(packets(out).at(0)).dup);
    pids.push_back(pid_of(out));
    out.clear();
  }
  s->received(out, puback(pids[0]), clock.now());  // 10 is done
  s->transport_closed("read: connection reset");
  ASSERT_EQ(ev.lost.size(), 1u);
  EXPECT_EQ(ev.lost[0], std::make_pair(std::string("read: connection reset"), true));
  EXPECT_EQ(s->in_flight(), 0u);
  const auto list = s->resend_list();
  EXPECT_EQ(std::vector<std::uint64_t>(list.begin(), list.end()), (std::vector<std::uint64_t>{11, 12, 13}));

  connect();
  for (std::uint64_t t = 11; t <= 14; ++t) {
    ASSERT_TRUE(s->publish(out, t, "t", "v", 1, false).ok());
    EXPECT_EQ(as_publish(packets(out).at(0)).dup, t != 14) << t;
    out.clear();
  }
  EXPECT_TRUE(s->resend_list().empty());
  // A PUBACK for an id of the lost connection means nothing now.
  s->received(out, puback(pids[1]), clock.now());
  EXPECT_EQ(ev.acked, (std::vector<std::uint64_t>{10}));
  EXPECT_EQ(s->inflight_qos1(), 4u);
}

// MQTT 5 PUBACK reason >= 0x80: the broker refused the message.
TEST_F(SessionTest, PubackReasonFrom0x80IsARejection) {
  make(options());
  connect();
  ASSERT_TRUE(s->publish(out, 7, "t", "v", 1, false).ok());
  const auto pid = pid_of(out);
  out.clear();
  ASSERT_TRUE(s->publish(out, 8, "t", "v", 1, false).ok());
  const auto pid2 = pid_of(out);
  s->received(out, puback(pid, 0x87) + puback(pid2, 0x10), clock.now());  // not authorized; no subscribers
  ASSERT_EQ(ev.rejected.size(), 1u);
  EXPECT_EQ(ev.rejected[0], std::make_pair(std::uint64_t{7}, 0x87));
  EXPECT_EQ(ev.acked, (std::vector<std::uint64_t>{8}));  // 0x10 is a success
  EXPECT_EQ(s->inflight_qos1(), 0u);
}

// Keepalive (MQTT 3.1.2.10): a PINGREQ every half keepalive when the link
// is quiet; no byte from the broker for 1.5 keepalives ends the connection.
TEST_F(SessionTest, KeepalivePingsWhenQuietAndLosesASilentBroker) {
  make(options());  // keepalive 10 s
  connect();
  ASSERT_TRUE(s->deadline());
  EXPECT_EQ(*s->deadline(), clock.now() + 5s);
  const int changes = ev.deadline_changes;

  clock.advance(5s);
  s->on_timer(out, clock.now());
  ASSERT_EQ(packets(out).size(), 1u);
  EXPECT_EQ(packets(out)[0].type, codec::PacketType::Pingreq);
  EXPECT_EQ(*s->deadline(), clock.now() + 5s);
  EXPECT_GT(ev.deadline_changes, changes);  // told, so the owner re-arms its timer
  out.clear();

  // The PINGRESP shows the broker is alive: no loss at 15 s.
  s->received(out, bytes({0xD0, 0x00}), clock.now());
  s->wrote(clock.now());
  clock.advance(5s);
  s->on_timer(out, clock.now());
  EXPECT_EQ(packets(out).size(), 1u);  // quiet again: the next PINGREQ
  out.clear();
  // Silence since 5 s: one ping outstanding is enough; lost after more
  // than 1.5 keepalives (15 s).
  clock.advance(5s);
  s->on_timer(out, clock.now());
  EXPECT_TRUE(out.empty());
  clock.advance(5s);
  s->on_timer(out, clock.now());  // 15 s of silence: not more yet
  EXPECT_TRUE(ev.lost.empty());
  clock.advance(5s);
  s->on_timer(out, clock.now());
  ASSERT_EQ(ev.lost.size(), 1u);
  EXPECT_EQ(ev.lost[0].first, "no answer from the broker within 1.5 keepalive intervals");
  EXPECT_TRUE(ev.lost[0].second);
  EXPECT_FALSE(s->deadline());
}

TEST_F(SessionTest, BusyLinkNeedsNoPing) {
  make(options());
  connect();
  for (int i = 0; i < 4; ++i) {
    clock.advance(2500ms);
    s->received(out, bytes({0xD0, 0x00}), clock.now());
    s->wrote(clock.now());
    s->on_timer(out, clock.now());
  }
  EXPECT_TRUE(out.empty());
  EXPECT_TRUE(ev.lost.empty());
}

// MQTT 5 Server Keep Alive replaces the keepalive the gateway asked for.
TEST_F(SessionTest, ServerKeepAliveWins) {
  make(options());  // asks for 10 s
  connect(connack5(0, bytes({0x13, 0x00, 0x04})));
  EXPECT_EQ(ev.connected.at(0).keepalive, 4s);
  EXPECT_EQ(*s->deadline(), clock.now() + 2s);
  clock.advance(2s);
  s->on_timer(out, clock.now());
  EXPECT_EQ(packets(out).at(0).type, codec::PacketType::Pingreq);
  clock.advance(2s);
  s->on_timer(out, clock.now());
  EXPECT_TRUE(ev.lost.empty());
  clock.advance(2s);
  s->on_timer(out, clock.now());  // 6 s of silence = 1.5 x 4 s: not yet more
  EXPECT_TRUE(ev.lost.empty());
  clock.advance(2s);
  s->on_timer(out, clock.now());
  EXPECT_EQ(ev.lost.size(), 1u);
}

TEST_F(SessionTest, ConnectTimeoutCoversTransportAndConnack) {
  make(options());  // connect_timeout 10 s
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  EXPECT_EQ(*s->deadline(), clock.now() + 10s);
  clock.advance(4s);
  s->transport_connected(out, clock.now());
  EXPECT_EQ(*s->deadline(), clock.now() + 6s);  // unchanged by the transport
  clock.advance(6s);
  s->on_timer(out, clock.now());
  ASSERT_EQ(ev.lost.size(), 1u);
  EXPECT_EQ(ev.lost[0], std::make_pair(std::string("connect timeout"), false));
  EXPECT_EQ(s->state(), Session::State::Idle);
}

// An incoming QoS 1 PUBLISH (a request) is acknowledged and handed on.
TEST_F(SessionTest, IncomingQos1PublishGetsPuback) {
  make(options());
  connect();
  std::string wire;
  codec::Publish in;
  in.topic = "canopen/gw/1/5/sdo/read";
  in.payload = "{}";
  in.qos = 1;
  in.packet_id = 0x1234;
  ASSERT_EQ(codec::encode_publish(wire, codec::kMqtt5, in), codec::Error::None);
  s->received(out, wire, clock.now());
  EXPECT_EQ(ev.incoming, (std::vector<std::string>{"canopen/gw/1/5/sdo/read"}));
  EXPECT_EQ(out, puback(0x1234));
}

// Bytes a broker must not send end the connection (and say why).
TEST_F(SessionTest, ProtocolErrorsEndTheConnection) {
  make(options());
  ASSERT_EQ(s->open(clock.now()), codec::Error::None);
  s->transport_connected(out, clock.now());
  s->received(out, bytes({0xD0, 0x00}), clock.now());  // PINGRESP before CONNACK
  ASSERT_EQ(ev.lost.size(), 1u);
  EXPECT_EQ(ev.lost[0], std::make_pair(std::string("expected CONNACK"), false));

  connect();
  s->received(out, connack5(0), clock.now());
  ASSERT_EQ(ev.lost.size(), 2u);
  EXPECT_EQ(ev.lost[1], std::make_pair(std::string("second CONNACK"), true));

  connect();
  s->received(out, bytes({0x00, 0x00}), clock.now());  // packet type 0
  ASSERT_EQ(ev.lost.size(), 3u);
  EXPECT_EQ(ev.lost[2].first.rfind("malformed data from the broker", 0), 0u);
}

// A stall restart forgets the queue messages in flight (they are handed
// out again, with DUP) but keeps waiting for the status' PUBACK.
TEST_F(SessionTest, RestartWindowKeepsControlMessages) {
  make(options());
  connect();
  ASSERT_TRUE(s->publish_control(out, "canopen/gw/status", "online", true));
  const auto control_pid = pid_of(out);
  out.clear();
  ASSERT_TRUE(s->publish(out, 5, "t", "v", 1, false).ok());
  out.clear();
  s->restart_window();
  EXPECT_EQ(s->inflight_qos1(), 0u);
  ASSERT_TRUE(s->publish(out, 5, "t", "v", 1, false).ok());
  EXPECT_TRUE(as_publish(packets(out).at(0)).dup);
  const auto pid = pid_of(out);
  EXPECT_NE(pid, control_pid);
  s->received(out, puback(control_pid) + puback(pid), clock.now());
  EXPECT_EQ(ev.acked, (std::vector<std::uint64_t>{5}));  // the status' PUBACK is no queue event
}

}  // namespace
