#include "mqtt/publisher.hpp"

#include "mqtt/mqtt_codec.hpp"
#include "mqtt/mqtt_connection.hpp"
#include "mqtt/stall_detector.hpp"
#include "mqtt/topic_filter.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <vector>

namespace gateway::mqtt {
namespace {

namespace asio = boost::asio;
namespace json = boost::json;

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
// pid_slot values besides a queue sequence number.
constexpr std::uint64_t kFreePid = 0;
constexpr std::uint64_t kControlPid = ~std::uint64_t{0};  // status, replies, SUBSCRIBE
}  // namespace

struct MqttPublisher::Impl : std::enable_shared_from_this<MqttPublisher::Impl> {
  Impl(asio::io_context& io_ctx, MqttConfig c, Logger& l, RequestSink h)
      : io(io_ctx), cfg(std::move(c)), log(l), on_request(std::move(h)), queue(queue_options(cfg)),
        sync_timer(io_ctx), retry_timer(io_ctx), pid_slot(65536, kFreePid) {
    for (const auto& w : queue.disk().take_warnings()) log.warn("mqtt: queue: " + w);
    uri = normalize_server_uri(cfg.server_uri);
    endpoint = parse_endpoint(uri);
    version = cfg.mqtt_version >= 5 ? codec::kMqtt5 : codec::kMqtt311;
    prefix = "canopen/" + cfg.gateway_id + "/";
    if (cfg.inflight_window == 0) cfg.inflight_window = 1;
  }

  asio::io_context& io;
  MqttConfig cfg;
  Logger& log;
  RequestSink on_request;  // mqtt_requests.hpp
  OutboundQueue queue;
  asio::steady_timer sync_timer;
  asio::steady_timer retry_timer;
  StallDetector stall;
  std::error_code storage_error;            // as last logged
  std::uint64_t dropped_at_storage_error = 0;
  std::string uri;
  Endpoint endpoint;
  std::unique_ptr<asio::ssl::context> tls_ctx;
  std::string prefix;
  std::uint8_t version = codec::kMqtt5;
  std::shared_ptr<MqttConnection> conn;
  std::uint64_t conn_gen = 0;  // which connection callbacks belong to
  bool buffer_full = false;    // drain() stopped at kMaxBuffered
  bool pump_posted = false;
  bool draining = false;  // inside drain(): on_drained must not re-enter it
  std::size_t receive_max = 0;  // the broker's Receive Maximum (MQTT 5), 0: none
  std::uint8_t max_qos = 1;     // the broker's Maximum QoS (MQTT 5)
  bool retain_available = true;
  std::size_t max_packet = 0;   // the broker's Maximum Packet Size, 0: none
  // The in-flight window; under the broker's Receive Maximum, leaving room
  // for the status message and request replies.
  std::size_t window() const {
    if (receive_max == 0) return cfg.inflight_window;
    const std::size_t cap = receive_max > 8 ? receive_max - 4 : receive_max;
    return std::min(cap, cfg.inflight_window);
  }
  bool running = false;
  bool connected = false;
  bool connecting = false;
  unsigned failures = 0;  // consecutive, for the backoff
  // Packet id -> queue seq (or kControlPid) while its PUBACK is due; one
  // flat table so the hot path never allocates. Reset per connection.
  std::vector<std::uint64_t> pid_slot;
  std::uint16_t next_pid = 0;
  std::size_t inflight_q1 = 0;               // queue messages awaiting PUBACK
  std::vector<std::uint64_t> unwritten_q0;   // QoS 0 seqs not yet in the kernel
  std::uint64_t socket_writes_before = 0;    // writes of earlier connections
  OutboundQueue::Item item;                  // reused by drain()
  std::vector<std::uint8_t> suback_codes;
  std::string scratch;                       // stop()'s last packets
  bool acks_in_batch = false;
  Counters counters;

  std::string status_topic() const { return prefix + "status"; }

  void start() {
    if (running) return;
    running = true;
    arm_sync();
    connect();
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
      if (ec || !self || !self->running) return;
      if (self->cfg.sync_interval.count() > 0)
        self->queue.disk().sync();  // flushes records and the position first
      else
        self->queue.disk().flush(true);
      self->check_storage();
      self->check_stall();
      self->arm_sync();
    });
  }

  std::size_t in_flight() const { return inflight_q1 + unwritten_q0.size(); }

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

  void check_stall() {
    if (!connected) return;
    const auto now = std::chrono::steady_clock::now();
    StallDetector::Observation o;
    o.in_flight = in_flight();
    o.unsent = o.in_flight == 0 && queue.depth() > 0 && queue.has_unsent();
    o.send_scheduled = pump_posted || buffer_full || (conn && conn->pending() > 0);
    const auto verdict = stall.check(now, o);
    if (verdict == StallDetector::Verdict::Ok) return;
    ++counters.stalls;
    log.warn(std::string("mqtt: delivery stalled (") +
             (verdict == StallDetector::Verdict::NoProgress ? "no acknowledgement for 30 s" : "nothing sent for 5 s") +
             ") with " + std::to_string(in_flight()) + " in flight; resending from " +
             std::to_string(queue.disk().head_seq()));
    forget_in_flight(false);
    queue.rewind();
    drain();
  }

  // Forgets what is in flight (it will be sent again after a rewind).
  // Packet ids keep counting up, so a late PUBACK for a forgotten one
  // finds a free slot and is ignored.
  void forget_in_flight(bool control_too) {
    for (auto& s : pid_slot)
      if (s != kFreePid && (control_too || s != kControlPid)) s = kFreePid;
    inflight_q1 = 0;
    unwritten_q0.clear();
  }

  std::uint16_t alloc_pid() {
    for (int i = 0; i < 65535; ++i) {
      if (++next_pid == 0) next_pid = 1;
      if (pid_slot[next_pid] == kFreePid) return next_pid;
    }
    return 0;
  }

  bool ensure_tls() {
    if (!endpoint.tls || tls_ctx) return true;
    try {
      auto ctx = std::make_unique<asio::ssl::context>(asio::ssl::context::tls_client);
      if (!cfg.ca_file.empty())
        ctx->load_verify_file(cfg.ca_file);
      else
        ctx->set_default_verify_paths();
      if (!cfg.key_password.empty())
        ctx->set_password_callback([pw = cfg.key_password](std::size_t, asio::ssl::context::password_purpose) {
          return pw;
        });
      if (!cfg.cert_file.empty()) ctx->use_certificate_chain_file(cfg.cert_file);
      if (!cfg.key_file.empty()) ctx->use_private_key_file(cfg.key_file, asio::ssl::context::pem);
      tls_ctx = std::move(ctx);
      return true;
    } catch (const std::exception& e) {
      log.error(std::string("mqtt: TLS setup for ") + uri + " failed: " + e.what());
      return false;
    }
  }

  void connect() {
    if (!running || connected || connecting) return;
    if (!ensure_tls()) {
      schedule_retry();
      return;
    }
    codec::ConnectOptions o;
    o.version = version;
    o.clean_start = true;  // the queue, not the broker, holds the backlog
    o.keepalive_s = static_cast<std::uint16_t>(std::clamp<long long>(cfg.keepalive.count(), 0, 65535));
    o.client_id = cfg.client_id;
    const std::string will_topic = status_topic();
    o.will = codec::Will{will_topic, cfg.offline_payload, 1, true};
    if (!cfg.username.empty()) o.username = cfg.username;
    if (!cfg.password.empty()) o.password = cfg.password;
    if (version == codec::kMqtt5) {
      o.session_expiry = 0;
      o.receive_maximum = kOurReceiveMaximum;
      o.maximum_packet_size = static_cast<std::uint32_t>(kMaxIncomingPacket);
    }
    std::string packet;
    if (auto e = codec::encode_connect(packet, o); e != codec::Error::None) {
      log.error(std::string("mqtt: cannot build CONNECT (client id, user, will): ") + codec::to_string(e));
      schedule_retry();
      return;
    }
    connecting = true;
    const std::uint64_t c = ++conn_gen;
    std::weak_ptr<Impl> weak = weak_from_this();
    MqttConnection::Callbacks cb;
    // Each callback checks that its connection is still the current one.
    auto current = [weak](std::uint64_t gen) -> std::shared_ptr<Impl> {
      auto self = weak.lock();
      return self && self->conn && self->conn_gen == gen ? self : nullptr;
    };
    cb.on_connack = [current, c](const codec::Connack& ca) {
      if (auto self = current(c)) self->on_connack(ca);
    };
    cb.on_packet = [current, c](const codec::Packet& p) {
      if (auto self = current(c)) self->on_packet(p);
    };
    cb.on_batch_end = [current, c] {
      if (auto self = current(c)) self->on_batch_end();
    };
    cb.on_drained = [current, c] {
      if (auto self = current(c)) self->on_drained();
    };
    cb.on_closed = [current, c](const std::string& why) {
      if (auto self = current(c)) self->on_closed(why);
    };
    conn = std::make_shared<MqttConnection>(io, tls_ctx.get(), cfg.verify_server, std::move(cb));
    conn->open(endpoint, std::move(packet), version, cfg.connect_timeout, cfg.keepalive, kMaxIncomingPacket);
  }

  void drop_connection() {
    if (!conn) return;
    socket_writes_before += conn->writes();
    conn->close();
    conn.reset();
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

  // The connection failed before or after CONNACK, or the broker closed it.
  void on_closed(const std::string& why) {
    drop_connection();
    if (connecting) {
      connecting = false;
      if (!running) return;
      if (failures == 0 || log.enabled(LogLevel::Debug)) log.warn("mqtt: connect to " + uri + " failed: " + why + ", retrying");
      schedule_retry();
      return;
    }
    on_lost(why);
  }

  void on_connack(const codec::Connack& ca) {
    connecting = false;
    if (!running) {
      drop_connection();
      return;
    }
    if (ca.code != 0) {
      drop_connection();
      // The broker refuses MQTT 5: v5 reason 0x84, or a 3.1.1 broker's
      // CONNACK code 1 (unacceptable protocol version).
      if (version == codec::kMqtt5 && cfg.mqtt_version >= 5 && (ca.code == 0x84 || ca.code == 1)) {
        log.warn("mqtt: broker " + uri + " refuses MQTT 5, falling back to 3.1.1");
        version = codec::kMqtt311;
        connect();
        return;
      }
      if (failures == 0 || log.enabled(LogLevel::Debug))
        log.warn("mqtt: connect to " + uri + " refused (code " + std::to_string(ca.code) + "), retrying");
      schedule_retry();
      return;
    }
    const bool v5 = version == codec::kMqtt5;
    receive_max = v5 ? ca.receive_maximum : 0;
    max_qos = v5 ? std::min<std::uint8_t>(ca.maximum_qos, 1) : 1;
    retain_available = v5 ? ca.retain_available : true;
    max_packet = v5 && ca.maximum_packet_size ? *ca.maximum_packet_size : 0;
    connected = true;
    failures = 0;
    if (counters.connects++ > 0) ++counters.reconnects;
    log.info("mqtt: connected to " + uri + " with MQTT " + (v5 ? "5" : "3.1.1") +
             (receive_max > 0 ? ", receive maximum " + std::to_string(receive_max) : std::string()));
    forget_in_flight(true);
    queue.set_online(true);
    // The online status before the backlog, then the request subscriptions.
    send_control(status_topic(), cfg.online_payload, true, nullptr);
    if (cfg.accept_requests) {
      const auto filters = request_filters(cfg.gateway_id);
      // MQTT 5: no local, so the gateway's own replies are not echoed.
      const codec::Subscription subs[] = {{filters[0], 1, true}, {filters[1], 1, true}, {filters[2], 1, true}};
      if (const std::uint16_t pid = alloc_pid(); pid != 0) {
        if (codec::encode_subscribe(conn->out(), version, pid, subs) == codec::Error::None)
          pid_slot[pid] = kControlPid;
        else
          log.warn("mqtt: request topics cannot be subscribed (gateway id not UTF-8?)");
      }
    }
    queue.rewind();
    stall.reset(std::chrono::steady_clock::now());
    if (log.enabled(LogLevel::Debug))
      log.debug("mqtt: sending from " + std::to_string(queue.disk().head_seq()) + ", " +
                std::to_string(queue.depth()) + " queued");
    drain();
    if (conn) conn->flush();  // status and SUBSCRIBE when the queue is empty
  }

  // The QoS a message goes out with: the broker's Maximum QoS caps QoS 1.
  std::uint8_t out_qos(std::uint8_t qos) const { return qos == 0 ? 0 : max_qos; }

  // Appends one PUBLISH to `out` as the broker allows it: `qos` as from
  // out_qos() (with `pid`, the caller's packet id, when it is 1), the retain
  // flag only where Retain Available, properties only under MQTT 5, and
  // PacketTooLarge above the broker's Maximum Packet Size. The caller
  // records the packet id in pid_slot once this returned None.
  codec::Error encode_out(std::string& out, std::string_view topic, std::string_view payload, std::uint8_t qos,
                          bool retain, std::uint16_t pid, const codec::PublishProperties* props = nullptr) const {
    codec::Publish p;
    p.topic = topic;
    p.payload = payload;
    p.qos = qos;
    p.retain = retain && retain_available;
    p.packet_id = qos > 0 ? pid : 0;
    if (props && version == codec::kMqtt5) p.props = *props;
    if (max_packet > 0 && codec::publish_size(version, p) > max_packet) return codec::Error::PacketTooLarge;
    return codec::encode_publish(out, version, p);
  }

  // A QoS 1 PUBLISH outside the queue (status, replies). False when it
  // could not be encoded.
  bool send_control(std::string_view topic, std::string_view payload, bool retain,
                    const codec::PublishProperties* props) {
    if (!conn) return false;
    const std::uint16_t pid = alloc_pid();
    if (pid == 0) return false;
    const std::uint8_t qos = out_qos(1);
    if (encode_out(conn->out(), topic, payload, qos, retain, pid, props) != codec::Error::None) return false;
    if (qos > 0) pid_slot[pid] = kControlPid;
    return true;
  }

  void on_lost(const std::string& why) {
    drop_connection();
    if (!connected) return;
    connected = false;
    forget_in_flight(true);
    queue.rewind();            // resend everything unacked, in order, after reconnect
    queue.set_online(false);   // `outage` messages in memory go to disk
    log.warn("mqtt: " + why + "; " + std::to_string(queue.depth()) + " messages queued");
    if (running) schedule_retry();
  }

  void on_packet(const codec::Packet& p) {
    switch (p.type) {
      case codec::PacketType::Puback: {
        std::uint16_t pid;
        std::uint8_t reason;
        if (auto e = codec::parse_puback(p, version, pid, reason); e != codec::Error::None) {
          on_lost(std::string("bad PUBACK: ") + codec::to_string(e));
          return;
        }
        on_puback(pid, reason);
        return;
      }
      case codec::PacketType::Publish: {
        codec::Publish in;
        if (auto e = codec::parse_publish(p, version, in); e != codec::Error::None) {
          on_lost(std::string("bad PUBLISH from the broker: ") + codec::to_string(e));
          return;
        }
        if (in.qos > 0) codec::encode_puback(conn->out(), version, in.packet_id);
        if (running && on_request) on_request(in);
        return;
      }
      case codec::PacketType::Suback: {
        std::uint16_t pid;
        suback_codes.clear();
        if (auto e = codec::parse_suback(p, version, pid, suback_codes); e != codec::Error::None) {
          on_lost(std::string("bad SUBACK: ") + codec::to_string(e));
          return;
        }
        if (pid_slot[pid] == kControlPid) pid_slot[pid] = kFreePid;
        for (auto c : suback_codes)
          if (c >= 0x80) log.warn("mqtt: broker refused a request subscription, code " + std::to_string(c));
        return;
      }
      case codec::PacketType::Disconnect: {
        std::uint8_t reason = 0;
        (void)codec::parse_disconnect(p, version, reason);
        on_lost("broker disconnected, reason " + std::to_string(reason));
        return;
      }
      default:
        // PUBREC etc. cannot come (QoS <= 1 both ways): a broker bug.
        on_lost("unexpected packet type " + std::to_string(static_cast<int>(p.type)));
        return;
    }
  }

  void on_puback(std::uint16_t pid, std::uint8_t reason) {
    const std::uint64_t slot = pid_slot[pid];
    if (slot == kFreePid) return;  // forgotten by a stall restart
    pid_slot[pid] = kFreePid;
    if (slot == kControlPid) return;
    --inflight_q1;
    acks_in_batch = true;
    if (reason >= 0x80) {
      // MQTT 5 PUBACK refusal (not authorized, topic invalid ...): resending
      // would only repeat it.
      ++counters.rejected;
      queue.ack(slot);
      log.warn("mqtt: broker refused a message, reason " + std::to_string(reason));
    } else if (queue.ack(slot)) {
      ++counters.acked;
    }
  }

  // After all packets of one read: refill the window once (one write for
  // the PUBACKs to requests and the next PUBLISHes).
  void on_batch_end() {
    if (acks_in_batch) {
      acks_in_batch = false;
      stall.progress(std::chrono::steady_clock::now());
    }
    const std::uint64_t writes = conn ? conn->writes() : 0;
    drain();
    if (!conn) return;
    conn->flush();
    // Nothing written back (the window is still more than half full): ACK
    // at once, or a Nagle broker holds the PUBACKs we wait for.
    if (conn && conn->writes() == writes && inflight_q1 > 0) conn->ack_now();
  }

  // Every QoS 0 message handed to the kernel has left the queue.
  void on_drained() {
    if (unwritten_q0.empty()) return;
    for (auto seq : unwritten_q0)
      if (queue.ack(seq)) ++counters.acked;
    unwritten_q0.clear();
    stall.progress(std::chrono::steady_clock::now());
    // A drain stopped by kMaxBuffered continues (not from inside drain()).
    if (!draining && buffer_full) schedule_pump();
  }

  void drain() {
    // Whoever drains (pump, PUBACK batch, reconnect, retry): what is sent
    // is written to the queue's files first.
    if (!connected || !conn) return;
    if (queue.disk().flush_pending()) flush_queue();
    const std::size_t limit = window();
    // Refill only once at most half the window is in flight: the window
    // goes out in a few large writes instead of one write per PUBACK read
    // (each read of the broker's PUBACKs otherwise frees a slot or two).
    if (inflight_q1 > limit / 2) return;
    draining = true;
    buffer_full = false;
    for (;;) {
      bool any = false;
      while (connected && inflight_q1 < limit && queue.next(item)) {
        const std::uint8_t qos = out_qos(item.msg.qos);
        std::uint16_t pid = 0;
        if (qos > 0 && (pid = alloc_pid()) == 0) {  // cannot happen with a window < 65535
          queue.rewind_to(item.seq);
          break;
        }
        const codec::Error e = encode_out(conn->out(), item.msg.topic, item.msg.payload, qos, item.msg.retained, pid);
        if (e != codec::Error::None) {
          // This very message cannot be sent (bad topic, too large): drop it
          // rather than block the queue forever.
          ++counters.rejected;
          queue.ack(item.seq);
          log.warn("mqtt: dropping message to '" + item.msg.topic + "': " + codec::to_string(e));
          continue;
        }
        if (qos > 0) {
          pid_slot[pid] = item.seq;
          ++inflight_q1;
        } else {
          unwritten_q0.push_back(item.seq);
        }
        ++counters.sent;
        any = true;
        if (conn->pending() >= kMaxBuffered) {
          buffer_full = true;
          break;
        }
      }
      if (!any || !conn) break;
      conn->flush();  // one write for the batch; may ack QoS 0 at once
      // Go on only if the buffer cap stopped us and the write took it all.
      if (!conn || !buffer_full || conn->pending() > 0) break;
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

  void publish(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained, StorageMode mode) {
    ++counters.published;
    if (queue.push(topic, payload, qos, retained, mode) == 0) return;  // dropped: counted by the queue
    schedule_pump();
  }

  // --- request replies (the requests themselves: mqtt_requests.hpp) -------

  ReplyOutcome send_reply(std::string_view topic, std::string_view body, const codec::PublishProperties& props) {
    if (!connected || !conn) return ReplyOutcome::not_connected;
    if (!send_control(topic, body, false, &props)) return ReplyOutcome::not_encodable;
    conn->flush();  // a reply from a handler completing later has no batch to join
    return ReplyOutcome::sent;
  }

  void stop(std::chrono::milliseconds timeout, const MqttPublisher::Farewell& last) {
    if (!running) return;
    running = false;
    sync_timer.cancel();
    retry_timer.cancel();
    bool farewell_sent = false;
    if (conn && connected) {
      // Everything goes in one synchronous write (a TLS write started now
      // could not be joined): first the queue's unsent messages as drain()
      // would send them (window and buffer cap), so the final messages
      // overtake nothing when there is no backlog; then the
      // farewell, the offline status (retained) and DISCONNECT. The broker
      // handles them in order, so the Will is not sent.
      scratch.clear();
      flush_queue();
      std::vector<std::uint64_t> tail_q0;  // leave the queue once written, as in on_drained()
      while (inflight_q1 < window() && scratch.size() < kMaxBuffered && queue.next(item)) {
        const std::uint8_t qos = out_qos(item.msg.qos);
        std::uint16_t pid = 0;
        if (qos > 0 && (pid = alloc_pid()) == 0) break;
        // Not encodable: left queued; the next run's drain() drops it.
        if (encode_out(scratch, item.msg.topic, item.msg.payload, qos, item.msg.retained, pid) != codec::Error::None)
          continue;
        if (qos > 0) {
          pid_slot[pid] = item.seq;
          ++inflight_q1;
        } else {
          tail_q0.push_back(item.seq);
        }
        ++counters.sent;
      }
      // The last messages' PUBACKs are never awaited: any id will do.
      auto add = [&](std::string_view topic, std::string_view payload, std::uint8_t qos, bool retain) {
        const std::uint8_t q = out_qos(qos);
        const std::uint16_t pid = q > 0 ? alloc_pid() : 0;
        (void)encode_out(scratch, topic, payload, q, retain, pid == 0 ? 1 : pid);
      };
      for (const auto& m : last.messages) add(m.topic, m.payload, m.qos, m.retained);
      add(status_topic(), last.offline_payload.empty() ? cfg.offline_payload : last.offline_payload, 1, true);
      codec::encode_disconnect(scratch, version);
      socket_writes_before += conn->writes();
      farewell_sent = conn->finish(scratch, timeout);
      if (!farewell_sent) log.warn("mqtt: disconnect did not complete; the broker sends the Will");
      for (auto seq : farewell_sent ? tail_q0 : std::vector<std::uint64_t>{})
        if (queue.ack(seq)) ++counters.acked;
      conn.reset();
    } else {
      drop_connection();
    }
    connected = false;
    connecting = false;
    forget_in_flight(true);
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
    c.connected = connected;
    c.mqtt_version = connected ? version : 0;
    c.socket_writes = socket_writes_before + (conn ? conn->writes() : 0);
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
                 ev->retained, known ? impl_->cfg.storage[k] : StorageMode::Disk);
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
