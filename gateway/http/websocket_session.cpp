// The WebSocket session of one stream type (TCP or TLS): handshake, reads,
// writes and the close; the rest is WsClient's (ws_client.cpp).
#include "http/websocket_session.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <string_view>
#include <utility>

#include "http/ws_client.hpp"

namespace gateway::http {

namespace {

template <class Stream>
class WsSession final : public WsClient {
 public:
  WsSession(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, Stream&& stream, bool binary, std::string peer)
      : WsClient(std::move(impl), std::move(slot), binary, std::move(peer)),
        ws_(std::move(stream)),
        kill_timer_(impl_->ioc) {}

  void run(BeastRequest req) {
    const auto& cfg = impl_->cfg;
    // The websocket stream's own timeouts replace tcp_stream's.
    beast::get_lowest_layer(ws_).expires_never();
    if (cfg.ws_socket_send_buffer > 0) {
      error_code ignored;
      beast::get_lowest_layer(ws_).socket().set_option(net::socket_base::send_buffer_size(cfg.ws_socket_send_buffer),
                                                       ignored);
    }
    websocket::stream_base::timeout t{};
    t.handshake_timeout = cfg.read_timeout;
    // Beast pings after idle_timeout/2 without incoming data and gives up
    // after idle_timeout.
    t.idle_timeout = cfg.ws_ping_interval * 2;
    t.keep_alive_pings = true;
    ws_.set_option(t);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(bhttp::field::server, "canopen-gateway"); }));
    ws_.read_message_max(cfg.ws_max_incoming_message);
    auto self = std::static_pointer_cast<WsSession>(shared_from_this());
    upgrade_req_ = std::move(req);  // must outlive the handshake
    ws_.async_accept(upgrade_req_, [self](error_code ec) {
      if (ec) {
        self->impl_->debug("ws handshake with " + self->peer_ + " failed: " + ec.message());
        self->closing_ = true;
        return;
      }
      if (self->impl_->stopped) {
        self->opened();
        self->shutdown();
        return;
      }
      self->opened();
      self->do_read();
    });
  }

 private:
  void do_read() {
    auto self = std::static_pointer_cast<WsSession>(shared_from_this());
    ws_.async_read(rbuf_, [self](error_code ec, std::size_t) {
      if (ec) {
        self->closed();
        self->kill_timer_.cancel();
        return;
      }
      if (self->ws_.got_text()) {
        const auto data = self->rbuf_.cdata();
        self->on_text_message(std::string_view(static_cast<const char*>(data.data()), data.size()));
      } else {
        self->on_binary_message();
      }
      self->rbuf_.consume(self->rbuf_.size());
      if (!self->closing_) self->do_read();
    });
  }

  void start_write(std::string_view payload, bool binary) override {
    ws_.binary(binary);
    auto self = std::static_pointer_cast<WsSession>(shared_from_this());
    ws_.async_write(net::buffer(payload.data(), payload.size()),
                    [self](error_code ec, std::size_t) { self->on_write(ec); });
  }

  void start_close(websocket::close_reason reason) override {
    auto self = std::static_pointer_cast<WsSession>(shared_from_this());
    // A stalled client never lets the close frame out (it waits behind a
    // blocked write): close the socket after a grace period.
    kill_timer_.expires_after(kCloseGrace);
    kill_timer_.async_wait([self](error_code ec) {
      if (!ec) self->force_close();
    });
    ws_.async_close(reason, [self](error_code) { self->kill_timer_.cancel(); });
  }

  void force_close() override {
    error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

  websocket::stream<Stream> ws_;
  BeastRequest upgrade_req_;
  beast::flat_buffer rbuf_;
  net::steady_timer kill_timer_;
};

template <class Stream>
void start_session(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, Stream&& stream, bool binary, std::string peer,
                   BeastRequest&& req, std::shared_ptr<StreamSource> source) {
  auto ws =
      std::make_shared<WsSession<Stream>>(std::move(impl), std::move(slot), std::move(stream), binary, std::move(peer));
  if (source) ws->set_source(std::move(source));
  ws->run(std::move(req));
}

}  // namespace

void start_websocket_session(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, beast::tcp_stream&& stream,
                             bool binary, std::string peer, BeastRequest&& req, std::shared_ptr<StreamSource> source) {
  start_session<beast::tcp_stream>(std::move(impl), std::move(slot), std::move(stream), binary, std::move(peer),
                                   std::move(req), std::move(source));
}

void start_websocket_session(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, TlsStream&& stream, bool binary,
                             std::string peer, BeastRequest&& req, std::shared_ptr<StreamSource> source) {
  start_session<TlsStream>(std::move(impl), std::move(slot), std::move(stream), binary, std::move(peer), std::move(req),
                           std::move(source));
}

}  // namespace gateway::http
