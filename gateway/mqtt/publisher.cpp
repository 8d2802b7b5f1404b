#include "mqtt/publisher.hpp"

#include "messages/event_encoder.hpp"

#include "mqtt/client.hpp"
#include "mqtt/mqtt_codec.hpp"
#include "mqtt/session.hpp"
#include "mqtt/stall_detector.hpp"
#include "mqtt/topic_filter.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

namespace gateway::mqtt {
namespace {

namespace asio = boost::asio;

}  // namespace

namespace {
// The publisher batches the queue's writes (see publisher.hpp, Delivery).
OutboundQueueOptions queue_options(const MqttConfig& c) {
  OutboundQueueOptions o;
  o.disk = c.queue;
  o.disk.buffered_writes = true;
  o.memory_max_bytes = c.memory_max_bytes;
  o.memory_max_messages = c.memory_max_messages;
  return o;
}

// Largest packet the publisher accepts from the broker (told to it under
// MQTT 5 as Maximum Packet Size); requests are small.
constexpr std::size_t kMaxIncomingPacket = 4u << 20;
// Receive Maximum told to the broker: requests it may have unacked with us.
constexpr std::uint16_t kOurReceiveMaximum = 64;
// Stop encoding once this much waits for the socket (QoS 0 is not bounded
// by the window); drain() resumes when it has gone out.
constexpr std::size_t kMaxBuffered = 256u << 10;

// The native session: the status Will (retained, QoS 1), the in-flight
// window of the configuration, requests as the only incoming traffic.
Client::Options client_options(const MqttConfig& c) {
  Client::Options o;
  o.session = Client::common_session_options(c);
  o.session.will_topic = gateway::status_topic(c.gateway_id);
  o.session.will_payload = c.offline_payload;
  o.session.inflight_window = c.inflight_window;
  o.session.receive_maximum = kOurReceiveMaximum;
  o.session.maximum_packet_size = static_cast<std::uint32_t>(kMaxIncomingPacket);
  o.log_prefix = "mqtt";
  o.connect_error_hint = "client id, user, will";
  return o;
}
}  // namespace

// The queue, its storage, stalls and requests over the MQTT client
// (client.hpp: connection, TLS, session, timers, reconnect backoff).
struct MqttPublisher::Impl : std::enable_shared_from_this<MqttPublisher::Impl>, ClientEvents {
  Impl(asio::io_context& io_ctx, MqttConfig c, Logger& l, RequestSink h)
      : io(io_ctx), cfg(std::move(c)), log(l), on_request(std::move(h)), queue(queue_options(cfg)),
        queue_warned(log_queue_warnings()), sync_timer(io_ctx), client(io_ctx, cfg, client_options(cfg), *this, l),
        session(client.session()) {}

  // The queue's open warnings go out before the client checks the URI.
  bool log_queue_warnings() {
    for (const auto& w : queue.disk().take_warnings()) log.warn("mqtt: queue: " + w);
    return true;
  }

  asio::io_context& io;
  MqttConfig cfg;
  Logger& log;
  RequestSink on_request;  // the request front end (mqtt_requests/)
  OutboundQueue queue;
  bool queue_warned;
  asio::steady_timer sync_timer;
  StallDetector stall;
  std::error_code storage_error;            // as last logged
  std::uint64_t dropped_at_storage_error = 0;
  Client client;
  Session& session;          // the client's
  bool buffer_full = false;  // drain() stopped at kMaxBuffered
  bool pump_posted = false;
  bool draining = false;     // inside drain(): on_drained must not re-enter it
  OutboundQueue::Item item;  // reused by drain()
  Counters counters;
  // The latest retained message per topic (status of buses, node states):
  // a broker restarted without persistence has lost them, so each one the
  // broker had is published again on every new connection (issue 27 item
  // 3). One still queued is sent from the queue, in order, instead.
  struct Retained {
    std::string payload;
    std::uint8_t qos = 0;
    StorageMode mode = StorageMode::Memory;
    std::uint64_t seq = 0;   // its place in the queue while not delivered
    bool delivered = false;  // acked (QoS 1) or written (QoS 0)
  };
  std::unordered_map<std::string, Retained> retained_topics;
  std::unordered_map<std::uint64_t, std::string> retained_in_queue;  // seq -> topic

  // Queues the latest retained messages the broker had had once more.
  void republish_retained() {
    std::size_t n = 0;
    for (auto& [topic, r] : retained_topics) {
      if (!r.delivered) continue;
      const std::uint64_t seq = queue.push(topic, r.payload, r.qos, true, r.mode);
      if (seq == 0) continue;  // dropped by the queue (counted there)
      r.seq = seq;
      r.delivered = false;
      retained_in_queue.emplace(seq, topic);
      ++n;
    }
    if (n > 0) log.info("mqtt: publishing the " + std::to_string(n) + " retained topics again on the new connection");
  }

  std::string status_topic() const { return gateway::status_topic(cfg.gateway_id); }

  void start() {
    if (client.running()) return;
    arm_sync();
    client.start(weak_from_this());
  }

  // Every sync_interval (or 1 s without syncing): write what the queue
  // buffered and its position, fdatasync what is durable and not yet synced
  // (nothing at all while only `outage`/`memory` messages flow), log a
  // storage failure or its end (once per episode), and unstick delivery if
  // the StallDetector says it stopped: resend from the oldest unacked, as
  // after a reconnect.
  void arm_sync() {
    const auto period = cfg.sync_interval.count() > 0 ? cfg.sync_interval : std::chrono::milliseconds(1000);
    sync_timer.expires_after(period);
    sync_timer.async_wait([weak = weak_from_this()](const boost::system::error_code& ec) {
      auto self = weak.lock();
      if (ec || !self || !self->client.running()) return;
      if (self->cfg.sync_interval.count() > 0)
        self->queue.disk().sync();  // flushes records and the position first
      else
        self->queue.disk().flush(true);
      self->check_storage();
      self->check_backpressure();
      self->check_stall();
      self->arm_sync();
    });
  }

  std::size_t in_flight() const { return session.in_flight(); }

  void check_storage() {
    const std::error_code now = queue.disk().storage_error();
    if (now == storage_error) return;
    const std::uint64_t dropped = queue.dropped();
    if (now && !storage_error) {
      log.error("mqtt: queue storage in " + cfg.queue.dir.string() + " failing (" + now.message() +
                "): queued messages are kept and sent, new ones that cannot be stored are dropped; retrying");
      dropped_at_storage_error = dropped;
    } else if (!now) {
      log.warn("mqtt: queue storage writable again; " + std::to_string(dropped - dropped_at_storage_error) +
               " messages dropped meanwhile");
    }
    storage_error = now;
  }

  // QoS 0 messages dropped under backpressure (OutboundQueue): logged once
  // when an episode begins and once when it has been over for 10 s.
  std::uint64_t backpressure_seen = 0, backpressure_at_start = 0;
  std::optional<std::chrono::steady_clock::time_point> backpressure_since;  // last drop of the episode
  void check_backpressure() {
    const std::uint64_t n = queue.counters().dropped_backpressure;
    const auto now = std::chrono::steady_clock::now();
    if (n != backpressure_seen) {
      if (!backpressure_since) {
        backpressure_at_start = backpressure_seen;
        log.warn("mqtt: the broker takes messages slower than the buses produce them: dropping the oldest QoS 0 "
                 "messages in memory, never writing them to storage (canopen_gateway_mqtt_dropped_total"
                 "{reason=\"backpressure\"})");
      }
      backpressure_seen = n;
      backpressure_since = now;
    } else if (backpressure_since && now - *backpressure_since > std::chrono::seconds(10)) {
      log.info("mqtt: the broker keeps up again; " + std::to_string(n - backpressure_at_start) +
               " QoS 0 messages were dropped meanwhile");
      backpressure_since.reset();
    }
  }

  void check_stall() {
    if (!client.connected()) return;
    const auto now = std::chrono::steady_clock::now();
    StallDetector::Observation o;
    o.in_flight = in_flight();
    o.unsent = o.in_flight == 0 && queue.depth() > 0 && queue.has_unsent();
    o.send_scheduled = pump_posted || buffer_full || client.pending() > 0;
    const auto verdict = stall.check(now, o);
    if (verdict == StallDetector::Verdict::Ok) return;
    ++counters.stalls;
    log.warn(std::string("mqtt: delivery stalled (") +
             (verdict == StallDetector::Verdict::NoProgress ? "no acknowledgement for 30 s" : "nothing sent for 5 s") +
             ") with " + std::to_string(in_flight()) + " in flight; resending from " +
             std::to_string(queue.disk().head_seq()));
    session.restart_window();
    queue.rewind();
    drain();
  }

  // --- ClientEvents -------------------------------------------------------

  // The connection is over after CONNACK (the session has forgotten what
  // was in flight); the client reconnects.
  void on_down(Down cause, const std::string& why) override {
    if (cause != Down::Lost) return;
    queue.rewind();           // resend everything unacked, in order, after reconnect
    queue.set_online(false);  // `outage` messages in memory go to disk
    log.warn("mqtt: " + why + "; " + std::to_string(queue.depth()) + " messages queued");
  }

  void on_up(const BrokerLimits& limits) override {
    log.info("mqtt: connected to " + client.uri() + " with MQTT " + (limits.version == codec::kMqtt5 ? "5" : "3.1.1") +
             (limits.receive_maximum > 0 ? ", receive maximum " + std::to_string(limits.receive_maximum)
                                         : std::string()));
    queue.set_online(true);
    republish_retained();
    // The online status before the backlog, then the request subscriptions.
    send_control(status_topic(), cfg.online_payload, true, nullptr);
    if (cfg.accept_requests) {
      const auto filters = request_filters(cfg.gateway_id);
      // MQTT 5: no local, so the gateway's own replies are not echoed.
      const codec::Subscription subs[] = {{filters[0], 1, true}, {filters[1], 1, true}, {filters[2], 1, true}};
      if (auto r = session.subscribe(client.out(), subs); r.error != codec::Error::None)
        log.warn("mqtt: request topics cannot be subscribed (gateway id not UTF-8?)");
    }
    queue.rewind();
    stall.reset(std::chrono::steady_clock::now());
    if (log.enabled(LogLevel::Debug))
      log.debug("mqtt: sending from " + std::to_string(queue.disk().head_seq()) + ", " +
                std::to_string(queue.depth()) + " queued");
    drain();
    if (client.has_connection()) client.flush();  // status and SUBSCRIBE when the queue is empty
  }

  // A QoS 1 PUBLISH outside the queue (status, replies). False when it
  // could not be encoded.
  bool send_control(std::string_view topic, std::string_view payload, bool retain,
                    const codec::PublishProperties* props) {
    if (!client.has_connection()) return false;
    return session.publish_control(client.out(), topic, payload, retain, props);
  }

  void on_acked(std::uint64_t seq) override {
    if (queue.ack(seq)) ++counters.acked;
    if (!retained_in_queue.empty()) delivered(seq);
  }

  void delivered(std::uint64_t seq) {
    const auto it = retained_in_queue.find(seq);
    if (it == retained_in_queue.end()) return;
    if (auto r = retained_topics.find(it->second); r != retained_topics.end() && r->second.seq == seq)
      r->second.delivered = true;
    retained_in_queue.erase(it);
  }

  void on_rejected(std::uint64_t seq, std::uint8_t reason) override {
    ++counters.rejected;
    queue.ack(seq);
    retained_in_queue.erase(seq);  // not delivered: not published again
    log.warn("mqtt: broker refused a message, reason " + std::to_string(reason));
  }

  // An incoming PUBLISH can only be a request (the only subscriptions).
  void on_publish(const codec::Publish& p) override {
    if (client.running() && on_request) on_request(p);
  }

  void on_subscribe_refused(std::uint8_t code) override {
    log.warn("mqtt: broker refused a request subscription, code " + std::to_string(code));
  }

  // After all packets of one read: refill the window once (one write for
  // the PUBACKs to requests and the next PUBLISHes).
  void on_batch_end(bool acked) override {
    if (acked) stall.progress(std::chrono::steady_clock::now());
    const std::uint64_t writes = client.writes();
    drain();
    if (!client.has_connection()) return;
    client.flush();
    // Nothing written back (the window is still more than half full): ACK
    // at once, or a Nagle broker holds the PUBACKs we wait for.
    if (client.has_connection() && client.writes() == writes && session.inflight_qos1() > 0) client.ack_now();
  }

  // Every byte handed to the kernel: the session's keepalive sees the
  // write, and every QoS 0 message written has left the queue.
  void on_drained(std::size_t qos0_acked, std::chrono::steady_clock::time_point now) override {
    if (qos0_acked == 0) return;
    stall.progress(now);
    // A drain stopped by kMaxBuffered continues (not from inside drain()).
    if (!draining && buffer_full) schedule_pump();
  }

  void drain() {
    // Whoever drains (pump, PUBACK batch, reconnect, retry): what is sent
    // is written to the queue's files first.
    if (!client.connected() || !client.has_connection()) return;
    if (queue.disk().flush_pending()) flush_queue();
    const std::size_t limit = session.window();
    // Refill only once at most half the window is in flight: the window
    // goes out in a few large writes instead of one write per PUBACK read
    // (each read of the broker's PUBACKs otherwise frees a slot or two).
    if (session.inflight_qos1() > limit / 2) return;
    draining = true;
    buffer_full = false;
    for (;;) {
      bool any = false;
      while (client.connected() && session.inflight_qos1() < limit && queue.next(item)) {
        const auto r =
            session.publish(client.out(), item.seq, item.msg.topic, item.msg.payload, item.msg.qos, item.msg.retained);
        if (r.busy) {  // no packet id free: cannot happen with the window's cap
          queue.rewind_to(item.seq);
          break;
        }
        if (r.error != codec::Error::None) {
          // This very message cannot be sent (bad topic, too large): drop it
          // rather than block the queue forever.
          ++counters.rejected;
          queue.ack(item.seq);
          log.warn("mqtt: dropping message to '" + item.msg.topic + "': " + codec::to_string(r.error));
          continue;
        }
        ++counters.sent;
        any = true;
        if (client.pending() >= kMaxBuffered) {
          buffer_full = true;
          break;
        }
      }
      if (!any || !client.has_connection()) break;
      client.flush();  // one write for the batch; may ack QoS 0 at once
      // Go on only if the buffer cap stopped us and the write took it all.
      if (!client.has_connection() || !buffer_full || client.pending() > 0) break;
      buffer_full = false;
    }
    draining = false;
  }

  // Once per io loop turn (posted by the first publish after the last
  // one): write the records the queue buffered, then send them. So a
  // message is in the kernel before it is sent, and the turn's messages go
  // to the socket in one write.
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

  // Writes what the queue buffered. While storage fails only the sync
  // timer retries (the records stay in memory and are sent meanwhile), so a
  // full disk costs no write() per message; check_storage() logs it.
  void flush_queue() {
    if (!queue.disk().storage_error()) (void)queue.disk().flush();
  }

  void keep_retained(std::string_view topic, std::string_view payload, std::uint8_t qos, StorageMode mode,
                     std::uint64_t seq) {
    std::string t(topic);
    const auto old = retained_topics.find(t);
    // At most one place in the queue per topic is followed (one dropped by
    // the queue is never acked).
    if (old != retained_topics.end() && !old->second.delivered) retained_in_queue.erase(old->second.seq);
    if (payload.empty()) {  // deletes the broker's retained message: nothing to publish again
      if (old != retained_topics.end()) retained_topics.erase(old);
      return;
    }
    Retained& r = old != retained_topics.end() ? old->second : retained_topics[t];
    r.payload.assign(payload);
    r.qos = qos;
    r.mode = mode;
    r.seq = seq;
    r.delivered = false;
    retained_in_queue.emplace(seq, std::move(t));
  }

  void publish(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained, StorageMode mode) {
    ++counters.published;
    const std::uint64_t seq = queue.push(topic, payload, qos, retained, mode);
    if (seq == 0) return;  // dropped: counted by the queue
    if (retained) keep_retained(topic, payload, qos, mode, seq);
    schedule_pump();
  }

  // --- request replies (the requests themselves: mqtt_requests.hpp) -------

  ReplyOutcome send_reply(std::string_view topic, std::string_view body, const codec::PublishProperties& props) {
    if (!client.connected() || !client.has_connection()) return ReplyOutcome::not_connected;
    if (!send_control(topic, body, false, &props)) return ReplyOutcome::not_encodable;
    client.flush();  // a reply from a handler completing later has no batch to join
    return ReplyOutcome::sent;
  }

  void stop(std::chrono::milliseconds timeout, const MqttPublisher::Farewell& last) {
    if (!client.running()) return;
    sync_timer.cancel();
    std::vector<std::uint64_t> tail_q0;  // leave the queue once written, as in on_drained()
    // Everything goes in one synchronous write: first the queue's unsent
    // messages as drain() would send them (window and buffer cap), so the
    // final messages overtake nothing when there is no backlog; then the
    // farewell, the offline status (retained) and DISCONNECT. The broker
    // handles them in order, so the Will is not sent.
    const auto farewell = client.stop(timeout, [&](std::string& out) {
      flush_queue();
      while (session.window_open() && out.size() < kMaxBuffered && queue.next(item)) {
        const auto r =
            session.publish(out, item.seq, item.msg.topic, item.msg.payload, item.msg.qos, item.msg.retained);
        if (r.busy) break;
        // Not encodable: left queued; the next run's drain() drops it.
        if (r.error != codec::Error::None) continue;
        if (session.out_qos(item.msg.qos) == 0) tail_q0.push_back(item.seq);
        ++counters.sent;
      }
      // The last messages' PUBACKs are never awaited.
      for (const auto& m : last.messages) session.publish_final(out, m.topic, m.payload, m.qos, m.retained);
      session.publish_final(out, status_topic(),
                            last.offline_payload.empty() ? cfg.offline_payload : last.offline_payload, 1, true);
      session.disconnect(out);
    });
    const bool farewell_sent = farewell == Client::Farewell::Sent;
    if (farewell == Client::Farewell::NotSent) log.warn("mqtt: disconnect did not complete; the broker sends the Will");
    for (auto seq : farewell_sent ? tail_q0 : std::vector<std::uint64_t>{})
      if (queue.ack(seq)) ++counters.acked;
    queue.rewind();
    queue.set_online(false);  // `outage` messages still in memory go to disk for the next run
    // Unacknowledged messages are replayed by the next run; the farewell
    // must come after them again (and at all, when it was not sent now).
    if (!last.messages.empty() && (!farewell_sent || queue.depth() > 0)) {
      for (const auto& m : last.messages) publish(m.topic, m.payload, m.qos, m.retained, StorageMode::Disk);
    }
    flush_queue();
    queue.disk().sync();
  }

  Counters snapshot() const {
    Counters c = counters;
    c.dropped += queue.dropped() + c.rejected;
    c.queue_depth = queue.depth();
    c.queue_bytes = queue.disk().counters().bytes + queue.counters().memory_bytes;
    c.storage_failing = static_cast<bool>(queue.disk().storage_error());
    c.in_flight = in_flight();
    c.connects = client.connects();
    c.reconnects = client.reconnects();
    c.connected = client.connected();
    c.mqtt_version = client.version();
    if (c.connected) c.broker = client.uri();
    c.socket_writes = client.writes();
    return c;
  }
};

MqttPublisher::MqttPublisher(asio::io_context& io, MqttConfig cfg, Logger& log, RequestSink on_request)
    : impl_(std::make_shared<Impl>(io, std::move(cfg), log, std::move(on_request))) {}

ReplySender MqttPublisher::reply_sender() const {
  return [weak = std::weak_ptr<Impl>(impl_)](std::string_view topic, std::string_view body,
                                             const codec::PublishProperties& props) {
    auto self = weak.lock();
    return self ? self->send_reply(topic, body, props) : ReplyOutcome::gone;
  };
}

MqttPublisher::~MqttPublisher() { impl_->stop(std::chrono::seconds(1), {}); }

void MqttPublisher::start() { impl_->start(); }
void MqttPublisher::stop(std::chrono::milliseconds timeout, const Farewell& last) { impl_->stop(timeout, last); }

void MqttPublisher::publish(const EncodedEventPtr& ev) { publish(ev, impl_->cfg.format); }

void MqttPublisher::publish(const EncodedEventPtr& ev, PayloadFormat format) {
  if (!ev) return;
  const auto k = static_cast<std::size_t>(ev->kind);
  const bool known = k < kEventKindCount;
  impl_->publish(ev->topic, format == PayloadFormat::Json ? ev->json : ev->binary, known ? impl_->cfg.qos[k] : 1,
                 ev->retained, known ? impl_->cfg.storage_for(ev->kind) : StorageMode::Disk);
}

void MqttPublisher::publish(const QueuedMessage& m) {
  publish(m, m.qos == 0 ? StorageMode::Outage : StorageMode::Disk);
}

void MqttPublisher::publish(const QueuedMessage& m, StorageMode mode) {
  impl_->publish(m.topic, m.payload, m.qos, m.retained, mode);
}

MqttPublisher::Counters MqttPublisher::counters() const { return impl_->snapshot(); }
const DiskQueue::Counters& MqttPublisher::queue_counters() const { return impl_->queue.disk().counters(); }
const OutboundQueue::Counters& MqttPublisher::tier_counters() const { return impl_->queue.counters(); }
std::string MqttPublisher::status_topic() const { return impl_->status_topic(); }

}  // namespace gateway::mqtt
