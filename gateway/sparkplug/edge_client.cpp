#include "sparkplug/edge_client.hpp"

#include <boost/asio/post.hpp>

#include "metrics/metrics.hpp"
#include "metrics/registry.hpp"
#include "mqtt/client.hpp"
#include "mqtt/mqtt_codec.hpp"
#include "mqtt/session.hpp"

namespace gateway::sparkplug {
namespace {

namespace asio = boost::asio;
namespace codec = mqtt::codec;

constexpr const char* kTypeNames[EdgeClient::kTypes] = {"NBIRTH", "NDEATH", "DBIRTH", "DDEATH", "NDATA", "DDATA"};

// Largest packet accepted from the broker (commands, STATE).
constexpr std::uint32_t kMaxIncomingPacket = 1u << 20;

mqtt::Client::Options client_options(const mqtt::MqttConfig& c) {
  mqtt::Client::Options o;
  o.session = mqtt::Client::common_session_options(c);
  o.session.will_qos = 1;         // facts A.4.2: NDEATH Will QoS 1, not retained
  o.session.will_retain = false;  // (topic and payload: set_will() per CONNECT)
  o.session.maximum_packet_size = kMaxIncomingPacket;
  o.log_prefix = "sparkplug";
  o.connect_error_hint = "client id, user, ids not UTF-8?";
  return o;
}

// The message type of a topic spBv1.0/G/<TYPE>/E[/D] under `prefix`.
std::optional<EdgeClient::Type> type_of(std::string_view topic, std::string_view prefix) {
  if (!topic.starts_with(prefix)) return std::nullopt;
  topic.remove_prefix(prefix.size());
  const auto type = topic.substr(0, topic.find('/'));
  for (std::size_t i = 0; i < EdgeClient::kTypes; ++i)
    if (type == kTypeNames[i]) return static_cast<EdgeClient::Type>(i);
  return std::nullopt;
}

}  // namespace

const char* state_name(EdgeSession::State s) {
  switch (s) {
    case EdgeSession::State::Offline: return "offline";
    case EdgeSession::State::WaitingForHost: return "waiting-for-host";
    case EdgeSession::State::Born: return "online";
    case EdgeSession::State::Stopping: return "stopping";
  }
  return "offline";
}

const char* EdgeClient::type_name(Type t) { return kTypeNames[static_cast<std::size_t>(t)]; }

// The EdgeSession over the MQTT client (mqtt/client.hpp: connection, TLS,
// session, timers, reconnect backoff).
struct EdgeClient::Impl : std::enable_shared_from_this<EdgeClient::Impl>, mqtt::ClientEvents {
  Impl(asio::io_context& io_ctx, EdgeClientConfig c, Logger& l)
      : io(io_ctx), cfg(std::move(c)), log(l), store(cfg.state_dir), edge(cfg.session, store),
        client(io_ctx, cfg.mqtt, client_options(cfg.mqtt), *this, l), session(client.session()) {}

  asio::io_context& io;
  EdgeClientConfig cfg;
  Logger& log;
  EdgeClient* owner = nullptr;  // for on_command; reset when the client goes
  BdSeqStore store;
  EdgeSession edge;
  mqtt::Client client;
  mqtt::Session& session;    // the client's
  bool closing = false;      // the EdgeSession ended the session: close once drained
  bool rebirth_due = false;  // DATA was dropped: births again once drained
  bool born_here = false;    // an NBIRTH went out on this connection
  Counters counters;
  std::vector<Outgoing> scratch_out;  // reused by the handlers

  std::uint64_t now_ms() const {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                          std::chrono::system_clock::now().time_since_epoch())
                                          .count());
  }

  void start() { client.start(weak_from_this()); }

  // The connection is over, whoever ended it: the EdgeSession starts over
  // (a new bdSeq and births on the next connection).
  void went_down() {
    closing = false;
    rebirth_due = false;
    born_here = false;
    edge.lost();
  }

  // --- carrying out the EdgeSession's list ---------------------------------

  void send(std::vector<Outgoing>& out) {
    if (!client.connected() || !client.has_connection()) {
      for (const auto& o : out) {
        if (o.kind != Outgoing::Kind::Publish) continue;
        const auto t = type_of(o.topic, edge.topic_prefix());
        if (t == Type::NDATA || t == Type::DDATA) ++counters.dropped;
      }
      out.clear();
      return;
    }
    for (auto& o : out) {
      if (!client.has_connection()) break;  // the session ended inside this loop
      switch (o.kind) {
        case Outgoing::Kind::Subscribe: {
          const codec::Subscription sub[] = {{o.topic, o.qos, false}};
          if (auto r = session.subscribe(client.out(), sub); !r.ok())
            log.warn("sparkplug: cannot subscribe to '" + o.topic + "' (id not UTF-8?)");
          break;
        }
        case Outgoing::Kind::Publish: publish(o); break;
        case Outgoing::Kind::Disconnect:
          // The EdgeSession ended the session (Primary Host offline): the
          // DISCONNECT goes out, the connection closes once it drained (or
          // the broker closes it), and the client connects again.
          session.disconnect(client.out(), session.version() == codec::kMqtt5 ? mqtt::Session::kDisconnectWithWill : 0);
          closing = true;
          break;
      }
    }
    out.clear();
    if (client.has_connection()) client.flush();
  }

  void publish(const Outgoing& o) {
    const auto t = type_of(o.topic, edge.topic_prefix());
    const bool data = t == Type::NDATA || t == Type::DDATA;
    if (data && (rebirth_due || client.pending() > cfg.max_buffered)) {
      // Backpressure: the births that follow the drain carry these values.
      ++counters.dropped;
      if (!rebirth_due) log.warn("sparkplug: the broker does not keep up; dropping DATA until a rebirth");
      rebirth_due = true;
      return;
    }
    bool ok = false;
    if (o.qos > 0) {
      ok = session.publish_control(client.out(), o.topic, o.payload, o.retain);
    } else {
      ok = session.publish(client.out(), 0, o.topic, o.payload, 0, o.retain).ok();
    }
    if (!ok) {
      log.warn("sparkplug: cannot send to '" + o.topic + "' (over the broker's maximum packet size?)");
      if (data) ++counters.dropped;
      return;
    }
    ++counters.published;
    counters.bytes += o.payload.size();
    if (t) ++counters.published_by_type[static_cast<std::size_t>(*t)];
    if (t == Type::NBIRTH) {
      if (born_here) ++counters.rebirths;
      born_here = true;
    }
  }

  // --- mqtt::ClientEvents ---------------------------------------------------

  // Every byte reached the kernel (possibly from inside a flush()): what
  // closes the connection or writes again runs as a handler of its own.
  void on_drained(std::size_t, std::chrono::steady_clock::time_point) override {
    if (!closing && !rebirth_due) return;
    asio::post(io, [weak = weak_from_this(), gen = client.connection_id()] {
      auto self = weak.lock();
      if (!self || !self->client.has_connection() || self->client.connection_id() != gen) return;
      if (self->closing) {
        // Closes the connection and connects again with backoff.
        self->client.end_connection("session ended by the edge node");
        return;
      }
      if (self->rebirth_due && self->client.pending() == 0) {
        self->rebirth_due = false;
        self->log.info("sparkplug: the broker caught up; births again");
        self->edge.rebirth(self->scratch_out, self->now_ms());
        self->send(self->scratch_out);
      }
    });
  }

  // A new bdSeq for every CONNECT attempt, stored before it is sent (facts A.5).
  void on_connecting() override {
    auto params = edge.connect_params(now_ms());
    if (!params.store_note.empty()) log.warn("sparkplug: " + params.store_note);
    session.set_will(std::move(params.will_topic), std::move(params.will_payload));
    closing = false;
  }

  void on_up(const mqtt::BrokerLimits& limits) override {
    born_here = false;
    log.info("sparkplug: edge node " + cfg.session.group_id + "/" + cfg.session.edge_node_id + " connected to " +
             client.uri() + " with MQTT " + (limits.version == codec::kMqtt5 ? "5" : "3.1.1") + ", bdSeq " +
             std::to_string(edge.bd_seq().value_or(0)) +
             (cfg.session.primary_host_id.empty() ? std::string()
                                                  : ", waiting for Primary Host " + cfg.session.primary_host_id));
    edge.connected(scratch_out, now_ms());
    send(scratch_out);
  }

  // Refused, failed, lost or ended by end_connection(): the client retries.
  void on_down(mqtt::Down cause, const std::string& why) override {
    if (cause == mqtt::Down::Lost && !closing) log.warn("sparkplug: connection to " + client.uri() + " lost: " + why);
    went_down();
  }

  void on_publish(const codec::Publish& p) override {
    if (!client.running() || !client.connected()) return;
    const auto t = std::string_view(p.topic);
    const auto& prefix = edge.topic_prefix();
    if (t.starts_with(prefix) && (t.substr(prefix.size()).starts_with("NCMD/") ||
                                  t.substr(prefix.size()).starts_with("DCMD/")))
      ++counters.commands;
    auto cmd = edge.received(scratch_out, p.topic, p.payload, now_ms());
    send(scratch_out);
    if (!cmd) return;
    if (!cmd->refused.empty()) {
      std::string names;
      for (const auto& n : cmd->refused) names += (names.empty() ? "" : ", ") + n;
      log.warn("sparkplug: " + std::string(cmd->device.empty() ? "NCMD" : "DCMD for " + cmd->device) +
               ": unknown metrics or values that do not fit their type: " + names);
    }
    if (owner && owner->on_command && (!cmd->items.empty() || cmd->rebirth)) owner->on_command(std::move(*cmd));
  }

  void on_rejected(std::uint64_t, std::uint8_t reason) override {
    log.warn("sparkplug: broker refused a message, reason " + std::to_string(reason));
  }
  void on_subscribe_refused(std::uint8_t code) override {
    log.warn("sparkplug: broker refused a subscription (NCMD/DCMD/STATE), code " + std::to_string(code));
  }

  void stop(std::chrono::milliseconds timeout) {
    if (!client.running()) return;
    // NDEATH and DISCONNECT in one synchronous write (facts A.4.6); after
    // the edge node's own DISCONNECT the connection is just closed.
    auto ndeath = [this](std::string& out) {
      std::vector<Outgoing> list;
      edge.stop(list, now_ms());
      for (const auto& o : list) {
        if (o.kind == Outgoing::Kind::Publish) {
          session.publish_final(out, o.topic, o.payload, o.qos, o.retain);
          ++counters.published;
          counters.bytes += o.payload.size();
          if (auto t = type_of(o.topic, edge.topic_prefix()))
            ++counters.published_by_type[static_cast<std::size_t>(*t)];
        } else if (o.kind == Outgoing::Kind::Disconnect) {
          session.disconnect(out, session.version() == codec::kMqtt5 ? mqtt::Session::kDisconnectWithWill : 0);
        }
      }
    };
    std::function<void(std::string&)> last_words;
    if (!closing) last_words = ndeath;
    const auto farewell = client.stop(timeout, last_words);
    if (farewell == mqtt::Client::Farewell::NotSent)
      log.warn("sparkplug: disconnect did not complete; the broker sends the Will (NDEATH)");
    went_down();
  }
};

EdgeClient::EdgeClient(boost::asio::io_context& io, EdgeClientConfig cfg, Logger& log)
    : impl_(std::make_shared<Impl>(io, std::move(cfg), log)) {
  impl_->owner = this;
}

EdgeClient::~EdgeClient() {
  impl_->owner = nullptr;
  impl_->stop(std::chrono::seconds(1));
}

void EdgeClient::start() { impl_->start(); }
void EdgeClient::stop(std::chrono::milliseconds timeout) { impl_->stop(timeout); }
EdgeSession& EdgeClient::edge() { return impl_->edge; }
const EdgeSession& EdgeClient::edge() const { return impl_->edge; }
void EdgeClient::send(std::vector<Outgoing>& out) { impl_->send(out); }
std::uint64_t EdgeClient::now_ms() const { return impl_->now_ms(); }
bool EdgeClient::connected() const { return impl_->client.connected(); }
int EdgeClient::mqtt_version() const { return impl_->client.version(); }
std::string EdgeClient::broker() const { return impl_->client.connected() ? impl_->client.uri() : std::string(); }
EdgeClient::Counters EdgeClient::counters() const {
  Counters c = impl_->counters;
  c.connects = impl_->client.connects();
  c.reconnects = impl_->client.reconnects();
  return c;
}
const EdgeClientConfig& EdgeClient::config() const { return impl_->cfg; }

void register_metrics(metrics::Registry& r, const std::unique_ptr<EdgeClient>& client,
                      const std::vector<std::string>& brokers) {
  using metrics::Value;
  auto counter = [&client](auto f) {
    return [&client, f]() -> Value { return client ? Value(f(client->counters())) : Value(std::uint64_t{0}); };
  };
  r.gauge_fn("canopen_gateway_sparkplug_connected", "1 while the Sparkplug B edge node is connected to its broker.",
             {}, [&client] { return Value(client && client->connected()); });
  for (const auto& uri : brokers)
    r.gauge_fn("canopen_gateway_sparkplug_broker_connected",
               "1 for the broker of sparkplug.uri's list the edge node is connected to, 0 for the others.",
               {{"uri", uri}}, [&client, uri] { return Value(client && client->broker() == uri); });
  r.gauge_fn("canopen_gateway_sparkplug_online",
             "1 while the Sparkplug B edge node is born (NBIRTH and every DBIRTH sent on this connection).", {},
             [&client] { return Value(client && client->edge().state() == EdgeSession::State::Born); });
  r.gauge_fn("canopen_gateway_sparkplug_bdseq",
             "The bdSeq of the Sparkplug B edge node's latest CONNECT (its Will and NBIRTH); -1 before the first.",
             {}, [&client]() -> Value {
               const auto b = client ? client->edge().bd_seq() : std::nullopt;
               return b ? Value(std::int64_t{*b}) : Value(std::int64_t{-1});
             });
  static constexpr std::string_view msgs = "canopen_gateway_sparkplug_messages_published_total";
  static constexpr std::string_view msgs_help = "Sparkplug B messages published by the edge node, by message type.";
  for (std::size_t i = 0; i < EdgeClient::kTypes; ++i)
    r.counter_fn(msgs, msgs_help, {{"type", kTypeNames[i]}},
                 counter([i](const EdgeClient::Counters& c) { return c.published_by_type[i]; }));
  r.counter_fn("canopen_gateway_sparkplug_published_bytes_total",
               "Payload bytes of the Sparkplug B messages published.", {},
               counter([](const EdgeClient::Counters& c) { return c.bytes; }));
  r.counter_fn("canopen_gateway_sparkplug_rebirths_total",
               "Sparkplug B birth sequences repeated on a connection (NCMD rebirth, or after dropped DATA).", {},
               counter([](const EdgeClient::Counters& c) { return c.rebirths; }));
  r.counter_fn("canopen_gateway_sparkplug_commands_total", "Sparkplug B NCMD/DCMD messages received.", {},
               counter([](const EdgeClient::Counters& c) { return c.commands; }));
  r.counter_fn("canopen_gateway_sparkplug_dropped_total",
               "Sparkplug B NDATA/DDATA dropped: not connected, or the broker did not keep up.", {},
               counter([](const EdgeClient::Counters& c) { return c.dropped; }));
  r.counter_fn("canopen_gateway_sparkplug_reconnects_total", "Reconnections of the Sparkplug B edge node.", {},
               counter([](const EdgeClient::Counters& c) { return c.reconnects; }));
}

}  // namespace gateway::sparkplug
