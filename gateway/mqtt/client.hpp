// One MQTT client on the caller's io_context: the Asio adapter around the
// sans-I/O Session (session.hpp) that both the native publisher
// (MqttPublisher, publisher.hpp) and the Sparkplug B edge node (EdgeClient,
// sparkplug/edge_client.hpp) run on, each with its own client.
//
// It owns the connection (MqttConnection: TCP/TLS I/O), the TLS context
// (made once, at the first ssl:// attempt; a failure is logged and retried
// with backoff), the Session and the one timer at its deadline (connect
// timeout, keepalive), CONNECT (MQTT 5 with the fallback to 3.1.1 at once
// when the broker refuses 5, or 3.1.1 only: Session::Options::mqtt_version)
// and the reconnect loop: reconnect_min doubling to reconnect_max
// (reconnect_delay()) after consecutive failures, reset by an accepted
// CONNACK. With several brokers (MqttConfig::uris(): a cluster, a
// standby) a failed attempt goes on to the next one at once, a round in
// which none answered waits the backoff, and a lost connection is followed
// by an attempt at the next broker: the client stays with the broker it
// reached until that one goes (no preference for the first). What the owner sends it appends to out() with the Session's
// encoders (session()) and flush()es; what happens is reported to the
// owner's ClientEvents.
//
// Log lines: "<log_prefix>: connect to <uri> failed: <why>, retrying" (or
// ", trying <next uri>") and
// "... refused (code N), retrying" (the first of a series, every one at
// debug level), "<log_prefix>: broker <uri> refuses MQTT 5, falling back to
// 3.1.1", "<log_prefix>: TLS setup for <uri> failed: ...",
// "<log_prefix>: cannot build CONNECT (<connect_error_hint>): ...",
// "<log_prefix>: disconnected from <uri>: <why>" (end_connection()). The
// owner logs its connects and losses itself.
//
// Thread safety: none; every call on the io thread (the thread that runs
// `io`); no threads of its own (a host name is resolved by asio's resolver,
// which has an internal thread). The io_context, events and logger MUST
// outlive the client; the client MUST live inside the object start() is
// given (its handlers keep that object alive while they run and do nothing
// once it is gone). Only stop() blocks.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/asio/steady_timer.hpp>

#include "log.hpp"
#include "mqtt/mqtt_codec.hpp"
#include "mqtt/mqtt_config.hpp"
#include "mqtt/mqtt_connection.hpp"
#include "mqtt/session.hpp"

namespace gateway::mqtt {

// "tcp://h:1" stays; mqtt:// -> tcp://, mqtts:// -> ssl://. Throws
// std::invalid_argument for any other scheme or an empty host.
std::string normalize_server_uri(const std::string& uri);

// Why a connection attempt or a connection is over (ClientEvents::on_down).
enum class Down : std::uint8_t {
  Failed,   // before CONNACK: TCP, TLS, connect timeout, protocol error
  Refused,  // CONNACK refused (also when the client falls back to 3.1.1)
  Lost,     // after CONNACK: the broker, the network or the keepalive ended it
  Ended,    // the owner ended it (Client::end_connection)
};

// The owner's side. Called on the io thread, from inside the client's
// handlers and calls; a handler may call the client back (append to out(),
// flush(), end_connection(), stop()).
class ClientEvents {
 public:
  virtual ~ClientEvents() = default;
  // A CONNECT is about to be built (after the TLS set-up): e.g. a new Will
  // with session().set_will().
  virtual void on_connecting() {}
  // CONNACK accepted: connected(), nothing in flight; append what opens
  // the session (status, SUBSCRIBEs, births) and flush().
  virtual void on_up(const BrokerLimits& limits) = 0;
  // The attempt or the connection is over and closed: connected() is
  // false. The client retries when this returns (at once after a fallback
  // to 3.1.1, else with backoff), unless it was stopped meanwhile. why: the
  // session's or end_connection()'s reason.
  virtual void on_down(Down cause, const std::string& why) = 0;
  // The Session's events (session.hpp), passed on as they come.
  virtual void on_publish(const codec::Publish& p) = 0;
  virtual void on_acked(std::uint64_t /*token*/) {}
  virtual void on_rejected(std::uint64_t /*token*/, std::uint8_t /*reason*/) {}
  virtual void on_subscribe_refused(std::uint8_t /*code*/) {}
  virtual void on_batch_end(bool /*acked*/) {}
  // Every byte appended so far reached the kernel (possibly from inside a
  // flush()); qos0_acked: the QoS 0 messages this acknowledged
  // (Session::wrote(), on_acked each).
  virtual void on_drained(std::size_t /*qos0_acked*/, std::chrono::steady_clock::time_point /*now*/) {}
};

class Client : private SessionEvents {
 public:
  struct Options {
    Session::Options session;         // common_session_options() plus the owner's Will and limits
    std::string log_prefix = "mqtt";  // "<log_prefix>: " starts each line
    std::string connect_error_hint = "client id, user, will";  // in "cannot build CONNECT (<hint>)"
  };
  // The Session::Options every owner takes from its MqttConfig: version,
  // client id, credentials, keepalive, connect timeout.
  static Session::Options common_session_options(const MqttConfig& c);

  // cfg: server_uri and standby_uris, the TLS files, verify_server,
  // reconnect_min/max (the session's part is in opts.session). Checks
  // every URI (std::invalid_argument, as normalize_server_uri and
  // parse_endpoint).
  // Does not connect.
  Client(boost::asio::io_context& io, const MqttConfig& cfg, Options opts, ClientEvents& events, Logger& log);
  ~Client() override;
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Connects, and reconnects until stop(). owner: the object that holds the
  // client and the events.
  void start(std::weak_ptr<void> owner);

  enum class Farewell : std::uint8_t { NotConnected, Sent, NotSent };
  // Stops reconnecting and ends the session. When connected and last_words
  // is given, it appends the last packets (publish_final(), disconnect())
  // to its argument; they are written with the unwritten output in one
  // synchronous write, blocking up to `timeout` until the broker has closed
  // the connection (Sent), or the socket is just closed (NotSent: the
  // broker publishes the Will). Otherwise the connection is just closed.
  // No events during or after it.
  Farewell stop(std::chrono::milliseconds timeout, const std::function<void(std::string& out)>& last_words);

  // The owner ends the connection itself (e.g. after its DISCONNECT has
  // drained): closes it, logs, reports Down::Ended and reconnects with
  // backoff.
  void end_connection(const std::string& why);

  // --- sending: the session's encoders append to out(); out(), flush() and
  // ack_now() only while has_connection() ---------------------------------
  Session& session() { return session_; }
  const Session& session() const { return session_; }
  bool has_connection() const { return conn_ != nullptr; }
  std::string& out() { return conn_->out(); }
  void flush() { conn_->flush(); }
  // Bytes appended and not yet handed to the kernel (0 without a connection).
  std::size_t pending() const { return conn_ ? conn_->pending() : 0; }
  // MqttConnection::ack_now().
  void ack_now() { conn_->ack_now(); }

  // --- state ---------------------------------------------------------------
  bool running() const { return running_; }
  bool connected() const { return connected_; }
  int version() const { return connected_ ? session_.version() : 0; }  // 5 or 4 while connected
  // Changes with every connection attempt: a handler the owner posts checks
  // it still has the connection it was posted for.
  std::uint64_t connection_id() const { return conn_gen_; }
  // The broker connected to, or the one being tried or tried next (normalized).
  const std::string& uri() const { return uris_[current_]; }
  const std::vector<std::string>& uris() const { return uris_; }  // every broker, normalized, in order
  std::uint64_t connects() const { return connects_; }                                     // CONNACKs accepted
  std::uint64_t reconnects() const { return reconnects_; }                                 // connects after the first
  std::uint64_t writes() const { return writes_before_ + (conn_ ? conn_->writes() : 0); }  // socket writes

 private:
  void connect();
  bool ensure_tls();
  void drop_connection();
  void schedule_retry();
  void went_down(Down cause, const std::string& why);
  // After a failed attempt: the next broker at once while this round has
  // not tried every one, else the backoff. `what`: "failed: <why>" or
  // "refused (code N)".
  void retry_after_failure(const std::string& what);
  void next_broker();

  // SessionEvents
  void on_connected(const BrokerLimits& limits) override;
  void on_refused(std::uint8_t code, bool fell_back) override;
  void on_acked(std::uint64_t token) override { events_.on_acked(token); }
  void on_rejected(std::uint64_t token, std::uint8_t reason) override { events_.on_rejected(token, reason); }
  void on_publish(const codec::Publish& p) override { events_.on_publish(p); }
  void on_subscribe_refused(std::uint8_t code) override { events_.on_subscribe_refused(code); }
  void on_batch_end(bool acked) override { events_.on_batch_end(acked); }
  void on_lost(const std::string& why, bool was_up, bool fell_back) override;
  void on_deadline_changed() override;

  boost::asio::io_context& io_;
  MqttConfig cfg_;
  std::string prefix_;  // "<log_prefix>: "
  std::string connect_error_hint_;
  ClientEvents& events_;
  Logger& log_;
  std::vector<std::string> uris_;  // normalized, never empty
  std::vector<Endpoint> endpoints_;
  std::size_t current_ = 0;        // uris_ index
  std::size_t tried_in_round_ = 0; // brokers that failed since the last connect or backoff
  std::weak_ptr<void> owner_;
  std::unique_ptr<boost::asio::ssl::context> tls_ctx_;
  boost::asio::steady_timer retry_timer_;
  boost::asio::steady_timer session_timer_;  // at session_.deadline()
  Session session_;
  std::shared_ptr<MqttConnection> conn_;
  std::uint64_t conn_gen_ = 0;  // which connection callbacks belong to
  bool running_ = false;
  bool connected_ = false;
  bool connecting_ = false;
  unsigned failures_ = 0;  // consecutive, for the backoff
  std::uint64_t connects_ = 0, reconnects_ = 0;
  std::uint64_t writes_before_ = 0;  // socket writes of earlier connections
  std::string final_;                // stop()'s last packets
};

}  // namespace gateway::mqtt
