// The client side of one MQTT session (3.1.1 and 5), sans-I/O: no sockets,
// timers, clocks or threads. The owner (MqttPublisher, the Asio adapter)
// feeds it what the transport saw and the current time, writes the bytes it
// appends to the owner's output buffer, and arms one timer at deadline().
//
//   open(now)                 a new connection attempt: builds CONNECT and
//                             sets the connect deadline (TCP connect, TLS
//                             handshake and CONNACK together)
//   transport_connected(out)  appends CONNECT
//   received(out, bytes, now) decodes (mqtt_codec.hpp) and handles packets;
//                             may append PUBACKs for incoming PUBLISHes
//   wrote(now)                every appended byte reached the kernel
//   transport_closed(why)     the transport failed or the broker closed it
//   on_timer(out, now)        deadline() came: connect timeout, PINGREQ,
//                             or the broker's silence ends the connection
//
// It owns the packet ids and the in-flight window: QoS 1 messages up to
// window() (the configured window, capped by the broker's MQTT 5 Receive
// Maximum less kReceiveMaximumReserve for status and replies), each
// identified by the owner's token (a queue id) until its PUBACK. It handles
// CONNACK (the fallback from MQTT 5 to 3.1.1 when the broker refuses 5:
// reason 0x84 or the 3.1.1 code 1, or closes the connection without a
// CONNACK; back to 5 when that 3.1.1 attempt fails too), the broker's limits (Maximum QoS caps
// QoS 1, Retain Available 0 clears retain, Maximum Packet Size refuses a
// PUBLISH larger than it, Server Keep Alive replaces the keepalive),
// keepalive (a PINGREQ every half keepalive when the link has been quiet in
// either direction; no byte from the broker for 1.5 keepalives ends the
// connection) and incoming PUBLISHes (QoS 1 acknowledged).
//
// Resend: the owner's queue holds every unacknowledged message and hands
// them out again, oldest first, after a reconnect (or a stall restart); the
// session remembers which tokens were in flight when the window was lost
// (resend_list(), oldest first) and sends those again with DUP set.
//
// Events go to SessionEvents, synchronously from inside the call that
// caused them; an event handler may call the session again (publish,
// close ...). After on_lost() the owner closes the transport.
//
// Thread safety: none; one owner thread.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/clock.hpp"
#include "mqtt/mqtt_codec.hpp"

namespace gateway::mqtt {

// What the broker's CONNACK allows on this connection.
struct BrokerLimits {
  std::uint8_t version = codec::kMqtt5;  // 5 or 4 (3.1.1)
  std::size_t receive_maximum = 0;        // MQTT 5 Receive Maximum; 0: none
  std::uint8_t maximum_qos = 1;           // of the QoS the gateway uses (0/1)
  bool retain_available = true;
  std::size_t maximum_packet_size = 0;    // 0: none
  std::chrono::seconds keepalive{0};      // in effect (Server Keep Alive wins)
};

class SessionEvents {
 public:
  virtual ~SessionEvents() = default;
  // CONNACK accepted; nothing is in flight.
  virtual void on_connected(const BrokerLimits& limits) = 0;
  // CONNACK refused; the session is closed. fell_back: the broker refused
  // MQTT 5 and the session now speaks 3.1.1: connect again at once.
  virtual void on_refused(std::uint8_t code, bool fell_back) = 0;
  // A message left the window: its PUBACK came (QoS 1), or its bytes
  // reached the kernel (QoS 0, from wrote()).
  virtual void on_acked(std::uint64_t token) = 0;
  // The broker refused it (MQTT 5 PUBACK reason >= 0x80); resending would
  // only repeat that.
  virtual void on_rejected(std::uint64_t token, std::uint8_t reason) = 0;
  // An incoming PUBLISH (views valid during the call); a QoS 1 one's PUBACK
  // is already appended to the output.
  virtual void on_publish(const codec::Publish& p) = 0;
  // The broker refused a subscription (SUBACK code >= 0x80).
  virtual void on_subscribe_refused(std::uint8_t code) = 0;
  // After the packets of one received() call, while connected. acked: a
  // PUBACK for a queue message was among them.
  virtual void on_batch_end(bool acked) = 0;
  // The connection is over (timeout, protocol error, broker's DISCONNECT,
  // transport closed); was_up: after an accepted CONNACK. The owner closes
  // the transport; what was in flight is on resend_list(). fell_back: the
  // broker closed the connection without a CONNACK to an MQTT 5 CONNECT
  // (as 3.1.1-only brokers do), so the next open() is 3.1.1: connect again
  // at once.
  virtual void on_lost(const std::string& why, bool was_up, bool fell_back) = 0;
  // deadline() changed: re-arm the timer (or cancel it when none).
  virtual void on_deadline_changed() = 0;
};

class Session {
 public:
  // MQTT 5 DISCONNECT reason 0x04 "Disconnect with Will Message" (what a
  // Sparkplug edge node sends at an intentional disconnect, facts A.4.6).
  static constexpr std::uint8_t kDisconnectWithWill = 0x04;
  // Room under the broker's Receive Maximum for the status and replies.
  static constexpr std::size_t kReceiveMaximumReserve = 4;

  struct Options {
    int mqtt_version = 5;  // 5: MQTT 5 with fallback to 3.1.1; 4: 3.1.1 only
    std::string client_id, username, password;  // empty user/password: none
    std::string will_topic, will_payload;        // empty topic: no Will
    // The native status Will is retained QoS 1 (the defaults); a Sparkplug
    // NDEATH Will is QoS 1, not retained (facts A.4.2).
    std::uint8_t will_qos = 1;
    bool will_retain = true;
    std::chrono::seconds keepalive{30};
    std::chrono::seconds connect_timeout{10};
    std::size_t inflight_window = 256;           // QoS 1 messages in flight
    // Told to the broker under MQTT 5 (requests it may have unacked with
    // us; the largest packet it may send).
    std::uint16_t receive_maximum = 64;
    std::uint32_t maximum_packet_size = 4u << 20;
  };

  enum class State : std::uint8_t { Idle, Connecting, AwaitConnack, Up };

  // What publish() did. ok(): appended. busy: no packet id free (nothing
  // appended; try again after PUBACKs). error: the message cannot go out
  // as the broker allows (empty topic, wildcards, not UTF-8, over the
  // Maximum Packet Size): nothing appended.
  struct SendResult {
    codec::Error error = codec::Error::None;
    bool busy = false;
    bool ok() const { return error == codec::Error::None && !busy; }
  };

  // events MUST outlive the session.
  Session(Options opts, SessionEvents& events);
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // --- the transport's life ------------------------------------------
  // Starts a connection attempt (state Connecting, deadline now +
  // connect_timeout). An error when CONNECT cannot be built (client id,
  // user or Will not encodable): nothing changes.
  codec::Error open(canopen::TimePoint now);
  // Replaces the Will (topic "" = none) for the next open(): a Sparkplug
  // edge node's NDEATH carries a new bdSeq with every CONNECT.
  void set_will(std::string topic, std::string payload);
  void transport_connected(std::string& out, canopen::TimePoint now);
  void received(std::string& out, std::string_view bytes, canopen::TimePoint now);
  // Returns how many QoS 0 messages this acknowledged (on_acked each).
  std::size_t wrote(canopen::TimePoint now);
  void transport_closed(const std::string& why);
  void on_timer(std::string& out, canopen::TimePoint now);
  // The owner ends the session (stop, or after it closed the transport
  // itself): state Idle, no events; what was in flight goes to
  // resend_list().
  void close();
  // The next CONNECT is at the configured version again, whatever the
  // last broker made it fall back to (the client moved on to another
  // broker of its list, which may speak MQTT 5). Only while Idle.
  void reset_version();

  // --- sending (state Up) ---------------------------------------------
  // A queue message; QoS 1 only while window_open(). DUP when the token is
  // on resend_list().
  SendResult publish(std::string& out, std::uint64_t token, std::string_view topic, std::string_view payload,
                     std::uint8_t qos, bool retain);
  // A message outside the queue (status, replies): QoS 1 (or the broker's
  // Maximum QoS), outside the window; its PUBACK produces no event. False
  // when it cannot be encoded or no packet id is free.
  bool publish_control(std::string& out, std::string_view topic, std::string_view payload, bool retain,
                       const codec::PublishProperties* props = nullptr);
  // A last message before disconnect(), whose PUBACK is never awaited.
  void publish_final(std::string& out, std::string_view topic, std::string_view payload, std::uint8_t qos,
                     bool retain);
  SendResult subscribe(std::string& out, std::span<const codec::Subscription> subs);
  // DISCONNECT. `reason` is sent under MQTT 5 only (3.1.1 has none; there
  // any DISCONNECT makes the broker discard the Will): 0 "normal", the
  // broker discards the Will; kDisconnectWithWill, the broker publishes it.
  void disconnect(std::string& out, std::uint8_t reason = 0);
  // Forgets the queue messages in flight (a stall: the owner hands them
  // out again, oldest first); control messages stay.
  void restart_window();

  // --- state -----------------------------------------------------------
  State state() const { return state_; }
  bool up() const { return state_ == State::Up; }
  std::uint8_t version() const { return version_; }  // of the current/next CONNECT
  const BrokerLimits& limits() const { return limits_; }
  std::size_t window() const;
  bool window_open() const { return inflight_q1_ < window(); }
  std::size_t inflight_qos1() const { return inflight_q1_; }
  std::size_t in_flight() const { return inflight_q1_ + unwritten_q0_.size(); }
  // The QoS a message of `qos` goes out with (Maximum QoS caps 1).
  std::uint8_t out_qos(std::uint8_t qos) const { return qos == 0 ? 0 : limits_.maximum_qos; }
  // Tokens that were in flight when the window was last lost, oldest
  // first, not yet sent again.
  std::span<const std::uint64_t> resend_list() const;
  std::optional<canopen::TimePoint> deadline() const { return deadline_; }

 private:
  void handle(std::string& out, const codec::Packet& p, canopen::TimePoint now);
  void handle_connack(const codec::Packet& p, canopen::TimePoint now);
  void on_puback(std::uint16_t pid, std::uint8_t reason);
  // closed_awaiting_connack: the transport closed before any CONNACK.
  void lost(const std::string& why, bool closed_awaiting_connack = false);
  void set_deadline(std::optional<canopen::TimePoint> d);
  void forget_window(bool control_too);
  bool take_resend(std::uint64_t token);
  std::uint16_t alloc_pid();
  codec::Error encode_out(std::string& out, std::string_view topic, std::string_view payload, std::uint8_t qos,
                          bool retain, std::uint16_t pid, bool dup, const codec::PublishProperties* props) const;
  std::chrono::milliseconds ping_period() const;

  Options opts_;
  SessionEvents& ev_;
  State state_ = State::Idle;
  std::uint8_t version_;
  bool fell_back_ = false;  // version_ is 3.1.1 by a fallback, not by the options
  BrokerLimits limits_;
  std::string connect_packet_;
  codec::Decoder decoder_;
  std::optional<canopen::TimePoint> deadline_;
  canopen::TimePoint last_read_{}, last_write_{};
  bool ping_outstanding_ = false;
  // Packet id -> token (or kControl) while its PUBACK is due; one flat
  // table so the hot path never allocates.
  std::vector<std::uint64_t> pid_slot_;
  std::uint16_t next_pid_ = 0;
  std::size_t inflight_q1_ = 0;
  std::vector<std::uint64_t> unwritten_q0_;  // QoS 0 tokens not yet in the kernel
  std::vector<std::uint64_t> resend_;        // resend_list() is resend_[resend_pos_..]
  std::size_t resend_pos_ = 0;
  bool acked_in_batch_ = false;
  std::vector<std::uint8_t> suback_codes_;
};

}  // namespace gateway::mqtt
