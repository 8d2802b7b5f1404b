// One MQTT network connection on the caller's io_context: TCP or TLS
// connect (with a timeout covering connect, handshake and CONNACK), the
// CONNECT/CONNACK exchange, a read loop that decodes packets, coalesced
// writes, and keepalive (PINGREQ, and a dead-connection timeout). It knows
// nothing of sessions, queues or packet ids: MqttPublisher drives it.
//
// Writing: callers append encoded packets to out() and call flush().
// Everything appended while a write is in progress goes out in the next
// single write; over TCP, flush() itself makes the send() call (no
// handler hop), so a caller that encodes a batch and flushes once costs one
// syscall. on_drained is called (possibly from inside flush()) whenever
// every appended byte has been handed to the kernel.
//
// Callbacks: on_connack once (any reason code; the owner closes on a
// refusal), on_packet for each packet after it (PINGRESP is swallowed),
// on_batch_end after the packets of one read, on_closed once when the
// connection fails or the broker closes it (never after close() or
// finish(); posted, never from inside a caller's call).
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
#include <boost/asio/steady_timer.hpp>

#include "mqtt/mqtt_codec.hpp"

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

class MqttConnection : public std::enable_shared_from_this<MqttConnection> {
 public:
  struct Callbacks {
    std::function<void(const codec::Connack&)> on_connack;
    std::function<void(const codec::Packet&)> on_packet;
    std::function<void()> on_batch_end;
    std::function<void()> on_drained;
    std::function<void(const std::string& why)> on_closed;
  };

  // tls_ctx: required when the endpoint is TLS; must outlive the connection.
  MqttConnection(boost::asio::io_context& io, boost::asio::ssl::context* tls_ctx, bool verify_server,
                 Callbacks cb);
  ~MqttConnection();
  MqttConnection(const MqttConnection&) = delete;
  MqttConnection& operator=(const MqttConnection&) = delete;

  // Starts connecting; connect_packet (an encoded CONNECT) is the first
  // thing written. version: the CONNECT's protocol level (for decoding).
  // keepalive 0: no PINGREQ and no dead-connection check.
  void open(const Endpoint& ep, std::string connect_packet, std::uint8_t version,
            std::chrono::seconds connect_timeout, std::chrono::seconds keepalive, std::size_t max_packet);

  // Sends the TCP ACK for what was read now instead of the kernel's
  // delayed ACK (TCP_QUICKACK). For a reader that read but writes nothing
  // back: a broker with Nagle on (mosquitto's default) holds its next
  // PUBACKs until that ACK comes, up to the delayed-ACK timeout (40 ms).
  // Called from on_batch_end, it also makes the read loop try one more
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

  bool up() const { return state_ == State::Up; }
  std::uint64_t writes() const { return writes_; }  // send()/write calls made
  std::uint64_t reads() const { return reads_; }

 private:
  enum class State : std::uint8_t { Connecting, AwaitConnack, Up, Closed };
  boost::asio::ip::tcp::socket& sock();
  void on_connected();
  void start_read();
  void on_read(const boost::system::error_code& ec, std::size_t n);
  bool consume(std::size_t n);
  void handle(const codec::Packet& p);
  void fail(std::string why);
  void arm_keepalive();
  void write_done(const boost::system::error_code& ec);

  boost::asio::io_context& io_;
  boost::asio::ssl::context* tls_ctx_;
  bool verify_server_;
  Callbacks cb_;
  boost::asio::ip::tcp::socket tcp_;
  std::unique_ptr<boost::asio::ssl::stream<boost::asio::ip::tcp::socket>> tls_;
  std::unique_ptr<boost::asio::ip::tcp::resolver> resolver_;
  boost::asio::steady_timer connect_timer_;
  boost::asio::steady_timer keepalive_timer_;
  State state_ = State::Connecting;
  std::uint8_t version_ = codec::kMqtt5;
  std::string host_;
  codec::Decoder decoder_;
  std::string rbuf_;
  // TCP: out_[sent_..] is unwritten; TLS: wbuf_ is being written, out_ waits.
  std::string out_, wbuf_;
  std::size_t sent_ = 0;
  bool write_busy_ = false;
  std::chrono::seconds keepalive_{0};
  std::chrono::steady_clock::time_point last_read_{}, last_write_{};
  bool ping_outstanding_ = false;
  bool read_again_ = false;  // set by ack_now(): read once more before waiting
  std::uint64_t writes_ = 0, reads_ = 0;
};

}  // namespace gateway::mqtt
