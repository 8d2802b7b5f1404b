#include "mqtt/publisher.hpp"

#include <mqtt/async_client.h>

#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/json.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace gateway::mqtt {
namespace {

namespace asio = boost::asio;
namespace json = boost::json;

void* to_context(std::uint64_t v) { return reinterpret_cast<void*>(static_cast<std::uintptr_t>(v)); }
std::uint64_t from_context(void* p) { return static_cast<std::uint64_t>(reinterpret_cast<std::uintptr_t>(p)); }

// "Bearer abc" -> "abc"; a bare token stays as it is.
std::string_view strip_bearer(std::string_view v) {
  constexpr std::string_view kBearer = "Bearer ";
  if (v.size() >= kBearer.size() && std::equal(kBearer.begin(), kBearer.end(), v.begin(), [](char a, char b) {
        return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
      }))
    v.remove_prefix(kBearer.size());
  return v;
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (;;) {
    auto pos = s.find(sep, start);
    out.push_back(s.substr(start, pos == std::string_view::npos ? std::string_view::npos : pos - start));
    if (pos == std::string_view::npos) return out;
    start = pos + 1;
  }
}

template <class T>
bool parse_decimal(std::string_view s, T& out) {
  if (s.empty()) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size();
}

std::string problem(int status, std::string_view title, std::string_view detail) {
  json::object o;
  o["type"] = "about:blank";
  o["title"] = title;
  o["status"] = status;
  o["detail"] = detail;
  return json::serialize(o);
}

}  // namespace

std::string normalize_server_uri(const std::string& uri) {
  static constexpr std::pair<std::string_view, std::string_view> kSchemes[] = {
      {"tcp://", "tcp://"}, {"ssl://", "ssl://"}, {"mqtt://", "tcp://"}, {"mqtts://", "ssl://"}};
  for (auto [from, to] : kSchemes) {
    if (uri.rfind(from, 0) == 0) {
      std::string rest = uri.substr(from.size());
      if (rest.empty() || rest[0] == ':' || rest[0] == '/') throw std::invalid_argument("MQTT URI without host: " + uri);
      return std::string(to) + rest;
    }
  }
  throw std::invalid_argument("MQTT URI must start with tcp://, ssl://, mqtt:// or mqtts://: " + uri);
}

// Delivery results collected from Paho's threads: the first one after the
// io thread took the last batch posts one handler, which takes all that
// arrived by then (one post per batch of PUBACKs, not per message).
// Posting at once matters: waiting for a bigger batch keeps the window
// from being refilled, and with nothing to send the client's delayed TCP
// ACKs meet the broker's Nagle on PUBACKs (~40 ms stalls).
struct DeliveryInbox {
  struct Result {
    std::uint64_t context;
    bool ok;
    int reason;
  };
  std::mutex mutex;
  std::vector<Result> results;
  bool posted = false;  // a handler is posted and has not taken them yet
};

// Paho threads call these; they only post to the io thread, holding the
// Impl weakly so a late callback after destruction does nothing.
class PahoListener : public ::mqtt::iaction_listener {
 public:
  enum class Kind { Connect, Delivery };
  PahoListener(asio::io_context& io, std::weak_ptr<MqttPublisher::Impl> impl, Kind kind,
               std::shared_ptr<DeliveryInbox> inbox = {})
      : io_(io), impl_(std::move(impl)), kind_(kind), inbox_(std::move(inbox)) {}
  void on_success(const ::mqtt::token& tok) override;
  void on_failure(const ::mqtt::token& tok) override;

 private:
  void deliver(std::uint64_t context, bool ok, int reason);
  asio::io_context& io_;
  std::weak_ptr<MqttPublisher::Impl> impl_;
  Kind kind_;
  std::shared_ptr<DeliveryInbox> inbox_;
};

namespace {
// The publisher batches the queue's writes (see publisher.hpp, Delivery).
DiskQueueOptions buffered(DiskQueueOptions o) {
  o.buffered_writes = true;
  return o;
}
}  // namespace

struct MqttPublisher::Impl : std::enable_shared_from_this<MqttPublisher::Impl> {
  Impl(asio::io_context& io_ctx, MqttConfig c, Logger& l, RequestHandler h)
      : io(io_ctx), cfg(std::move(c)), log(l), handler(std::move(h)), queue(buffered(cfg.queue)),
        sync_timer(io_ctx), retry_timer(io_ctx), drain_timer(io_ctx) {
    uri = normalize_server_uri(cfg.server_uri);
    version = cfg.mqtt_version >= 5 ? 5 : 4;
    prefix = "canopen/" + cfg.gateway_id + "/";
    if (cfg.inflight_window == 0) cfg.inflight_window = 1;
  }

  asio::io_context& io;
  MqttConfig cfg;
  Logger& log;
  RequestHandler handler;
  DiskQueue queue;
  asio::steady_timer sync_timer;
  asio::steady_timer retry_timer;
  asio::steady_timer drain_timer;
  bool drain_retry_armed = false;
  static constexpr std::chrono::seconds kStallTimeout{30};
  std::chrono::steady_clock::time_point last_progress{};
  std::string uri;
  std::string prefix;
  int version = 5;
  // Listeners live as long as the Impl, longer than any client they serve.
  std::unique_ptr<PahoListener> connect_listener, delivery_listener;
  std::shared_ptr<DeliveryInbox> inbox = std::make_shared<DeliveryInbox>();
  std::vector<DeliveryInbox::Result> delivered;  // io thread's swap buffer
  bool pump_posted = false;
  std::size_t receive_max = 0;  // the broker's Receive Maximum (MQTT 5), 0: none
  // The in-flight window; under the broker's Receive Maximum, leaving room
  // for the status message and request replies.
  std::size_t window() const {
    if (receive_max == 0) return cfg.inflight_window;
    const std::size_t cap = receive_max > 8 ? receive_max - 4 : receive_max;
    return std::min(cap, cfg.inflight_window);
  }
  std::unique_ptr<::mqtt::async_client> client;
  bool running = false;
  bool connected = false;
  bool connecting = false;
  std::uint64_t attempt = 0;       // id of the current connect attempt
  unsigned failures = 0;           // consecutive, for the backoff
  // seq -> connection epoch it was sent on; a Paho context is
  // (seq << 16 | epoch) so a late callback for an earlier send of the same
  // seq does not retire the current one.
  std::unordered_map<std::uint64_t, std::uint16_t> in_flight;
  std::uint16_t epoch = 0;
  Counters counters;

  void make_client() {
    ::mqtt::create_options co(version == 5 ? MQTTVERSION_5 : MQTTVERSION_3_1_1);
    co.set_send_while_disconnected(false);
    // The DiskQueue is the buffer; Paho's limit also counts commands queued
    // while connected, so it must hold the window plus status and replies.
    co.set_max_buffered_messages(static_cast<int>(cfg.inflight_window + 64));
    client = std::make_unique<::mqtt::async_client>(uri, cfg.client_id, co, nullptr);  // no persistence
    std::weak_ptr<Impl> weak = weak_from_this();
    asio::io_context* ioc = &io;
    client->set_connection_lost_handler([weak, ioc](const std::string&) {
      asio::post(*ioc, [weak] {
        if (auto self = weak.lock()) self->on_lost("connection lost");
      });
    });
    client->set_disconnected_handler([weak, ioc](const ::mqtt::properties&, ::mqtt::ReasonCode rc) {
      asio::post(*ioc, [weak, rc] {
        if (auto self = weak.lock()) self->on_lost("broker disconnected, reason " + std::to_string(static_cast<int>(rc)));
      });
    });
    client->set_message_callback([weak, ioc](::mqtt::const_message_ptr msg) {
      asio::post(*ioc, [weak, msg = std::move(msg)] {
        if (auto self = weak.lock()) self->on_request(*msg);
      });
    });
  }

  ::mqtt::connect_options connect_options() const {
    ::mqtt::connect_options o;
    o.set_mqtt_version(version == 5 ? MQTTVERSION_5 : MQTTVERSION_3_1_1);
    if (version == 5)
      o.set_clean_start(true);
    else
      o.set_clean_session(true);
    o.set_keep_alive_interval(cfg.keepalive);
    o.set_connect_timeout(cfg.connect_timeout);
    o.set_automatic_reconnect(false);  // ours, so the queue drives resends
    o.set_max_inflight(static_cast<int>(cfg.inflight_window + 16));
    if (!cfg.username.empty()) o.set_user_name(cfg.username);
    if (!cfg.password.empty()) o.set_password(cfg.password);
    o.set_will(::mqtt::will_options(status_topic(), cfg.offline_payload, 1, true));
    if (uri.rfind("ssl://", 0) == 0) {
      ::mqtt::ssl_options ssl;
      if (!cfg.ca_file.empty()) ssl.set_trust_store(cfg.ca_file);
      if (!cfg.cert_file.empty()) ssl.set_key_store(cfg.cert_file);
      if (!cfg.key_file.empty()) ssl.set_private_key(cfg.key_file);
      if (!cfg.key_password.empty()) ssl.set_private_key_password(cfg.key_password);
      ssl.set_enable_server_cert_auth(cfg.verify_server);
      ssl.set_verify(cfg.verify_server);
      o.set_ssl(std::move(ssl));
    }
    return o;
  }

  std::string status_topic() const { return prefix + "status"; }

  void start() {
    if (running) return;
    running = true;
    std::weak_ptr<Impl> weak = weak_from_this();
    connect_listener = std::make_unique<PahoListener>(io, weak, PahoListener::Kind::Connect);
    delivery_listener = std::make_unique<PahoListener>(io, weak, PahoListener::Kind::Delivery, inbox);
    make_client();
    arm_sync();
    connect();
  }

  // Every sync_interval (or 1 s without syncing): fdatasync the queue, and
  // unstick delivery if Paho lost track of a message (no token pending yet
  // messages handed out, or no PUBACK for stall_timeout): resend from the
  // oldest unacked, as after a reconnect.
  void arm_sync() {
    const auto period = cfg.sync_interval.count() > 0 ? cfg.sync_interval : std::chrono::milliseconds(1000);
    sync_timer.expires_after(period);
    sync_timer.async_wait([weak = weak_from_this()](const boost::system::error_code& ec) {
      auto self = weak.lock();
      if (ec || !self || !self->running) return;
      self->flush_queue(true);  // records and the ack position
      if (self->cfg.sync_interval.count() > 0) self->queue.sync();
      self->check_stall();
      self->arm_sync();
    });
  }

  void check_stall() {
    if (!connected || drain_retry_armed) return;
    const auto now = std::chrono::steady_clock::now();
    const bool idle_but_pending = in_flight.empty() && queue.depth() > 0;
    const bool no_progress = !in_flight.empty() && now - last_progress > kStallTimeout;
    if (!idle_but_pending && !no_progress) return;
    log.warn("mqtt: delivery stalled with " + std::to_string(in_flight.size()) + " in flight; resending from " +
             std::to_string(queue.head_seq()));
    in_flight.clear();
    ++epoch;
    last_progress = now;
    queue.rewind();
    drain();
  }

  void connect() {
    if (!running || connected || connecting) return;
    connecting = true;
    ++attempt;
    try {
      client->connect(connect_options(), to_context(attempt), *connect_listener);
    } catch (const std::exception& e) {
      connecting = false;
      log.warn(std::string("mqtt: connect to ") + uri + " failed: " + e.what());
      schedule_retry();
    }
  }

  void schedule_retry() {
    if (!running) return;
    auto delay = cfg.reconnect_min;
    for (unsigned i = 0; i < failures && delay < cfg.reconnect_max; ++i) delay *= 2;
    if (delay > cfg.reconnect_max) delay = cfg.reconnect_max;
    ++failures;
    retry_timer.expires_after(delay);
    retry_timer.async_wait([weak = weak_from_this()](const boost::system::error_code& ec) {
      auto self = weak.lock();
      if (ec || !self) return;
      self->connect();
    });
  }

  void on_connect_result(std::uint64_t id, bool ok, int rc, int reason) {
    if (id != attempt || !connecting) return;  // a stale attempt
    connecting = false;
    if (!running) return;
    if (!ok) {
      // The broker refuses MQTT 5: v5 reason 0x84, or a 3.1.1 broker's
      // CONNACK code 1 (unacceptable protocol version).
      if (version == 5 && cfg.mqtt_version >= 5 && (reason == 0x84 || rc == 1 || rc == 0x84)) {
        log.warn("mqtt: broker " + uri + " refuses MQTT 5, falling back to 3.1.1");
        version = 4;
        make_client();
        connect();
        return;
      }
      if (failures == 0 || log.enabled(LogLevel::Debug))
        log.warn("mqtt: connect to " + uri + " failed (rc " + std::to_string(rc) + ", reason " +
                 std::to_string(reason) + "), retrying");
      schedule_retry();
      return;
    }
    connected = true;
    failures = 0;
    if (counters.connects++ > 0) ++counters.reconnects;
    log.info("mqtt: connected to " + uri + " with MQTT " + (version == 5 ? "5" : "3.1.1") +
             (receive_max > 0 ? ", receive maximum " + std::to_string(receive_max) : std::string()));
    try {
      auto online = ::mqtt::make_message(status_topic(), cfg.online_payload, 1, true);
      client->publish(online);
      if (cfg.accept_requests) {
        for (const char* suffix : {"/+/+/sdo/read", "/+/+/sdo/write", "/+/+/nmt"}) {
          std::string filter = "canopen/" + cfg.gateway_id + suffix;
          if (version == 5)
            client->subscribe(filter, 1, ::mqtt::subscribe_options(true));  // no local: no echo of replies
          else
            client->subscribe(filter, 1);
        }
      }
    } catch (const std::exception& e) {
      log.warn(std::string("mqtt: after connect: ") + e.what());
    }
    queue.rewind();
    in_flight.clear();
    ++epoch;
    last_progress = std::chrono::steady_clock::now();
    if (log.enabled(LogLevel::Debug))
      log.debug("mqtt: sending from " + std::to_string(queue.head_seq()) + ", " + std::to_string(queue.depth()) +
                " queued");
    drain();
  }

  void on_lost(const std::string& why) {
    if (!connected) return;
    connected = false;
    ++epoch;
    in_flight.clear();
    queue.rewind();  // resend everything unacked, in order, after reconnect
    log.warn("mqtt: " + why + "; " + std::to_string(queue.depth()) + " messages queued");
    if (running) schedule_retry();
  }

  void drain() {
    // Whoever drains (pump, delivery batch, reconnect, retry): what is sent
    // is written to the queue's files first.
    if (connected && queue.flush_pending()) flush_queue();
    DiskQueue::Item item;
    const std::size_t limit = window();
    while (connected && in_flight.size() < limit && queue.next(item)) {
      auto msg = ::mqtt::make_message(item.msg.topic, item.msg.payload, item.msg.qos == 0 ? 0 : 1, item.msg.retained);
      try {
        client->publish(msg, to_context(item.seq << 16 | epoch), *delivery_listener);
        in_flight[item.seq] = epoch;
        ++counters.sent;
      } catch (const ::mqtt::exception& e) {
        const int rc = e.get_return_code();
        if (rc == MQTTASYNC_DISCONNECTED) {
          // The loss callback follows; it rewinds.
          on_lost("publish while disconnected");
          return;
        }
        if (rc == MQTTASYNC_MAX_BUFFERED_MESSAGES || rc == MQTTASYNC_MAX_MESSAGES_INFLIGHT ||
            rc == MQTTASYNC_NO_MORE_MSGIDS) {
          // Paho is full for now: hand this one out again later.
          queue.rewind_to(item.seq);
          arm_drain_retry();
          return;
        }
        if (rc == MQTTASYNC_BAD_UTF8_STRING || rc == MQTTASYNC_NULL_PARAMETER || rc == MQTTASYNC_TOPICNAME_TRUNCATED ||
            rc == MQTTASYNC_BAD_STRUCTURE || rc == MQTTASYNC_BAD_QOS) {
          // Paho refuses this very message (bad topic ...): drop it rather
          // than block the queue forever.
          ++counters.rejected;
          queue.ack(item.seq);
          log.warn("mqtt: dropping message to '" + item.msg.topic + "': " + e.what());
          continue;
        }
        // Anything else is the connection's state (e.g. going down while the
        // broker stops), not the message's: keep it and try again later, so
        // nothing accepted is ever dropped for it.
        queue.rewind_to(item.seq);
        arm_drain_retry();
        if (log.enabled(LogLevel::Debug)) log.debug(std::string("mqtt: publish refused for now: ") + e.what());
        return;
      }
    }
  }

  void arm_drain_retry() {
    if (drain_retry_armed) return;
    drain_retry_armed = true;
    drain_timer.expires_after(std::chrono::milliseconds(10));
    drain_timer.async_wait([weak = weak_from_this()](const boost::system::error_code& ec) {
      auto self = weak.lock();
      if (ec || !self) return;
      self->drain_retry_armed = false;
      self->drain();
    });
  }

  // All delivery results that arrived since the last batch, then one drain
  // for all of them (the ack position goes to disk on the sync tick).
  void on_deliveries() {
    delivered.clear();
    {
      std::lock_guard<std::mutex> lock(inbox->mutex);
      delivered.swap(inbox->results);
      inbox->posted = false;
    }
    for (const auto& r : delivered) on_delivery(r.context, r.ok, r.reason);
    drain();
  }

  // Once per io loop turn (posted by the first publish after the last
  // one): write the records the queue buffered, then hand them to Paho. So
  // a message is in the kernel before it is sent, and Paho gets the turn's
  // messages in one burst (its send thread wakes once, not per message).
  void schedule_pump() {
    if (pump_posted) return;
    pump_posted = true;
    asio::post(io, [weak = weak_from_this()] {
      if (auto self = weak.lock()) {
        self->pump_posted = false;
        self->flush_queue();
        self->drain();
      }
    });
  }

  void flush_queue(bool with_position = false) {
    try {
      queue.flush(with_position);
    } catch (const std::exception& e) {
      // Kept in memory and retried (next publish, ack or sync tick).
      log.error(std::string("mqtt: queue write failed: ") + e.what());
    }
  }

  // One result; the caller (on_deliveries) drains after the batch.
  void on_delivery(std::uint64_t context, bool ok, int reason) {
    const std::uint64_t seq = context >> 16;
    const auto sent_epoch = static_cast<std::uint16_t>(context & 0xffff);
    if (auto it = in_flight.find(seq); it != in_flight.end() && it->second == sent_epoch) in_flight.erase(it);
    else if (!ok) return;  // a failure from an earlier connection: already rewound
    last_progress = std::chrono::steady_clock::now();
    if (ok) {
      // A late ack from an earlier connection is still a real ack.
      if (queue.ack(seq)) ++counters.acked;
    } else if (reason >= 0x80 && connected) {
      // MQTT 5 PUBACK refusal (not authorized, topic invalid ...): resending
      // would only repeat it.
      ++counters.rejected;
      queue.ack(seq);
      log.warn("mqtt: broker refused a message, reason " + std::to_string(reason));
    }
    // Other failures come with a connection loss: resent after reconnect.
    if (!ok && log.enabled(LogLevel::Debug))
      log.debug("mqtt: delivery of " + std::to_string(seq) + " failed, reason " + std::to_string(reason) +
                (connected ? " (connected)" : ""));
  }

  void publish(const QueuedMessage& m) {
    ++counters.published;
    try {
      queue.push(m);
    } catch (const std::exception& e) {
      ++counters.dropped;
      log.error(std::string("mqtt: queue write failed: ") + e.what());
      return;
    }
    schedule_pump();
  }

  // --- requests ---------------------------------------------------------

  struct ReplyAddress {
    std::string topic;
    std::string correlation;           // MQTT 5 correlation data
    std::optional<json::value> corr_id;  // 3.1.1 correlationId
    bool v5 = false;
  };

  bool is_request_topic(std::string_view t) const {
    if (t.rfind(prefix, 0) != 0) return false;
    auto parts = split(t.substr(prefix.size()), '/');
    return (parts.size() == 4 && parts[2] == "sdo" && (parts[3] == "read" || parts[3] == "write")) ||
           (parts.size() == 3 && parts[2] == "nmt");
  }

  static bool valid_reply_topic(std::string_view t) {
    return !t.empty() && t.find_first_of("+#") == std::string_view::npos && t.size() < 65535;
  }

  void on_request(const ::mqtt::message& msg) {
    if (!running) return;
    ++counters.requests;
    const std::string& topic = msg.get_topic();
    ApiRequest req;
    ReplyAddress addr;
    req.body = msg.get_payload_str();
    const auto& props = msg.get_properties();
    try {
      if (props.contains(::mqtt::property::RESPONSE_TOPIC)) {
        addr.topic = ::mqtt::get<std::string>(props, ::mqtt::property::RESPONSE_TOPIC);
        addr.v5 = true;
        if (props.contains(::mqtt::property::CORRELATION_DATA))
          addr.correlation = ::mqtt::get<std::string>(props, ::mqtt::property::CORRELATION_DATA);
      }
      // MQTT 5 user property "authorization": "Bearer <token>" (or the token).
      const auto n_user = props.count(::mqtt::property::USER_PROPERTY);
      for (std::size_t i = 0; i < n_user; ++i) {
        auto [name, value] = ::mqtt::get<::mqtt::string_pair>(props, ::mqtt::property::USER_PROPERTY, i);
        if (name == "authorization") req.token = std::string(strip_bearer(value));
      }
      if (props.contains(::mqtt::property::CONTENT_TYPE) &&
          ::mqtt::get<std::string>(props, ::mqtt::property::CONTENT_TYPE) == "application/x-protobuf")
        req.protobuf = true;
    } catch (const std::exception&) {
      // Malformed properties: treated as absent.
    }
    if (!req.protobuf) {
      // replyTo/correlationId in a JSON body (3.1.1; allowed over 5 too).
      boost::system::error_code ec;
      json::value v = json::parse(req.body, ec);
      if (!ec && v.is_object()) {
        auto& o = v.as_object();
        bool changed = false;
        if (auto* r = o.if_contains("replyTo")) {
          if (r->is_string() && addr.topic.empty()) addr.topic = std::string(r->as_string());
          o.erase("replyTo");
          changed = true;
        }
        if (auto* c = o.if_contains("correlationId")) {
          if (!addr.v5) addr.corr_id = *c;
          o.erase("correlationId");
          changed = true;
        }
        if (auto* t = o.if_contains("token")) {
          if (t->is_string() && req.token.empty()) req.token = std::string(strip_bearer(t->as_string()));
          o.erase("token");
          changed = true;
        }
        if (changed) req.body = json::serialize(o);
      }
    }
    if (!addr.topic.empty() && (!valid_reply_topic(addr.topic) || is_request_topic(addr.topic))) {
      ++counters.bad_requests;
      log.warn("mqtt: request on " + topic + ": refused reply topic '" + addr.topic + "'");
      addr.topic.clear();
    }

    // canopen/<gw>/<net>/<node>/sdo/read|write or canopen/<gw>/<net>/<node>/nmt
    std::string error;
    if (topic.rfind(prefix, 0) != 0) {
      error = "not this gateway's request topic";
    } else {
      auto parts = split(std::string_view(topic).substr(prefix.size()), '/');
      unsigned node = 0;
      if (parts.size() == 4 && parts[2] == "sdo" && parts[3] == "read") {
        req.kind = RequestKind::SdoRead;
      } else if (parts.size() == 4 && parts[2] == "sdo" && parts[3] == "write") {
        req.kind = RequestKind::SdoWrite;
      } else if (parts.size() == 3 && parts[2] == "nmt") {
        req.kind = RequestKind::Nmt;
      } else {
        error = "unknown request topic";
      }
      if (error.empty() && (!parse_decimal(parts[0], req.network) || req.network == 0))
        error = "network must be a number from 1";
      else if (error.empty() && (!parse_decimal(parts[1], node) || node > 127 ||
                                 (node == 0 && req.kind != RequestKind::Nmt)))
        error = "node must be 1..127 (0 = all nodes, NMT only)";
      req.node = static_cast<std::uint8_t>(node);
    }
    if (error.empty() && !handler) error = "requests are not served";

    auto reply_fn = make_reply_fn(std::move(addr), topic);
    if (!error.empty()) {
      ++counters.bad_requests;
      log.warn("mqtt: request on " + topic + ": " + error);
      reply_fn(ApiReply{400, problem(400, "Bad Request", error), "application/problem+json"});
      return;
    }
    handler(req, std::move(reply_fn));
  }

  ReplyFn make_reply_fn(ReplyAddress addr, std::string request_topic) {
    auto done = std::make_shared<bool>(false);
    return [weak = weak_from_this(), addr = std::move(addr), request_topic = std::move(request_topic),
            done](ApiReply r) {
      if (*done) return;  // exactly once, whatever the handler does
      *done = true;
      if (auto self = weak.lock()) self->send_reply(addr, request_topic, std::move(r));
    };
  }

  void send_reply(const ReplyAddress& addr, const std::string& request_topic, ApiReply r) {
    if (addr.topic.empty()) {
      log.info("mqtt: request on " + request_topic + " without reply address: status " + std::to_string(r.status));
      return;
    }
    if (!connected || !client) {
      ++counters.replies_dropped;
      log.warn("mqtt: reply to " + addr.topic + " dropped: not connected");
      return;
    }
    std::string body = std::move(r.body);
    if (addr.corr_id) {
      boost::system::error_code ec;
      json::value v = json::parse(body, ec);
      if (!ec && v.is_object()) {
        v.as_object()["correlationId"] = *addr.corr_id;
        body = json::serialize(v);
      }
    }
    auto msg = ::mqtt::make_message(addr.topic, body, 1, false);
    if (version == 5) {
      ::mqtt::properties p;
      if (!addr.correlation.empty()) p.add(::mqtt::property(::mqtt::property::CORRELATION_DATA, addr.correlation));
      p.add(::mqtt::property(::mqtt::property::USER_PROPERTY, "status", std::to_string(r.status)));
      p.add(::mqtt::property(::mqtt::property::CONTENT_TYPE, r.content_type));
      msg->set_properties(p);
    }
    try {
      client->publish(msg);
      ++counters.replies;
    } catch (const std::exception& e) {
      ++counters.replies_dropped;
      log.warn("mqtt: reply to " + addr.topic + " failed: " + e.what());
    }
  }

  void stop(std::chrono::milliseconds timeout) {
    if (!running) return;
    running = false;
    sync_timer.cancel();
    retry_timer.cancel();
    drain_timer.cancel();
    if (client && connected) {
      try {
        auto half = timeout / 2;
        auto tok = client->publish(::mqtt::make_message(status_topic(), cfg.offline_payload, 1, true));
        tok->wait_for(half);
        client->disconnect(static_cast<int>(half.count()))->wait_for(half);
      } catch (const std::exception& e) {
        log.warn(std::string("mqtt: disconnect: ") + e.what());
      }
    }
    connected = false;
    connecting = false;
    flush_queue(true);
    queue.sync();
  }

  Counters snapshot() const {
    Counters c = counters;
    const auto& q = queue.counters();
    c.dropped += q.dropped() + c.rejected;
    c.queue_depth = queue.depth();
    c.queue_bytes = q.bytes;
    c.in_flight = in_flight.size();
    c.connected = connected;
    c.mqtt_version = connected ? version : 0;
    return c;
  }
};

void PahoListener::on_success(const ::mqtt::token& tok) {
  const std::uint64_t id = from_context(tok.get_user_context());
  if (kind_ == Kind::Connect) {
    // MQTT 5: the broker's Receive Maximum (CONNACK; mosquitto's
    // max_inflight_messages, 20 by default) caps the QoS 1 messages in
    // flight. Paho holds back more than that, so the window must not exceed
    // it (or sending stalls).
    std::size_t receive_max = 0;
    try {
      const auto props = tok.get_connect_response().get_properties();
      if (props.contains(::mqtt::property::RECEIVE_MAXIMUM))
        receive_max = static_cast<std::size_t>(::mqtt::get<int>(props, ::mqtt::property::RECEIVE_MAXIMUM));
    } catch (const std::exception&) {
      // No connect response (3.1.1) or no such property: no cap.
    }
    asio::post(io_, [w = impl_, id, receive_max] {
      if (auto self = w.lock()) {
        self->receive_max = receive_max;
        self->on_connect_result(id, true, 0, 0);
      }
    });
  } else {
    deliver(id, true, 0);
  }
}

void PahoListener::deliver(std::uint64_t context, bool ok, int reason) {
  bool post = false;
  {
    std::lock_guard<std::mutex> lock(inbox_->mutex);
    inbox_->results.push_back({context, ok, reason});
    if (!inbox_->posted) post = inbox_->posted = true;
  }
  if (post) {
    asio::post(io_, [w = impl_] {
      if (auto self = w.lock()) self->on_deliveries();
    });
  }
}

void PahoListener::on_failure(const ::mqtt::token& tok) {
  const std::uint64_t id = from_context(tok.get_user_context());
  const int rc = tok.get_return_code();
  const int reason = static_cast<int>(tok.get_reason_code());
  if (kind_ == Kind::Connect) {
    asio::post(io_, [w = impl_, id, rc, reason] {
      if (auto self = w.lock()) self->on_connect_result(id, false, rc, reason);
    });
  } else {
    deliver(id, false, reason);
  }
}

MqttPublisher::MqttPublisher(asio::io_context& io, MqttConfig cfg, Logger& log, RequestHandler handler)
    : impl_(std::make_shared<Impl>(io, std::move(cfg), log, std::move(handler))) {}

MqttPublisher::~MqttPublisher() { impl_->stop(std::chrono::seconds(1)); }

void MqttPublisher::start() { impl_->start(); }
void MqttPublisher::stop(std::chrono::milliseconds timeout) { impl_->stop(timeout); }

void MqttPublisher::publish(const EncodedEventPtr& ev) { publish(ev, impl_->cfg.format); }

void MqttPublisher::publish(const EncodedEventPtr& ev, PayloadFormat format) {
  if (!ev) return;
  const auto k = static_cast<std::size_t>(ev->kind);
  QueuedMessage m;
  m.topic = ev->topic;
  m.payload = format == PayloadFormat::Json ? ev->json : ev->binary;
  m.qos = k < kEventKindCount ? impl_->cfg.qos[k] : 1;
  m.retained = ev->retained;
  impl_->publish(m);
}

void MqttPublisher::publish(const QueuedMessage& m) { impl_->publish(m); }

MqttPublisher::Counters MqttPublisher::counters() const { return impl_->snapshot(); }
const DiskQueue::Counters& MqttPublisher::queue_counters() const { return impl_->queue.counters(); }
std::string MqttPublisher::status_topic() const { return impl_->status_topic(); }

}  // namespace gateway::mqtt
