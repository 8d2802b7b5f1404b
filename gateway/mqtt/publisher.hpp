// MQTT side of the gateway: publishes encoded events through an
// OutboundQueue (a bounded memory tier and a crash-safe DiskQueue) and takes
// SDO/NMT requests (../shared/api-contract.md).
//
// Settings: MqttConfig (mqtt_config.hpp). The MQTT protocol (CONNECT and
// CONNACK, packet ids, the in-flight window, keepalive, the fallback to
// 3.1.1, the broker's limits) is the sans-I/O Session (session.hpp), run by
// the MQTT client (client.hpp: socket, TLS, timer, reconnect backoff); the
// publisher adds the queue and its storage, the flow and requests.
//
// Storage: each event kind has a StorageMode (MqttConfig::storage_for;
// outbound_queue.hpp). `disk` (default for QoS 1 kinds): written to the
// DiskQueue and fdatasync'ed. `outage` (default for QoS 0 kinds): kept in
// memory while the broker is connected, so a healthy link costs no storage
// writes at all; written to the DiskQueue (never fdatasync'ed on its own)
// while the broker is unreachable or the memory tier is full, and
// everything of it still in memory moves there when the connection is lost
// or the publisher stops. `memory`: never on storage, oldest dropped when
// the tier is full. publish(QueuedMessage) uses `outage` for QoS 0 and
// `disk` otherwise.
//
// Delivery: publish() queues (in memory) and returns; a handler it posts
// (once per io loop turn) writes the turn's `disk`/spilled records to the
// queue's files with one write() and then encodes the messages and writes
// them to the socket, all that the window allows in ONE write (the
// publisher's own MQTT client, mqtt_codec.hpp and mqtt_connection.hpp, on
// the caller's io_context; no threads). A read of the socket handles all
// PUBACKs that arrived; the window is refilled, with one write, once at
// most half of it is in flight (so a window goes out in a few large writes,
// not one write per PUBACK read). So a `disk` message given to publish()
// is in the kernel (survives kill -9 of the gateway) once the io thread has
// finished the handlers ready in the same turn, and before it is sent; a
// kill -9 loses at most the messages published in the current turn (and
// the `outage`/`memory` messages in memory). Every sync_interval the
// queue's position is written and what holds unsynced `disk` data is
// fdatasync'ed (power loss: at most that much lost); with no unsynced
// `disk` data there is no fdatasync. After a crash up to sync_interval of
// already delivered messages may be sent again. While connected an
// in-flight window (Config::inflight_window, capped by the broker's MQTT 5
// Receive Maximum less 4 for status and replies) drains the queue in
// publish order, and a message leaves the queue when the broker
// acknowledges it (PUBACK for QoS 1, handed to the kernel's socket buffer
// for QoS 0). On a connection loss everything unacknowledged is sent again,
// oldest first, after the reconnect; so order holds across outages (per
// topic; across kinds too unless the memory tier overflowed) and a QoS 1
// message is delivered at least once (a duplicate only when a PUBACK was
// lost with the connection). The session is clean (clean start / clean
// session, MQTT 5 Session Expiry 0): the queue, not the broker, holds the
// backlog. A message the broker refuses (MQTT 5 PUBACK reason >= 0x80) or
// that cannot be encoded (empty topic, wildcards, not UTF-8, over the
// broker's Maximum Packet Size) is dropped and counted in `rejected`, so
// one bad message cannot block the queue. Under MQTT 5 the broker's Maximum
// QoS 0 sends QoS 1 messages as QoS 0, and Retain Available 0 clears the
// retain flag.
//
// Stalls (StallDetector, checked on the sync timer): no acknowledgement for
// 30 s while messages are in flight, or messages waiting for 5 s with none
// in flight and no send scheduled, on a live connection: sending restarts
// from the oldest unacked message (duplicates possible, no loss; counted in
// `stalls`). A message merely waiting for the pump handler of its turn is
// not a stall.
//
// Storage failures (disk full, I/O errors): see disk_queue.hpp. The
// publisher keeps running and sending; messages that cannot be stored are
// dropped (newest first, counted), the failure and its end are logged once
// per episode, and writing resumes by itself (retried on the sync timer).
// Warnings of the queue's open (corrupt records skipped, unknown files
// ignored) are logged by the constructor.
//
// Connection: the gateway's own reconnect loop with exponential backoff
// (reconnect_min doubling to reconnect_max); connect_timeout covers TCP
// connect, TLS handshake and CONNACK. keepalive: a PINGREQ when the link is
// quiet, and a connection that sends nothing for 1.5 keepalives is taken
// as lost (the broker's Server Keep Alive wins if it sends one). Will: `<status topic>` retained
// offline_payload; after every connect online_payload is published retained
// before the backlog. With mqtt_version 5, a broker refusing MQTT 5 (CONNACK
// "unsupported protocol version", 0x84, or the 3.1.1 code 1) makes the
// publisher fall back to 3.1.1 for the rest of its life.
//
// Requests: with accept_requests it subscribes (QoS 1) to request_filters()
// (topic_filter.hpp) and hands every PUBLISH received to the RequestSink
// (mqtt_requests.hpp decodes and answers them); replies go out through
// reply_sender() as QoS 1 PUBLISHes outside the queue, flushed at once.
//
// Thread safety: every member function must be called on the thread that
// runs `io` (the io thread); all state lives there and the publisher starts
// no threads (a host name that is not a numeric address is resolved by
// asio's resolver, which uses its own internal thread). The io_context,
// logger and handler must outlive the publisher. stop() (or the
// destructor) blocks the io thread for up to its timeout while the offline
// status and DISCONNECT go out and the broker closes the connection; if
// that cannot be done (TLS write in progress, timeout) the socket is just
// closed and the broker publishes the Will (the same offline status).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>

#include "event_message.hpp"
#include "log.hpp"
#include "mqtt/mqtt_codec.hpp"
#include "mqtt/mqtt_config.hpp"
#include "mqtt/reply_sender.hpp"
#include "mqtt/outbound_queue.hpp"

namespace gateway::mqtt {


class MqttPublisher {
 public:
  struct Counters {
    std::uint64_t published = 0;        // accepted by publish()
    std::uint64_t sent = 0;             // encoded for the socket (resends included)
    std::uint64_t acked = 0;            // confirmed by the broker
    std::uint64_t dropped = 0;          // queue drops (policy) + rejected + write errors
    std::uint64_t rejected = 0;         // refused by the broker (PUBACK >= 0x80) or not encodable
    std::uint64_t queue_depth = 0;
    std::uint64_t queue_bytes = 0;
    std::uint64_t in_flight = 0;
    std::uint64_t connects = 0;         // successful connects
    std::uint64_t reconnects = 0;       // connects after the first
    std::uint64_t socket_writes = 0;    // send()/write calls on the sockets (batching)
    std::uint64_t stalls = 0;           // StallDetector restarts
    bool storage_failing = false;       // the DiskQueue cannot write (see storage failures)
    bool connected = false;
    int mqtt_version = 0;               // of the current connection: 5 or 4
    std::string broker;                 // the connected broker (normalized URI); "" when not connected
  };

  // Every PUBLISH the broker delivers on a request subscription, on the io
  // thread (a view, valid during the call only).
  using RequestSink = std::function<void(const codec::Publish&)>;

  // Opens the queue (throws std::system_error) and validates the URI
  // (throws std::invalid_argument). Does not connect: call start().
  MqttPublisher(boost::asio::io_context& io, MqttConfig cfg, Logger& log, RequestSink on_request = {});
  ~MqttPublisher();
  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  // What stop() sends last, before DISCONNECT.
  struct Farewell {
    // Sent in order before the offline status, e.g. empty retained
    // payloads that delete retained topics (MQTT 3.3.1.3). When they
    // cannot all be sent now (not connected, or the DISCONNECT did not
    // complete), or messages stay queued for the next run (whose replay
    // would end with older values), they are also queued after everything
    // else, so the next run delivers them after that backlog.
    std::vector<QueuedMessage> messages;
    // The offline status as of the stop (e.g. its time and the uptime);
    // "" = MqttConfig::offline_payload, the Will's.
    std::string offline_payload;
  };

  void start();
  // Stops reconnecting and, when connected, sends in one synchronous write
  // (blocking the io thread for up to `timeout`): the queued messages not
  // yet sent, as far as the in-flight window allows (so nothing published
  // before stop() is overtaken), `last.messages`, the offline status
  // (retained) and DISCONNECT. Messages not acknowledged stay on disk for
  // the next run.
  void stop(std::chrono::milliseconds timeout = std::chrono::seconds(2), const Farewell& last = {});

  // Never blocks on the network: queued, sent when the window allows.
  // Events use the storage mode of their kind; a QueuedMessage `outage`
  // for QoS 0 and `disk` otherwise, unless given.
  void publish(const EncodedEventPtr& ev);
  void publish(const EncodedEventPtr& ev, PayloadFormat format);
  void publish(const QueuedMessage& m);
  void publish(const QueuedMessage& m, StorageMode mode);

  // Sends a request's reply now (connected) or says why not. The function
  // may be kept and called after the publisher is gone (ReplyOutcome::gone).
  ReplySender reply_sender() const;

  Counters counters() const;
  const DiskQueue::Counters& queue_counters() const;     // the disk tier
  const OutboundQueue::Counters& tier_counters() const;  // the memory tier and spills
  std::string status_topic() const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace gateway::mqtt
