// The HTTP session of one stream type (TCP or TLS): TLS handshake, reading
// requests, writing answers, the close and the upgrade to WebSocket; the
// rest is Connection's (connection.cpp).
#include "http/http_session.hpp"

#include <array>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/url/parse.hpp>
#include <cstddef>
#include <optional>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "http/connection.hpp"
#include "http/websocket_session.hpp"

namespace gateway::http {

namespace {

// First read of a request: whatever has arrived, up to this much.
constexpr std::size_t kFirstRead = 4096;

bool iequals(std::string_view a, std::string_view b) { return beast::iequals(a, b); }

template <class Stream>
class HttpSession final : public Connection {
 public:
  HttpSession(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, Stream&& stream, std::string peer)
      : Connection(std::move(impl), std::move(slot), std::move(peer), std::is_same_v<Stream, TlsStream>),
        stream_(std::move(stream)) {}

  // The stream's deadline `d` from now: beast's expires_after() reads the
  // clock once for each of its two timers; a clock read is a system call on
  // some kernels (user-mode Linux), and this runs several times a request.
  void expire_in(std::chrono::steady_clock::duration d) {
    beast::get_lowest_layer(stream_).expires_at(std::chrono::steady_clock::now() + d);
  }

  void run() {
    registered();
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    if constexpr (std::is_same_v<Stream, TlsStream>) {
      set_idle(true);  // no request yet; whether a handshake has begun is unknown
      expire_in(impl_->cfg.read_timeout);
      stream_.async_handshake(net::ssl::stream_base::server, [self](error_code ec) {
        if (ec) {
          self->impl_->counters.tls_failures.fetch_add(1, std::memory_order_relaxed);
          self->impl_->debug("TLS handshake with " + self->peer_ + " failed: " + ec.message());
          self->close_now();
          return;
        }
        self->read_request();
      });
    } else {
      read_request();
    }
  }

  void shutdown() override { close_now(); }

 private:
  void read_request() {
    if (impl_->stopped) {
      close_now();
      return;
    }
    head_ = false;  // an error answer must not inherit the previous request's
    version_ = 11;
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(impl_->cfg.max_header_bytes));
    body_limit_ = impl_->cfg.max_body_bytes;
    // Beast would check a Content-Length against the limit while it parses
    // the header, before the route is known: on_header() applies the
    // route's (or this) limit instead, before any body byte is read.
    parser_->body_limit(boost::none);
    if (buffer_.size() > 0) {  // pipelined: the next request has begun
      read_header();
      return;
    }
    // Idle until the first byte: this connection may be closed for a new
    // one meanwhile (Impl::evict_idle).
    set_idle(true);
    expire_in(impl_->cfg.idle_timeout);
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    stream_.async_read_some(buffer_.prepare(kFirstRead), [self](error_code ec, std::size_t n) {
      self->set_idle(false);
      if (ec) return self->close_now();  // end of stream, idle timeout, evicted
      self->buffer_.commit(n);
      self->read_header();
    });
  }

  // From the request's first byte, the whole header within header_timeout.
  void read_header() {
    expire_in(impl_->cfg.header_timeout);
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    bhttp::async_read_header(stream_, buffer_, *parser_, [self](error_code ec, std::size_t) {
      if (ec == beast::error::timeout) {
        self->impl_->counters.header_timeouts.fetch_add(1, std::memory_order_relaxed);
        self->impl_->debug("closing " + self->peer_ + ": request header not complete in time");
      }
      self->on_header(ec);
    });
  }

  void on_header(error_code ec) {
    if (ec) {
      on_read_error(ec);
      return;
    }
    expire_in(impl_->cfg.read_timeout);
    const auto& req = parser_->get();
    head_ = req.method() == bhttp::verb::head;
    version_ = req.version();
    if (auto refused = screen(req)) {
      // The body (or what follows) is not read: it may be anything.
      keep_alive_ = false;
      send(std::move(*refused));
      return;
    }
    // A route with its own body limit (an upload) gets it before its body
    // is read; every other request keeps the server's.
    if (const auto* opts = route_options(req); opts != nullptr && opts->max_body_bytes > 0)
      body_limit_ = opts->max_body_bytes;
    if (const auto length = parser_->content_length(); length && *length > body_limit_) {
      keep_alive_ = false;  // the body is not read
      send(Response::problem(413, "request body larger than " + std::to_string(body_limit_) + " bytes"));
      return;
    }
    parser_->body_limit(body_limit_);  // a chunked body counts against it as it comes
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    if (!parser_->is_done() && iequals(req[bhttp::field::expect], "100-continue")) {
      // curl and others wait for this before sending a larger body.
      static constexpr std::string_view kContinue = "HTTP/1.1 100 Continue\r\n\r\n";
      net::async_write(stream_, net::buffer(kContinue.data(), kContinue.size()),
                       [self](error_code ec2, std::size_t) {
                         if (ec2) return self->close_now();
                         self->read_body();
                       });
      return;
    }
    read_body();
  }

  void read_body() {
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    if (parser_->is_done()) {
      on_request();
      return;
    }
    bhttp::async_read(stream_, buffer_, *parser_, [self](error_code ec, std::size_t) {
      if (ec) return self->on_read_error(ec);
      self->on_request();
    });
  }

  void on_request() {
    if (impl_->stopped) return close_now();
    beast::get_lowest_layer(stream_).expires_never();  // the handler may take its time
    handle(parser_->release());
  }

  // The options of the route the header's target and method match; nullptr
  // for none (or a target the request's handling will refuse anyway).
  const RouteOptions* route_options(const BeastRequest& req) const {
    auto parsed = boost::urls::parse_origin_form(req.target());
    if (!parsed) return nullptr;
    std::vector<std::string> segments;
    for (auto seg : parsed->segments()) segments.emplace_back(seg);
    auto m = impl_->router.match(std::string(req.method_string()), segments);
    return m.kind == Router::Match::Kind::Found ? m.options : nullptr;
  }

  void on_read_error(error_code ec) {
    if (ec == bhttp::error::body_limit) {
      keep_alive_ = false;
      send(Response::problem(413, "request body larger than " + std::to_string(body_limit_) + " bytes"));
    } else if (ec == bhttp::error::header_limit) {
      keep_alive_ = false;
      send(Response::problem(431, "request header too large"));
    } else if (ec.category() == bhttp::make_error_code(bhttp::error::end_of_stream).category() &&
               ec != bhttp::error::end_of_stream &&
               ec != bhttp::error::partial_message) {
      keep_alive_ = false;
      send(Response::problem(400, "malformed request: " + ec.message()));
    } else {
      close_now();  // end of stream, timeout, reset
    }
  }

  void write(BeastResponse&& res) override {
    res_ = std::move(res);
    expire_in(impl_->cfg.read_timeout);
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    bhttp::async_write(stream_, res_, [self](error_code ec, std::size_t) {
      if (ec) return self->close_now();
      if (!self->res_.keep_alive()) return self->graceful_close();
      self->res_ = {};
      self->read_request();
    });
  }

  void write_stream_head(std::unique_ptr<StreamHead> head) override {
    stream_head_ = std::move(head);
    stream_sr_.emplace(*stream_head_);
    expire_in(impl_->cfg.read_timeout);
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    bhttp::async_write_header(stream_, *stream_sr_, [self](error_code ec, std::size_t) {
      // The body takes as long as the route says; a client that does not
      // read only costs the sink's bound (the route drops beyond it).
      beast::get_lowest_layer(self->stream_).expires_never();
      self->stream_head_written(ec);
    });
  }

  void write_stream_bytes(std::string bytes, bool last) override {
    out_ = std::move(bytes);
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    auto done = [self](error_code ec, std::size_t) { self->stream_written(ec); };
    if (last) {
      // What is left to send must go out in time; then the close.
      expire_in(impl_->cfg.read_timeout);
      if (chunked_) return net::async_write(stream_, bhttp::make_chunk_last(), std::move(done));
      return net::post(impl_->ioc, [done] { done({}, 0); });
    }
    if (chunked_) return net::async_write(stream_, bhttp::make_chunk(net::buffer(out_)), std::move(done));
    net::async_write(stream_, net::buffer(out_), std::move(done));
  }

  void watch_client() override {
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    stream_.async_read_some(net::buffer(discard_), [self](error_code ec, std::size_t) {
      if (!ec && !self->ending_) return self->watch_client();  // pipelined bytes: ignored, the connection closes
      if (self->ending_) return self->close_now();
      self->stream_gone();
    });
  }

  void end_stream() override {
    // Half-close so the client reads it all; watch_client's read then ends
    // with the client's close (or the grace time).
    ending_ = true;
    out_ = {};
    expire_in(kCloseGrace);
    if constexpr (!std::is_same_v<Stream, TlsStream>) {
      error_code ignored;
      stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    }
  }

  void upgrade(BeastRequest&& req, bool binary, std::shared_ptr<StreamSource> source) override {
    beast::get_lowest_layer(stream_).expires_never();
    upgraded_ = true;
    start_websocket_session(impl_, slot_, std::move(stream_), binary, peer_, std::move(req), std::move(source));
  }

  // Half-closes so the client reads the whole response before the FIN (an
  // abrupt close with unread input would send a reset and could destroy it).
  void graceful_close() {
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    expire_in(kCloseGrace);
    if constexpr (std::is_same_v<Stream, TlsStream>) {
      stream_.async_shutdown([self](error_code) { self->close_now(); });
    } else {
      error_code ignored;
      stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
      drain();
    }
  }

  void drain() {
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    stream_.async_read_some(net::buffer(discard_), [self](error_code ec, std::size_t) {
      if (ec) return self->close_now();
      self->drain();
    });
  }

  void close_now() override {
    set_idle(false);
    if (upgraded_) return;  // the stream now belongs to the WebSocket session
    error_code ignored;
    beast::get_lowest_layer(stream_).socket().close(ignored);
    handler_timer_.cancel();  // a pending handler's late answer is then a no-op
    if (body_) body_->close();  // a streamed body's route stops producing
  }

  Stream stream_;
  beast::flat_buffer buffer_;
  std::optional<bhttp::request_parser<bhttp::string_body>> parser_;
  std::size_t body_limit_ = 0;  // of the request being read: the route's or the server's
  BeastResponse res_;
  std::array<char, 4096> discard_{};
  bool upgraded_ = false;
  // A streamed response: its header and serializer, the bytes being written.
  std::unique_ptr<StreamHead> stream_head_;
  std::optional<bhttp::response_serializer<bhttp::empty_body>> stream_sr_;
  std::string out_;
  bool ending_ = false;  // the end of the body is written; waiting for the client's close
};

}  // namespace

void start_http_session(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, tcp::socket socket, std::string peer) {
  if (impl->tls) {
    auto s = std::make_shared<HttpSession<TlsStream>>(impl, std::move(slot),
                                                      TlsStream(beast::tcp_stream(std::move(socket)), *impl->tls),
                                                      std::move(peer));
    s->run();
  } else {
    auto s = std::make_shared<HttpSession<beast::tcp_stream>>(std::move(impl), std::move(slot),
                                                              beast::tcp_stream(std::move(socket)), std::move(peer));
    s->run();
  }
}

}  // namespace gateway::http
