// HttpServer's own functions. The server's parts share HttpServer::Impl
// (server_impl.hpp): the listener (listener.cpp), the HTTP sessions
// (connection.cpp, http_session.cpp) and the WebSocket sessions
// (ws_client.cpp, websocket_session.cpp). Only the sessions' files
// instantiate Beast (HTTP, WebSocket, TLS): Beast is slow to compile, so
// everything else talks to it through http_server.hpp. Stream-independent
// logic lives in the non-template bases (Connection, WsClient) so the two
// stream types (TCP, TLS) duplicate as little code as possible.
#include "http/http_server.hpp"

#include <boost/asio/ssl.hpp>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "http/server_impl.hpp"
#include "http/ws_client.hpp"

namespace gateway::http {

HttpServer::HttpServer(boost::asio::io_context& ioc, HttpConfig config, Logger* log)
    : impl_(std::make_shared<Impl>(ioc, std::move(config), log)) {
  const auto& cfg = impl_->cfg;
  if (cfg.cert_file.empty() != cfg.key_file.empty())
    throw std::runtime_error("TLS needs both a certificate file and a key file");
  if (!cfg.cert_file.empty()) {
    impl_->tls.emplace(net::ssl::context::tls_server);
    auto& ctx = *impl_->tls;
    ctx.set_options(net::ssl::context::default_workarounds | net::ssl::context::no_sslv2 |
                    net::ssl::context::no_sslv3 | net::ssl::context::no_tlsv1 | net::ssl::context::no_tlsv1_1 |
                    net::ssl::context::single_dh_use);
    error_code ec;
    ctx.use_certificate_chain_file(cfg.cert_file.string(), ec);
    if (ec) throw std::runtime_error("TLS certificate " + cfg.cert_file.string() + ": " + ec.message());
    ctx.use_private_key_file(cfg.key_file.string(), net::ssl::context::pem, ec);
    if (ec) throw std::runtime_error("TLS key " + cfg.key_file.string() + ": " + ec.message());
  }
}

HttpServer::~HttpServer() {
  impl_->stop();
  // Connections may outlive *this; release what the routes captured.
  impl_->router = Router{};
  impl_->authorizer = nullptr;
}

void HttpServer::add_route(std::string method, std::string_view pattern, Handler handler, RouteOptions options) {
  if (pattern == kEventsPath) throw std::invalid_argument("route " + std::string(pattern) + " is the event stream's");
  impl_->router.add(std::move(method), pattern, std::move(handler), std::move(options));
}

std::size_t HttpServer::binary_clients() const {
  return static_cast<std::size_t>(impl_->counters.ws_binary_clients.load(std::memory_order_relaxed));
}

void HttpServer::add_stream_route(std::string_view pattern, StreamHandler handler) {
  if (pattern == kEventsPath) throw std::invalid_argument("route " + std::string(pattern) + " is the event stream's");
  impl_->stream_router.add("GET", pattern, [](const Request&, Responder) {});
  impl_->streams.emplace(std::string(pattern), std::move(handler));
}

std::vector<std::pair<std::string, std::string>> HttpServer::routes() const {
  auto all = impl_->router.list();
  for (auto& r : impl_->stream_router.list()) all.push_back(std::move(r));
  return all;
}

void HttpServer::set_authorizer(Authorizer authorizer) { impl_->authorizer = std::move(authorizer); }

void HttpServer::start() {
  auto& i = *impl_;
  if (i.started) return;
  // std::system_error with the errno and the step, not Boost's exception
  // with its source location: the caller words it for people (main.cpp).
  error_code ec;
  const auto check = [&](const char* step) {
    if (!ec) return;
    if (i.acceptor.is_open()) {
      error_code ignored;
      i.acceptor.close(ignored);
    }
    throw std::system_error(std::error_code(ec.value(), std::generic_category()), step);
  };
  const auto addr = net::ip::make_address(i.cfg.address, ec);
  check("address");
  const tcp::endpoint ep(addr, i.cfg.port);
  i.acceptor.open(ep.protocol(), ec);
  check("socket");
  i.acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  check("setsockopt");
  i.acceptor.bind(ep, ec);
  check("bind");
  i.acceptor.listen(net::socket_base::max_listen_connections, ec);
  check("listen");
  i.port = i.acceptor.local_endpoint().port();
  i.started = true;
  i.debug("listening on " + endpoint_string(i.acceptor.local_endpoint()) + (i.tls ? " (TLS)" : ""));
  i.do_accept();
}

void HttpServer::stop() { impl_->stop(); }

std::uint16_t HttpServer::bound_port() const { return impl_->port.load(); }

void HttpServer::publish(const EncodedEventPtr& event) {
  auto& i = *impl_;
  if (!event || i.ws_clients.empty()) return;
  // Copy first: a delivery may end a client, which unregisters itself.
  auto& clients = i.publish_scratch;
  clients.clear();
  for (auto& [id, w] : i.ws_clients)
    if (auto c = w.lock()) clients.push_back(std::move(c));
  for (auto& c : clients) c->deliver(event);
  clients.clear();
}

HttpStats HttpServer::stats() const {
  const auto& c = impl_->counters;
  HttpStats s;
  s.connections_accepted = c.accepted.load(std::memory_order_relaxed);
  s.connections_rejected_per_address = c.rejected_per_address.load(std::memory_order_relaxed);
  s.connections_rejected_full = c.rejected_full.load(std::memory_order_relaxed);
  s.connections_rejected = s.connections_rejected_per_address + s.connections_rejected_full;
  s.connections_evicted_idle = c.evicted_idle.load(std::memory_order_relaxed);
  s.connections_active = c.active.load(std::memory_order_relaxed);
  s.connections_idle = c.idle.load(std::memory_order_relaxed);
  s.header_timeouts = c.header_timeouts.load(std::memory_order_relaxed);
  s.refused_framing = c.refused_framing.load(std::memory_order_relaxed);
  s.refused_host = c.refused_host.load(std::memory_order_relaxed);
  s.refused_origin = c.refused_origin.load(std::memory_order_relaxed);
  s.refused_media_type = c.refused_media_type.load(std::memory_order_relaxed);
  s.tls_handshake_failures = c.tls_failures.load(std::memory_order_relaxed);
  s.ws_clients = c.ws_clients.load(std::memory_order_relaxed);
  s.ws_clients_total = c.ws_total.load(std::memory_order_relaxed);
  s.ws_messages_sent = c.ws_sent.load(std::memory_order_relaxed);
  s.ws_messages_dropped = c.ws_dropped.load(std::memory_order_relaxed);
  s.ws_clients_closed_slow = c.ws_closed_slow.load(std::memory_order_relaxed);
  for (std::size_t st = 100; st < c.by_status.size(); ++st)
    if (auto n = c.by_status[st].load(std::memory_order_relaxed)) s.responses_by_status[static_cast<int>(st)] = n;
  return s;
}

}  // namespace gateway::http
