#include "mqtt/mqtt_connection.hpp"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl/host_name_verification.hpp>
#include <boost/asio/write.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <stdexcept>

namespace gateway::mqtt {

namespace asio = boost::asio;
using asio::ip::tcp;
using Clock = std::chrono::steady_clock;

std::unique_ptr<asio::ssl::context> make_tls_context(const MqttConfig& c) {
  auto ctx = std::make_unique<asio::ssl::context>(asio::ssl::context::tls_client);
  if (!c.ca_file.empty())
    ctx->load_verify_file(c.ca_file);
  else
    ctx->set_default_verify_paths();
  if (!c.key_password.empty())
    ctx->set_password_callback([pw = c.key_password](std::size_t, asio::ssl::context::password_purpose) { return pw; });
  if (!c.cert_file.empty()) ctx->use_certificate_chain_file(c.cert_file);
  if (!c.key_file.empty()) ctx->use_private_key_file(c.key_file, asio::ssl::context::pem);
  return ctx;
}

std::chrono::milliseconds reconnect_delay(const MqttConfig& c, unsigned failures) {
  auto delay = c.reconnect_min;
  for (unsigned i = 0; i < failures && delay < c.reconnect_max; ++i) delay *= 2;
  return std::min(delay, c.reconnect_max);
}

Endpoint parse_endpoint(const std::string& uri) {
  Endpoint ep;
  std::string_view rest(uri);
  if (rest.rfind("tcp://", 0) == 0) {
    rest.remove_prefix(6);
  } else if (rest.rfind("ssl://", 0) == 0) {
    rest.remove_prefix(6);
    ep.tls = true;
  } else {
    throw std::invalid_argument("MQTT URI must start with tcp:// or ssl://: " + uri);
  }
  if (auto slash = rest.find('/'); slash != std::string_view::npos) rest = rest.substr(0, slash);
  std::string_view host = rest, port;
  if (!rest.empty() && rest[0] == '[') {  // [IPv6]:port
    const auto close = rest.find(']');
    if (close == std::string_view::npos) throw std::invalid_argument("MQTT URI: unclosed '[': " + uri);
    host = rest.substr(1, close - 1);
    if (close + 1 < rest.size()) {
      if (rest[close + 1] != ':') throw std::invalid_argument("MQTT URI: bad port: " + uri);
      port = rest.substr(close + 2);
    }
  } else if (auto colon = rest.rfind(':'); colon != std::string_view::npos && rest.find(':') == colon) {
    host = rest.substr(0, colon);
    port = rest.substr(colon + 1);
  }
  if (host.empty()) throw std::invalid_argument("MQTT URI without host: " + uri);
  if (!port.empty()) {
    unsigned p = 0;
    auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), p);
    if (ec != std::errc() || end != port.data() + port.size() || p == 0 || p > 65535)
      throw std::invalid_argument("MQTT URI: bad port: " + uri);
  }
  ep.host = std::string(host);
  ep.port = port.empty() ? (ep.tls ? "8883" : "1883") : std::string(port);
  return ep;
}

MqttConnection::MqttConnection(asio::io_context& io, asio::ssl::context* tls_ctx, bool verify_server, Callbacks cb)
    : io_(io), tls_ctx_(tls_ctx), verify_server_(verify_server), cb_(std::move(cb)), tcp_(io) {}

MqttConnection::~MqttConnection() = default;

tcp::socket& MqttConnection::sock() { return tls_ ? tls_->next_layer() : tcp_; }

void MqttConnection::open(const Endpoint& ep) {
  host_ = ep.host;
  out_.clear();
  sent_ = 0;
  if (ep.tls) {
    if (!tls_ctx_) {
      fail("TLS requested without a TLS context");
      return;
    }
    tls_ = std::make_unique<asio::ssl::stream<tcp::socket>>(io_, *tls_ctx_);
  }
  auto on_connect = [self = shared_from_this()](const boost::system::error_code& ec, const tcp::endpoint&) {
    if (self->state_ == State::Closed) return;
    if (ec) {
      self->fail("connect to " + self->host_ + ": " + ec.message());
      return;
    }
    self->on_connected();
  };
  // A numeric address needs no resolver (whose async form runs a thread).
  boost::system::error_code aec;
  const auto addr = asio::ip::make_address(ep.host, aec);
  if (!aec) {
    std::uint16_t port = 0;
    std::from_chars(ep.port.data(), ep.port.data() + ep.port.size(), port);
    const std::array<tcp::endpoint, 1> eps{tcp::endpoint(addr, port)};
    asio::async_connect(sock(), eps, on_connect);
    return;
  }
  resolver_ = std::make_unique<tcp::resolver>(io_);
  resolver_->async_resolve(ep.host, ep.port,
                           [self = shared_from_this(), on_connect](const boost::system::error_code& ec,
                                                                   const tcp::resolver::results_type& results) {
                             if (self->state_ == State::Closed) return;
                             if (ec) {
                               self->fail("resolve " + self->host_ + ": " + ec.message());
                               return;
                             }
                             asio::async_connect(self->sock(), results, on_connect);
                           });
}

void MqttConnection::on_connected() {
  boost::system::error_code ec;
  sock().set_option(tcp::no_delay(true), ec);  // batches are ours; no Nagle delay on top
  if (!tls_) {
    // TCP: flush() calls send() directly and waits only when the kernel's
    // buffer is full.
    sock().non_blocking(true, ec);
    opened();
    return;
  }
  if (verify_server_) {
    tls_->set_verify_mode(asio::ssl::verify_peer);
    tls_->set_verify_callback(asio::ssl::host_name_verification(host_));
  } else {
    tls_->set_verify_mode(asio::ssl::verify_none);
  }
  boost::system::error_code aec;
  asio::ip::make_address(host_, aec);
  if (aec)  // SNI only for names
    SSL_ctrl(tls_->native_handle(), SSL_CTRL_SET_TLSEXT_HOSTNAME, TLSEXT_NAMETYPE_host_name,
             const_cast<char*>(host_.c_str()));
  tls_->async_handshake(asio::ssl::stream_base::client, [self = shared_from_this()](const boost::system::error_code& e) {
    if (self->state_ == State::Closed) return;
    if (e) {
      self->fail("TLS handshake with " + self->host_ + ": " + e.message());
      return;
    }
    self->opened();
  });
}

// The owner appends CONNECT in on_open; it is the first thing written.
void MqttConnection::opened() {
  state_ = State::Open;
  if (cb_.on_open) cb_.on_open();
  if (state_ != State::Open) return;
  flush();
  if (state_ != State::Open) return;
  start_read();
}

void MqttConnection::flush() {
  if (state_ != State::Open || write_busy_) return;
  if (tls_) {
    if (out_.empty()) return;
    wbuf_.swap(out_);
    out_.clear();
    write_busy_ = true;
    ++writes_;
    asio::async_write(*tls_, asio::buffer(wbuf_),
                      [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
                        self->write_done(ec);
                      });
    return;
  }
  bool wrote = false;
  while (sent_ < out_.size()) {
    boost::system::error_code ec;
    const std::size_t n = tcp_.send(asio::buffer(out_.data() + sent_, out_.size() - sent_), 0, ec);
    ++writes_;
    if (ec == asio::error::would_block || ec == asio::error::try_again) {
      // The kernel's buffer is full: wait until writable, keep appending.
      write_busy_ = true;
      tcp_.async_wait(tcp::socket::wait_write, [self = shared_from_this()](const boost::system::error_code& e) {
        self->write_done(e);
      });
      return;
    }
    if (ec) {
      fail("write: " + ec.message());
      return;
    }
    sent_ += n;
    wrote = true;
  }
  out_.clear();
  sent_ = 0;
  if (wrote && cb_.on_drained) cb_.on_drained();
}

void MqttConnection::write_done(const boost::system::error_code& ec) {
  if (state_ == State::Closed) return;
  write_busy_ = false;
  if (ec) {
    fail("write: " + ec.message());
    return;
  }
  if (tls_) {
    wbuf_.clear();
    if (out_.empty()) {
      if (cb_.on_drained) cb_.on_drained();
      return;
    }
  }
  flush();
}

void MqttConnection::ack_now() {
  if (state_ != State::Open) return;
  const int one = 1;
  ::setsockopt(sock().native_handle(), IPPROTO_TCP, TCP_QUICKACK, &one, sizeof one);
  read_again_ = true;  // on_read() tries one more non-blocking read
}

void MqttConnection::start_read() {
  if (rbuf_.size() != 64 * 1024) rbuf_.resize(64 * 1024);
  auto h = [self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) { self->on_read(ec, n); };
  if (tls_)
    tls_->async_read_some(asio::buffer(rbuf_), std::move(h));
  else
    tcp_.async_read_some(asio::buffer(rbuf_), std::move(h));
}

void MqttConnection::on_read(const boost::system::error_code& ec, std::size_t n) {
  if (state_ == State::Closed) return;
  if (ec) {
    fail(ec == asio::error::eof ? std::string("connection closed by the broker") : "read: " + ec.message());
    return;
  }
  if (!consume(n)) return;
  // After ack_now() the broker's held PUBACKs were usually delivered within
  // that very syscall (loopback): take them now rather than after another
  // wakeup.
  while (read_again_ && !tls_ && state_ != State::Closed) {
    read_again_ = false;
    boost::system::error_code rec;
    const std::size_t m = tcp_.receive(asio::buffer(rbuf_), 0, rec);
    if (rec == asio::error::would_block || rec == asio::error::try_again) break;
    if (rec) {
      fail(rec == asio::error::eof ? std::string("connection closed by the broker") : "read: " + rec.message());
      return;
    }
    if (!consume(m)) return;
  }
  read_again_ = false;
  if (state_ != State::Closed) start_read();
}

// Hands one chunk up; false when the connection closed meanwhile.
bool MqttConnection::consume(std::size_t n) {
  ++reads_;
  if (cb_.on_data) cb_.on_data(std::string_view(rbuf_.data(), n));
  return state_ != State::Closed;
}

void MqttConnection::fail(std::string why) {
  if (state_ == State::Closed) return;
  close();
  if (cb_.on_closed)
    asio::post(io_, [self = shared_from_this(), why = std::move(why)] {
      if (self->cb_.on_closed) self->cb_.on_closed(why);
      self->cb_ = {};
    });
}

void MqttConnection::close() {
  if (state_ == State::Closed) return;
  state_ = State::Closed;
  boost::system::error_code ec;
  if (resolver_) resolver_->cancel();
  sock().close(ec);
}

bool MqttConnection::finish(std::string_view tail, std::chrono::milliseconds timeout) {
  if (state_ != State::Open) {
    close();
    cb_ = {};
    return false;
  }
  const auto deadline = Clock::now() + timeout;
  auto left_ms = [&] {
    const auto l = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    return static_cast<int>(std::max<long long>(0, l));
  };
  bool ok = false;
  boost::system::error_code ec;
  if (tls_) {
    // A TLS write in progress cannot be joined synchronously.
    if (!write_busy_) {
      out_.append(tail);
      asio::write(*tls_, asio::buffer(out_), ec);
      ok = !ec;
      out_.clear();
    }
  } else {
    out_.append(tail);
    const int fd = tcp_.native_handle();
    ok = true;
    while (sent_ < out_.size()) {
      const std::size_t n = tcp_.send(asio::buffer(out_.data() + sent_, out_.size() - sent_), 0, ec);
      if (ec == asio::error::would_block || ec == asio::error::try_again) {
        pollfd pfd{fd, POLLOUT, 0};
        if (::poll(&pfd, 1, left_ms()) <= 0) {
          ok = false;
          break;
        }
        continue;
      }
      if (ec) {
        ok = false;
        break;
      }
      sent_ += n;
    }
    if (ok) {
      // Half-close and wait for the broker to close after DISCONNECT, so
      // unread bytes on our side cannot turn the close into a reset that
      // races with the broker reading the offline status.
      tcp_.shutdown(tcp::socket::shutdown_send, ec);
      char sink[4096];
      for (;;) {
        tcp_.receive(asio::buffer(sink), 0, ec);
        if (ec == asio::error::would_block || ec == asio::error::try_again) {
          pollfd pfd{fd, POLLIN, 0};
          if (::poll(&pfd, 1, left_ms()) <= 0) break;
          continue;
        }
        if (ec) break;  // eof (the broker closed) or an error
      }
    }
  }
  close();
  cb_ = {};
  return ok;
}

}  // namespace gateway::mqtt
