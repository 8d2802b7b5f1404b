// One MQTT network connection on the caller's io_context: TCP or TLS
// connect, a read loop that hands up what arrives, and coalesced writes.
// It knows no MQTT packets, sessions, queues or timeouts: the Session
// (session.hpp) does the protocol and mqtt::Client (client.hpp) drives both
// (and limits the connect time by closing the connection).
//
// Writing: callers append encoded packets to out() and call flush().
// Everything appended while a write is in progress goes out in the next
// single write; over TCP, flush() itself makes the send() call (no
// handler hop), so a caller that encodes a batch and flushes once costs one
// syscall. on_drained is called (possibly from inside flush()) whenever
// every appended byte has been handed to the kernel.
//
// Callbacks: on_open once the transport is up (TCP connected, TLS
// handshake done: append CONNECT and flush), on_data for each chunk read,
// on_closed once when the connection fails or the broker closes it (never
// after close() or finish(); posted, never from inside a caller's call).
//
// Thread safety: none; every call on the io thread. Create with
// std::make_shared (handlers keep the connection alive until they ran).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/asio/ssl/stream.hpp>
#include <string_view>

#include "mqtt/mqtt_config.hpp"

namespace gateway::mqtt {

// From a normalized URI (tcp://, ssl://): host (no brackets), port.
struct Endpoint {
  bool tls = false;
  std::string host;
  std::string port;
};
// Throws std::invalid_argument for a URI normalize_server_uri() would not
// give, or a bad port.
Endpoint parse_endpoint(const std::string& normalized_uri);

// The TLS client context of an ssl:// connection from c's ca_file ("" =
// the system trust store), cert_file, key_file and key_password. Throws
// std::exception (e.g. boost::system::system_error) when a file cannot be
// used; callers log that and retry later.
std::unique_ptr<boost::asio::ssl::context> make_tls_context(const MqttConfig& c);

// The reconnect delay after `failures` consecutive failed attempts:
// reconnect_min doubling per failure, capped at reconnect_max.
std::chrono::milliseconds reconnect_delay(const MqttConfig& c, unsigned failures);

class MqttConnection : public std::enable_shared_from_this<MqttConnection> {
 public:
  struct Callbacks {
    std::function<void()> on_open;
    std::function<void(std::string_view)> on_data;
    std::function<void()> on_drained;
    std::function<void(const std::string& why)> on_closed;
  };

  // tls_ctx: required when the endpoint is TLS; must outlive the connection.
  MqttConnection(boost::asio::io_context& io, boost::asio::ssl::context* tls_ctx, bool verify_server,
                 Callbacks cb);
  ~MqttConnection();
  MqttConnection(const MqttConnection&) = delete;
  MqttConnection& operator=(const MqttConnection&) = delete;

  // Starts connecting (resolve, TCP, TLS); on_open when done.
  void open(const Endpoint& ep);

  // Sends the TCP ACK for what was read now instead of the kernel's
  // delayed ACK (TCP_QUICKACK). For a reader that read but writes nothing
  // back: a broker with Nagle on (mosquitto's default) holds its next
  // PUBACKs until that ACK comes, up to the delayed-ACK timeout (40 ms).
  // Called from on_data, it also makes the read loop try one more
  // non-blocking read before it waits (what the ACK released is often
  // there already).
  void ack_now();

  std::string& out() { return out_; }
  void flush();
  // Bytes appended but not yet handed to the kernel.
  std::size_t pending() const { return out_.size() - sent_ + wbuf_.size(); }

  // Closes at once (pending bytes are lost). No callbacks afterwards.
  void close();
  // Blocks up to `timeout`: writes what is pending plus `tail` (e.g. the
  // offline status and DISCONNECT), half-closes and waits for the broker to
  // close, then closes. False if that could not be done (e.g. a TLS write
  // was in progress: the socket is just closed and the broker publishes
  // the Will).
  bool finish(std::string_view tail, std::chrono::milliseconds timeout);

  bool up() const { return state_ == State::Open; }
  std::uint64_t writes() const { return writes_; }  // send()/write calls made
  std::uint64_t reads() const { return reads_; }

 private:
  enum class State : std::uint8_t { Connecting, Open, Closed };
  boost::asio::ip::tcp::socket& sock();
  void on_connected();
  void start_read();
  void on_read(const boost::system::error_code& ec, std::size_t n);
  bool consume(std::size_t n);
  void opened();
  void fail(std::string why);
  void write_done(const boost::system::error_code& ec);

  boost::asio::io_context& io_;
  boost::asio::ssl::context* tls_ctx_;
  bool verify_server_;
  Callbacks cb_;
  boost::asio::ip::tcp::socket tcp_;
  std::unique_ptr<boost::asio::ssl::stream<boost::asio::ip::tcp::socket>> tls_;
  std::unique_ptr<boost::asio::ip::tcp::resolver> resolver_;
  State state_ = State::Connecting;
  std::string host_;
  std::string rbuf_;
  // TCP: out_[sent_..] is unwritten; TLS: wbuf_ is being written, out_ waits.
  std::string out_, wbuf_;
  std::size_t sent_ = 0;
  bool write_busy_ = false;
  bool read_again_ = false;  // set by ack_now(): read once more before waiting
  std::uint64_t writes_ = 0, reads_ = 0;
};

}  // namespace gateway::mqtt
