// EdgeClient against a real mosquitto (skipped without /usr/sbin/mosquitto):
// what a Sparkplug host sees on spBv1.0/#, through Paho (an independent
// client) and decoded with the generated protobuf parser. Spec references:
// ../shared/ref/sparkplug-ascii-lss-facts.md section A.
#include "sparkplug/edge_client.hpp"

#include <gtest/gtest.h>

#include "unit/gateway/mqtt/mqtt_support.hpp"
#include "unit/gateway/sparkplug/sparkplug_support.hpp"

namespace gateway::sparkplug {
namespace {

using namespace std::chrono_literals;
using mqtt_test::Broker;
using mqtt_test::eventually;
using mqtt_test::IoThread;
using mqtt_test::Subscriber;
using sparkplug_test::metric;
using sparkplug_test::parse;
namespace pb = sparkplug_test::pb;

const std::string kNbirth = "spBv1.0/plant1/NBIRTH/gw1";
const std::string kNdeath = "spBv1.0/plant1/NDEATH/gw1";
const std::string kDbirth = "spBv1.0/plant1/DBIRTH/gw1/d1";

std::vector<Metric> device_metrics() {
  Metric sw;
  sw.name = "Statusword";
  sw.datatype = DataType::UInt16;
  sw.value = std::uint64_t{0x0237};
  sw.object = ObjectRef{0x6041, 0};
  Metric target;
  target.name = "Target velocity";
  target.datatype = DataType::Int32;
  target.value = std::int64_t{0};
  target.object = ObjectRef{0x60FF, 0};
  return {sw, target};
}

std::int64_t bdseq_of(const ::mqtt::const_message_ptr& m) {
  const auto p = parse(m->to_string());
  const auto* b = metric(p, "bdSeq");
  return b ? static_cast<std::int64_t>(b->long_value()) : -1;
}

// A TCP relay in front of the broker whose cut() closes both sides at once:
// the broker sees the edge node's connection end without DISCONNECT, as
// after kill -9 or a network loss.
class CuttableRelay {
 public:
  explicit CuttableRelay(int broker_port) : broker_port_(broker_port) {
    listen_fd_ = mqtt_test::listen_on_loopback(port_);
    thread_ = std::thread([this] { run(); });
  }
  ~CuttableRelay() {
    stop_ = true;
    thread_.join();
    ::close(listen_fd_);
  }
  std::string uri() const { return "tcp://127.0.0.1:" + std::to_string(port_); }
  void cut() { cut_ = true; }
  // While refusing, every connection is closed as soon as it is accepted.
  void refuse(bool on) { refuse_ = on; }
  // While paused, nothing is read from the edge node: its socket buffers
  // fill up as with a broker that does not keep up.
  void pause(bool on) { pause_ = on; }

 private:
  void run() {
    int c = -1, b = -1;
    char tmp[4096];
    while (!stop_) {
      if (cut_) {
        if (c >= 0) ::close(c);
        if (b >= 0) ::close(b);
        c = b = -1;
        cut_ = false;
      }
      if (c < 0) {
        pollfd p{listen_fd_, POLLIN, 0};
        if (::poll(&p, 1, 20) <= 0) continue;
        c = ::accept(listen_fd_, nullptr, nullptr);
        if (refuse_) {
          ::close(c);
          c = -1;
          continue;
        }
        b = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        a.sin_port = htons(static_cast<std::uint16_t>(broker_port_));
        if (::connect(b, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) cut_ = true;
        continue;
      }
      pollfd ps[2] = {{pause_ ? -1 : c, POLLIN, 0}, {b, POLLIN, 0}};
      if (::poll(ps, 2, 20) <= 0) continue;
      for (int i = 0; i < 2; ++i) {
        if (ps[i].fd < 0 || ps[i].revents == 0) continue;
        const ssize_t n = ::read(ps[i].fd, tmp, sizeof tmp);
        if (n <= 0 || ::write(i == 0 ? b : c, tmp, static_cast<std::size_t>(n)) != n) cut_ = true;
      }
    }
    if (c >= 0) ::close(c);
    if (b >= 0) ::close(b);
  }

  int broker_port_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false}, cut_{false}, refuse_{false}, pause_{false};
  std::thread thread_;
};

class EdgeClientTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!mqtt_test::have_mosquitto()) GTEST_SKIP() << "no mosquitto";
    ASSERT_TRUE(broker.start());
    host = std::make_unique<Subscriber>(broker.uri(), "host", std::vector<std::string>{"spBv1.0/#"},
                                        Subscriber::Options{});
    ASSERT_TRUE(host->connect());
  }
  void TearDown() override { drop(); }

  EdgeClientConfig config(int version = 5, std::string uri = {}) {
    EdgeClientConfig c;
    c.session = {"plant1", "gw1", ""};
    c.mqtt.server_uri = uri.empty() ? broker.uri() : uri;
    c.mqtt.client_id = "canopen-gateway-gw1-spb";
    c.mqtt.mqtt_version = version;
    c.mqtt.reconnect_min = 50ms;
    c.mqtt.reconnect_max = 200ms;
    c.state_dir = state.path();
    return c;
  }
  // A client with device d1 known before it connects.
  void make(EdgeClientConfig c) {
    io.call([&] {
      client = std::make_unique<EdgeClient>(io.io(), std::move(c), log);
      client->on_command = [this](WriteCommand w) { commands.push_back(std::move(w)); };
      std::vector<Outgoing> out;
      client->edge().device_online(out, "d1", device_metrics(), client->now_ms());
      client->send(out);
      client->start();
    });
  }
  void stop() {
    io.call([&] { client->stop(); });
  }
  void drop() {
    io.call([&] { client.reset(); });
  }
  bool wait_messages(const std::string& topic, std::size_t n, std::chrono::milliseconds t = 10s) {
    return eventually([&] { return host->on_topic(topic).size() >= n; }, t);
  }
  void publish(const std::string& topic, const std::string& payload) {
    ::mqtt::async_client& c = host->client();
    c.publish(topic, payload.data(), payload.size(), 1, false)->wait_for(5s);
  }

  Broker broker;
  mqtt_test::TempDir state;
  std::unique_ptr<Subscriber> host;
  Logger log{LogLevel::Error};
  IoThread io;  // after the client's state; the client lives on it
  std::unique_ptr<EdgeClient> client;
  std::vector<WriteCommand> commands;  // io thread; read after io.call()
};

// Facts A.4.3/A.4.4/A.5: the births are the first messages, NBIRTH with
// seq 0 and the bdSeq of its Will (0 on a fresh state dir), then DBIRTH
// (seq 1); QoS 0 (a QoS 1 subscriber gets QoS 0) and not retained.
TEST_F(EdgeClientTest, NbirthComesFirstWithSeq0AndTheBdSeq) {
  make(config());
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  const auto all = host->messages();
  ASSERT_GE(all.size(), 2u);
  EXPECT_EQ(all[0]->get_topic(), kNbirth);
  EXPECT_EQ(all[1]->get_topic(), kDbirth);
  const auto nbirth = parse(all[0]->to_string());
  EXPECT_EQ(nbirth.seq(), 0u);
  EXPECT_EQ(bdseq_of(all[0]), 0);
  ASSERT_NE(metric(nbirth, "Node Control/Rebirth"), nullptr);
  EXPECT_EQ(parse(all[1]->to_string()).seq(), 1u);
  for (const auto& m : all) {
    EXPECT_EQ(m->get_qos(), 0) << m->get_topic();
    EXPECT_FALSE(m->is_retained()) << m->get_topic();
  }
  EXPECT_TRUE(io.call([&] { return client->connected(); }));
  const auto c = io.call([&] { return client->counters(); });
  EXPECT_EQ(c.published_by_type[static_cast<std::size_t>(EdgeClient::Type::NBIRTH)], 1u);
  EXPECT_EQ(c.published_by_type[static_cast<std::size_t>(EdgeClient::Type::DBIRTH)], 1u);
}

// Facts A.5: bdSeq goes up by one with every CONNECT, on a reconnect and
// across a new client (a restart) on the same state dir. The connection
// loss in between makes the broker publish the Will with the old bdSeq.
TEST_F(EdgeClientTest, BdSeqGoesUpByOneOnReconnectAndAcrossARestart) {
  CuttableRelay relay(broker.port());
  make(config(5, relay.uri()));
  ASSERT_TRUE(wait_messages(kNbirth, 1));
  EXPECT_EQ(bdseq_of(host->on_topic(kNbirth)[0]), 0);
  relay.cut();
  ASSERT_TRUE(wait_messages(kNbirth, 2));
  EXPECT_EQ(bdseq_of(host->on_topic(kNbirth)[1]), 1);
  ASSERT_TRUE(wait_messages(kNdeath, 1));
  EXPECT_EQ(bdseq_of(host->on_topic(kNdeath)[0]), 0) << "the Will of the lost connection";
  EXPECT_EQ(io.call([&] { return client->counters().reconnects; }), 1u);
  drop();
  make(config(5, relay.uri()));
  ASSERT_TRUE(wait_messages(kNbirth, 3));
  EXPECT_EQ(bdseq_of(host->on_topic(kNbirth)[2]), 2);
}

// Issue 27 item 2 (contract "Brokers"): with sparkplug.uri a list, the
// edge node goes on to the next broker when its broker goes; there it is a
// new connection: a new NBIRTH (seq 0) with the next bdSeq, and the DBIRTH.
// broker() names the one it is on.
TEST_F(EdgeClientTest, FailsOverToTheNextBrokerWithANewBirthAndTheNextBdSeq) {
  Broker standby;
  ASSERT_TRUE(standby.start()) << standby.log();
  Subscriber standby_host(standby.uri(), "host-b", {"spBv1.0/#"}, {});
  ASSERT_TRUE(standby_host.connect());
  auto c = config();
  c.mqtt.standby_uris = {standby.uri()};
  make(c);
  ASSERT_TRUE(wait_messages(kNbirth, 1));
  EXPECT_EQ(bdseq_of(host->on_topic(kNbirth)[0]), 0);
  EXPECT_EQ(io.call([&] { return client->broker(); }), broker.uri());

  broker.stop();
  ASSERT_TRUE(eventually([&] { return standby_host.on_topic(kDbirth).size() >= 1; }, 10s)) << standby.log();
  const auto births = standby_host.on_topic(kNbirth);
  ASSERT_EQ(births.size(), 1u);
  EXPECT_EQ(bdseq_of(births[0]), 1) << "the next CONNECT's bdSeq";
  EXPECT_EQ(parse(births[0]->to_string()).seq(), 0u);
  EXPECT_EQ(io.call([&] { return client->broker(); }), standby.uri());
  EXPECT_EQ(io.call([&] { return client->counters().reconnects; }), 1u);
  drop();
}

// Facts A.4.6, MQTT 3.1.1: a clean stop publishes NDEATH with the Will's
// bdSeq, and its DISCONNECT makes the broker discard the Will: exactly one
// NDEATH.
TEST_F(EdgeClientTest, CleanStopOn311PublishesNdeathAndTheBrokerDropsTheWill) {
  make(config(4));
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  stop();
  ASSERT_TRUE(wait_messages(kNdeath, 1));
  std::this_thread::sleep_for(500ms);  // the Will would follow at once
  const auto deaths = host->on_topic(kNdeath);
  ASSERT_EQ(deaths.size(), 1u);
  EXPECT_EQ(bdseq_of(deaths[0]), bdseq_of(host->on_topic(kNbirth)[0]));
  EXPECT_EQ(parse(deaths[0]->to_string()).has_seq(), false) << "NDEATH carries no seq (facts A.5)";
  EXPECT_FALSE(io.call([&] { return client->connected(); }));
}

// Facts A.4.6, MQTT 5: NDEATH, then DISCONNECT with reason 0x04 "Disconnect
// with Will Message": the broker publishes the Will as well, with the same
// bdSeq (a duplicate hosts ignore by bdSeq).
TEST_F(EdgeClientTest, CleanStopOn5PublishesNdeathAndDisconnectsWithTheWill) {
  make(config(5));
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  stop();
  ASSERT_TRUE(wait_messages(kNdeath, 2));
  const auto deaths = host->on_topic(kNdeath);
  const auto bd = bdseq_of(host->on_topic(kNbirth)[0]);
  EXPECT_EQ(bdseq_of(deaths[0]), bd);
  EXPECT_EQ(bdseq_of(deaths[1]), bd);
}

// Facts A.4.2: a connection that ends without DISCONNECT makes the broker
// publish the Will: NDEATH with the connection's bdSeq, QoS 1, not retained.
TEST_F(EdgeClientTest, AbruptCloseMakesTheBrokerPublishTheWill) {
  CuttableRelay relay(broker.port());
  make(config(4, relay.uri()));
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  relay.cut();  // the client sends nothing more on that connection
  ASSERT_TRUE(wait_messages(kNdeath, 1));
  const auto will = host->on_topic(kNdeath)[0];
  EXPECT_EQ(bdseq_of(will), 0);
  EXPECT_EQ(will->get_qos(), 1);
  ASSERT_TRUE(wait_messages(kNbirth, 2)) << "reconnected";
  EXPECT_EQ(bdseq_of(host->on_topic(kNbirth)[1]), 1);
  EXPECT_EQ(host->on_topic(kNdeath).size(), 1u) << "only the Will: the client did not stop";
  // Not retained: a host that subscribes now gets nothing on the topic.
  Subscriber late(broker.uri(), "late-host", {kNdeath}, Subscriber::Options{});
  ASSERT_TRUE(late.connect());
  std::this_thread::sleep_for(300ms);
  EXPECT_TRUE(late.on_topic(kNdeath).empty());
}

std::string command(const std::string& name, bool is_bool, std::int64_t value) {
  pb::Payload p;
  p.set_timestamp(1'767'225'600'000);
  auto* m = p.add_metrics();
  m->set_name(name);
  if (is_bool) {
    m->set_datatype(pb::Boolean);
    m->set_boolean_value(value != 0);
  } else {
    m->set_datatype(pb::Int32);
    m->set_int_value(static_cast<std::uint32_t>(value));
  }
  return p.SerializeAsString();
}

// Facts A.6: an NCMD Node Control/Rebirth repeats NBIRTH (seq 0, same
// bdSeq) and every DBIRTH.
TEST_F(EdgeClientTest, NcmdRebirthRepeatsTheBirths) {
  make(config());
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  publish("spBv1.0/plant1/NCMD/gw1", command("Node Control/Rebirth", true, 1));
  ASSERT_TRUE(wait_messages(kDbirth, 2));
  const auto births = host->on_topic(kNbirth);
  ASSERT_EQ(births.size(), 2u);
  EXPECT_EQ(parse(births[1]->to_string()).seq(), 0u);
  EXPECT_EQ(bdseq_of(births[1]), bdseq_of(births[0]));
  const auto c = io.call([&] { return client->counters(); });
  EXPECT_EQ(c.rebirths, 1u);
  EXPECT_EQ(c.commands, 1u);
  EXPECT_TRUE(io.call([&] { return commands.empty(); })) << "a rebirth is not a write";
}

// Contract "Sparkplug B", DCMD: a write of a device metric reaches
// on_command resolved to that metric and typed.
TEST_F(EdgeClientTest, DcmdWriteReachesOnCommand) {
  make(config());
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  publish("spBv1.0/plant1/DCMD/gw1/d1", command("Target velocity", false, -250));
  ASSERT_TRUE(eventually([&] { return io.call([&] { return commands.size(); }) == 1; }, 10s));
  const auto w = io.call([&] { return commands.at(0); });
  EXPECT_EQ(w.device, "d1");
  ASSERT_EQ(w.items.size(), 1u);
  EXPECT_EQ(w.items[0].metric, 1u);
  EXPECT_EQ(w.items[0].value, Value(std::int64_t{-250}));
  EXPECT_TRUE(w.refused.empty());
}

// The seam: what an EdgeSession call appends while the client is not
// connected is dropped (nothing queued), and the EdgeSession keeps the
// values for the birth once it connects.
TEST_F(EdgeClientTest, DataWhileOfflineIsDroppedAndShowsInTheNextBirth) {
  CuttableRelay relay(broker.port());
  relay.refuse(true);
  io.call([&] {
    client = std::make_unique<EdgeClient>(io.io(), config(5, relay.uri()), log);
    client->start();
    std::vector<Outgoing> out;
    client->edge().device_online(out, "d1", device_metrics(), client->now_ms());
    const Update u[] = {{0, std::uint64_t{0x0637}, client->now_ms()}};
    client->edge().device_data(out, "d1", u, client->now_ms());
    client->send(out);
    EXPECT_TRUE(out.empty());
  });
  std::this_thread::sleep_for(200ms);
  EXPECT_FALSE(io.call([&] { return client->connected(); }));
  relay.refuse(false);
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  const auto dbirth = parse(host->on_topic(kDbirth)[0]->to_string());
  ASSERT_NE(metric(dbirth, "Statusword"), nullptr);
  EXPECT_EQ(metric(dbirth, "Statusword")->int_value(), 0x0637u);
  EXPECT_TRUE(host->on_topic("spBv1.0/plant1/DDATA/gw1/d1").empty()) << "nothing queued while offline";
}

// Backpressure: while the broker does not take the edge node's bytes, DATA
// beyond max_buffered is dropped (counted), births are not; once the link
// has drained the whole birth sequence goes out again (same bdSeq, seq 0),
// so the host has current values instead of a seq gap (facts A.5, A.6).
TEST_F(EdgeClientTest, DataDroppedUnderBackpressureIsFollowedByARebirth) {
  CuttableRelay relay(broker.port());
  EdgeClientConfig c = config(5, relay.uri());
  c.max_buffered = 64u << 10;
  c.mqtt.keepalive = std::chrono::seconds(60);
  make(std::move(c));
  ASSERT_TRUE(wait_messages(kDbirth, 1));
  relay.pause(true);
  // Far more than the socket buffers and max_buffered hold.
  ASSERT_TRUE(eventually(
      [&] {
        return io.call([&] {
          std::vector<Outgoing> out;
          for (int i = 0; i < 2000; ++i) {
            const Update u[] = {{1, std::int64_t{i}, client->now_ms()}};
            client->edge().device_data(out, "d1", u, client->now_ms());
          }
          client->send(out);
          return client->counters().dropped > 0;
        });
      },
      20s));
  relay.pause(false);
  ASSERT_TRUE(wait_messages(kNbirth, 2, 20s)) << "births again once drained";
  const auto births = host->on_topic(kNbirth);
  EXPECT_EQ(parse(births[1]->to_string()).seq(), 0u);
  EXPECT_EQ(bdseq_of(births[1]), bdseq_of(births[0])) << "the same connection";
  ASSERT_TRUE(wait_messages(kDbirth, 2));
  const auto dbirth = parse(host->on_topic(kDbirth)[1]->to_string());
  ASSERT_NE(metric(dbirth, "Target velocity"), nullptr);
  EXPECT_EQ(static_cast<std::int32_t>(metric(dbirth, "Target velocity")->int_value()), 1999) << "the latest value";
  const auto counters = io.call([&] { return client->counters(); });
  EXPECT_GT(counters.dropped, 0u);
  EXPECT_EQ(counters.rebirths, 1u);
  EXPECT_EQ(counters.reconnects, 0u);
}

}  // namespace
}  // namespace gateway::sparkplug
