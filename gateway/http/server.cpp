// The only translation unit that instantiates Beast (HTTP, WebSocket, TLS):
// Beast is slow to compile, so everything else talks to it through
// http_server.hpp. Stream-independent logic lives in the non-template bases
// (Connection, WsClient) so the two stream types (TCP, TLS) duplicate as
// little code as possible.
#include "http_server.hpp"

#include <array>
#include <atomic>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <boost/url/parse.hpp>
#include <boost/url/url_view.hpp>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <unistd.h>
#include <unordered_map>

#include "event_stream.hpp"
#include "log.hpp"
#include "request_checks.hpp"
#include "router.hpp"
#include "static_files.hpp"

namespace gateway::http {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace bhttp = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using error_code = boost::system::error_code;
using BeastRequest = bhttp::request<bhttp::string_body>;
using BeastResponse = bhttp::response<bhttp::string_body>;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

namespace {

constexpr std::string_view kEventsPath = "/api/v1/events";
constexpr auto kCloseGrace = std::chrono::seconds(2);
// A refusal of connections is logged once per episode: again only after
// this long without refusals for that address (or for the full server).
constexpr auto kRefusalQuiet = std::chrono::seconds(60);
// First read of a request: whatever has arrived, up to this much.
constexpr std::size_t kFirstRead = 4096;

using SteadyTime = std::chrono::steady_clock::time_point;

struct Counters {
  std::atomic<std::uint64_t> accepted{0}, active{0}, tls_failures{0};
  std::atomic<std::uint64_t> rejected_per_address{0}, rejected_full{0}, evicted_idle{0}, idle{0}, header_timeouts{0};
  std::atomic<std::uint64_t> refused_framing{0}, refused_host{0}, refused_origin{0}, refused_media_type{0};
  std::atomic<std::uint64_t> ws_binary_clients{0};
  std::atomic<std::uint64_t> ws_clients{0}, ws_total{0}, ws_sent{0}, ws_dropped{0}, ws_closed_slow{0};
  std::array<std::atomic<std::uint64_t>, 600> by_status{};
  void count_status(int status) {
    if (status >= 100 && status < 600) by_status[static_cast<std::size_t>(status)].fetch_add(1, std::memory_order_relaxed);
  }
};

// Something stop() can close.
class Closable {
 public:
  virtual ~Closable() = default;
  virtual void shutdown() = 0;
  // Since when it has been waiting for a request (nullopt: busy, or not an
  // HTTP connection): such a connection may be closed for a new one.
  virtual std::optional<SteadyTime> idle_since() const { return std::nullopt; }
};

// The key of a client address for the per-address limit (an IPv4 client of
// a dual-stack listener counts as its IPv4 address).
std::string address_key(const net::ip::address& a) {
  if (a.is_v6() && a.to_v6().is_v4_mapped()) return net::ip::make_address_v4(net::ip::v4_mapped, a.to_v6()).to_string();
  return a.to_string();
}

std::string endpoint_string(const tcp::endpoint& ep) {
  const auto addr = ep.address();
  std::string s = addr.is_v6() ? "[" + addr.to_string() + "]" : addr.to_string();
  return s + ":" + std::to_string(ep.port());
}

bool iequals(std::string_view a, std::string_view b) { return beast::iequals(a, b); }

}  // namespace

class WsClient;

struct HttpServer::Impl : std::enable_shared_from_this<HttpServer::Impl> {
  Impl(net::io_context& io, HttpConfig c, Logger* l)
      : ioc(io), cfg(std::move(c)), log(l), policy(policy_settings(cfg)), acceptor(io), accept_timer(io) {}

  static OriginPolicy::Settings policy_settings(const HttpConfig& c) {
    std::array<char, 256> name{};
    if (::gethostname(name.data(), name.size() - 1) != 0) name[0] = '\0';
    return {c.address, c.host_names, c.allowed_origins, std::string(name.data())};
  }

  net::io_context& ioc;
  HttpConfig cfg;
  Logger* log;
  OriginPolicy policy;
  std::optional<net::ssl::context> tls;
  tcp::acceptor acceptor;
  net::steady_timer accept_timer;  // back-off after EMFILE and the like
  Router router;
  // WebSocket routes served by a StreamSource: matched by stream_router
  // (whose handlers are never called), answered by streams[pattern].
  Router stream_router;
  std::map<std::string, StreamHandler, std::less<>> streams;
  Authorizer authorizer;
  Counters counters;
  std::atomic<std::uint16_t> port{0};
  bool started = false;
  bool stopped = false;
  std::uint64_t next_id = 1;
  std::unordered_map<std::uint64_t, std::weak_ptr<Closable>> connections;
  std::unordered_map<std::uint64_t, std::weak_ptr<WsClient>> ws_clients;
  std::vector<std::shared_ptr<WsClient>> publish_scratch;
  // Open connections (HTTP and WebSocket) per client address (address_key).
  std::unordered_map<std::string, std::size_t> per_address;
  // Refusal episodes: client address ("" = server full) -> last refusal.
  std::unordered_map<std::string, SteadyTime> refusing;

  void debug(const std::string& m) {
    if (log && log->enabled(LogLevel::Debug)) log->debug("http: " + m);
  }
  void do_accept();
  void on_accept(error_code ec, tcp::socket socket);
  bool evict_idle();
  void note_refusal(const std::string& key, const std::string& message);
  void stop();
};

namespace {

// One connection's place in its client address's count, from accept to
// close; the HTTP session hands it on to the WebSocket session it becomes.
class AddressSlot {
 public:
  AddressSlot(std::shared_ptr<HttpServer::Impl> impl, std::string address)
      : impl_(std::move(impl)), address_(std::move(address)) {
    ++impl_->per_address[address_];
  }
  ~AddressSlot() {
    auto it = impl_->per_address.find(address_);
    if (it != impl_->per_address.end() && --it->second == 0) impl_->per_address.erase(it);
  }
  AddressSlot(const AddressSlot&) = delete;
  AddressSlot& operator=(const AddressSlot&) = delete;

 private:
  std::shared_ptr<HttpServer::Impl> impl_;
  std::string address_;
};

using SlotPtr = std::shared_ptr<AddressSlot>;

}  // namespace

namespace {

// ---------------------------------------------------------------------------
// WebSocket client: queue, filter and policy (stream independent).

}  // namespace

class WsClient : public Closable, public std::enable_shared_from_this<WsClient> {
 public:
  WsClient(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, bool binary, std::string peer)
      : impl_(std::move(impl)),
        slot_(std::move(slot)),
        binary_(binary),
        peer_(std::move(peer)),
        queue_(SendQueue::Limits{impl_->cfg.ws_queue_max_messages, impl_->cfg.ws_queue_max_bytes,
                                 impl_->cfg.ws_stall_timeout}),
        id_(impl_->next_id++) {
    impl_->counters.active.fetch_add(1, std::memory_order_relaxed);
  }
  ~WsClient() override {
    release_source();
    impl_->connections.erase(id_);
    impl_->ws_clients.erase(id_);
    if (registered_) impl_->counters.ws_clients.fetch_sub(1, std::memory_order_relaxed);
    if (registered_ && binary_) impl_->counters.ws_binary_clients.fetch_sub(1, std::memory_order_relaxed);
    impl_->counters.active.fetch_sub(1, std::memory_order_relaxed);
  }

  void deliver(const EncodedEventPtr& ev) {
    if (!open_ || closing_ || !filter_.matches(*ev)) return;
    // Encoded without protobuf (nobody wanted it when it was encoded, e.g.
    // just before this client connected): nothing to send it.
    if (binary_ && ev->binary.empty() && ev->ws_binary.empty()) return;
    push(SendQueue::Item{ev, {}, binary_});
  }

  void shutdown() override { begin_close(websocket::close_reason(websocket::close_code::going_away, "server stopping")); }

  // Serve `source` instead of the event stream (before run()).
  void set_source(std::shared_ptr<StreamSource> source) { source_ = std::move(source); }

 protected:
  // Called once the handshake succeeded.
  void opened() {
    open_ = true;
    registered_ = true;
    impl_->connections.emplace(id_, weak_from_this());
    if (source_) {
      source_->wake = [w = weak_from_this()] {
        if (auto self = w.lock()) self->maybe_write();
      };
    } else {
      impl_->ws_clients.emplace(id_, weak_from_this());  // publish() reaches it
    }
    impl_->counters.ws_clients.fetch_add(1, std::memory_order_relaxed);
    if (binary_) impl_->counters.ws_binary_clients.fetch_add(1, std::memory_order_relaxed);
    impl_->counters.ws_total.fetch_add(1, std::memory_order_relaxed);
    impl_->counters.count_status(101);
    impl_->debug("ws client " + peer_ + " connected" + (binary_ ? " (protobuf)" : ""));
    if (source_) maybe_write();  // what the source queued during the handshake
  }

  void on_text_message(std::string_view text) {
    if (source_) {
      source_->on_message(text);
      maybe_write();
      return;
    }
    std::string error;
    std::string reply;
    if (filter_.parse(text, error)) {
      reply = "{\"subscribed\":" + filter_.to_json() + "}";
    } else {
      reply = "{\"error\":" + Response::problem(400, error).body + "}";
    }
    push(SendQueue::Item{nullptr, std::move(reply), false});
  }
  void on_binary_message() {
    if (source_) {
      source_->on_message("binary frame");  // not JSON: the source answers with its error
      maybe_write();
      return;
    }
    push(SendQueue::Item{
        nullptr, "{\"error\":" + Response::problem(400, "filter messages are JSON text frames").body + "}", false});
  }

  void push(SendQueue::Item item) {
    if (closing_) return;
    const auto before = queue_.dropped();
    const auto r = queue_.push(std::move(item), std::chrono::steady_clock::now());
    impl_->counters.ws_dropped.fetch_add(queue_.dropped() - before, std::memory_order_relaxed);
    if (r == SendQueue::Result::Close) {
      impl_->counters.ws_closed_slow.fetch_add(1, std::memory_order_relaxed);
      impl_->debug("ws client " + peer_ + " too slow, closing (dropped " + std::to_string(queue_.dropped()) + ")");
      begin_close(websocket::close_reason(websocket::close_code::policy_error, "slow consumer"));
      return;
    }
    maybe_write();
  }

  void maybe_write() {
    if (source_ && !writing_ && !closing_ && open_) {
      source_msg_ = source_->next();
      if (!source_msg_) return;
      writing_ = true;
      start_write(*source_msg_, false);
      return;
    }
    if (writing_ || closing_ || queue_.empty()) return;
    current_ = queue_.pop();
    writing_ = true;
    start_write(current_.payload(), current_.binary);
  }

  void on_write(error_code ec) {
    writing_ = false;
    current_ = {};
    source_msg_.reset();
    if (ec) {
      closed();
      return;
    }
    impl_->counters.ws_sent.fetch_add(1, std::memory_order_relaxed);
    maybe_write();
  }

  void begin_close(websocket::close_reason reason) {
    if (closing_) return;
    closing_ = true;
    queue_.clear();
    release_source();
    if (!open_) {
      force_close();
      return;
    }
    start_close(reason);
  }

  // The connection is gone (read or write failed, or closed).
  void closed() {
    closing_ = true;
    queue_.clear();
    release_source();
    if (open_) {
      open_ = false;
      impl_->ws_clients.erase(id_);
    }
  }

  void release_source() {
    if (!source_ || source_released_) return;
    source_released_ = true;
    source_->wake = nullptr;
    source_->on_close();
  }

  virtual void start_write(std::string_view payload, bool binary) = 0;
  // Sends a close frame, closing the socket if that takes too long.
  virtual void start_close(websocket::close_reason reason) = 0;
  virtual void force_close() = 0;

  std::shared_ptr<HttpServer::Impl> impl_;
  SlotPtr slot_;
  bool binary_;
  std::string peer_;
  SendQueue queue_;
  EventFilter filter_;
  SendQueue::Item current_;  // being written; kept alive for the write
  std::shared_ptr<StreamSource> source_;          // a stream route's client: messages from here
  std::shared_ptr<const std::string> source_msg_;  // being written
  bool source_released_ = false;
  bool open_ = false;
  bool closing_ = false;
  bool writing_ = false;
  bool registered_ = false;
  std::uint64_t id_;
};

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

}  // namespace

// ---------------------------------------------------------------------------
// HTTP connection: request -> route -> response (stream independent).

namespace {

class Connection;

// State shared between a pending request and its Responder.
struct PendingReply {
  std::weak_ptr<Connection> conn;
  std::atomic<bool> done{false};
};

// The sink of a streamed response: what the route wrote and the
// connection has not yet taken (at most `limit` bytes, plus the bytes in
// flight), finished or not, closed or not. The connection pulls from it.
class StreamBody final : public BodySink {
 public:
  StreamBody(std::weak_ptr<Connection> conn, std::size_t limit) : conn_(std::move(conn)), limit_(limit) {}

  bool write(std::string_view bytes) override {
    if (closed_ || finished_) return false;
    if (bytes.empty()) return true;
    // One piece larger than the bound still goes when nothing waits.
    if (waiting() > 0 && waiting() + bytes.size() > limit_) return false;
    pending_.append(bytes);
    kick();
    return true;
  }
  void finish(std::string_view tail) override {
    if (closed_ || finished_) return;
    finished_ = true;
    on_close = nullptr;
    pending_.append(tail);
    kick();
  }
  bool closed() const override { return closed_; }

  // Connection side.
  std::size_t waiting() const { return pending_.size() + in_flight_; }
  bool finished() const { return finished_; }
  // The bytes to write next (all that waits), counted until written().
  std::string take() {
    std::string out;
    out.swap(pending_);
    in_flight_ = out.size();
    return out;
  }
  void written() { in_flight_ = 0; }
  void close() {
    if (closed_) return;
    closed_ = true;
    pending_ = {};
    in_flight_ = 0;
    if (auto f = std::move(on_close)) {
      on_close = nullptr;
      f();
    }
  }

 private:
  void kick();

  std::weak_ptr<Connection> conn_;
  std::size_t limit_;
  std::string pending_;
  std::size_t in_flight_ = 0;
  bool finished_ = false;
  bool closed_ = false;
};

class Connection : public Closable, public std::enable_shared_from_this<Connection> {
 public:
  Connection(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, std::string peer, bool tls)
      : impl_(std::move(impl)),
        slot_(std::move(slot)),
        peer_(std::move(peer)),
        tls_(tls),
        handler_timer_(impl_->ioc),
        id_(impl_->next_id++) {
    impl_->connections.emplace(id_, std::weak_ptr<Closable>());
  }
  ~Connection() override {
    if (body_) body_->close();
    set_idle(false);
    impl_->connections.erase(id_);
    impl_->counters.active.fetch_sub(1, std::memory_order_relaxed);
  }

  void registered() { impl_->connections[id_] = weak_from_this(); }

  std::optional<SteadyTime> idle_since() const override { return idle_since_; }

  // Sends `r` for the current request; ignored when it is not `pending`.
  void reply(const std::shared_ptr<PendingReply>& pending, Response r) {
    if (pending != pending_) return;
    pending_.reset();
    handler_timer_.cancel();
    send(std::move(r));
  }

 protected:
  // Waiting for a request (true) or not. Staying idle keeps the first time.
  void set_idle(bool idle) {
    if (idle == idle_since_.has_value()) return;
    if (idle) {
      idle_since_ = std::chrono::steady_clock::now();
      impl_->counters.idle.fetch_add(1, std::memory_order_relaxed);
    } else {
      idle_since_.reset();
      impl_->counters.idle.fetch_sub(1, std::memory_order_relaxed);
    }
  }

  // The checks a request's header must pass before its body is read: a
  // refusal to send (the caller then closes the connection), or nullopt.
  std::optional<Response> screen(const BeastRequest& breq) {
    auto& c = impl_->counters;
    HeaderFields fields;
    for (const auto& f : breq) fields.emplace_back(f.name_string(), f.value());
    if (auto why = framing_error(fields, breq.version())) {
      c.refused_framing.fetch_add(1, std::memory_order_relaxed);
      return Response::problem(400, "malformed request: " + *why);
    }
    std::optional<std::string_view> host;
    if (auto it = breq.find(bhttp::field::host); it != breq.end()) host = it->value();
    switch (impl_->policy.check_host(host, breq.version())) {
      case OriginPolicy::HostVerdict::Own:
        break;
      case OriginPolicy::HostVerdict::Missing:
        c.refused_host.fetch_add(1, std::memory_order_relaxed);
        return Response::problem(400, "an HTTP/1.1 request needs a Host header");
      case OriginPolicy::HostVerdict::Malformed:
        c.refused_host.fetch_add(1, std::memory_order_relaxed);
        return Response::problem(400, "malformed Host header");
      case OriginPolicy::HostVerdict::Foreign:
        c.refused_host.fetch_add(1, std::memory_order_relaxed);
        impl_->debug("request from " + peer_ + " for host '" + std::string(*host) + "' refused");
        return Response::problem(421, "this server does not answer for host '" + std::string(*host) +
                                          "' (its listen address, or a name in http.host-names)");
    }
    // Browsers send Origin on these; a page from elsewhere may not act on
    // the gateway or read its event stream.
    if (is_state_changing(breq.method_string()) || websocket::is_upgrade(breq)) {
      if (auto it = breq.find(bhttp::field::origin);
          it != breq.end() && !impl_->policy.origin_allowed(it->value(), host, tls_)) {
        c.refused_origin.fetch_add(1, std::memory_order_relaxed);
        impl_->debug("request from " + peer_ + " with origin '" + std::string(it->value()) + "' refused");
        return Response::problem(403, "cross-origin request from '" + std::string(it->value()) +
                                          "' refused (not this server, nor in http.allowed-origins)");
      }
    }
    return std::nullopt;
  }

  void handle(BeastRequest&& breq) {
    keep_alive_ = breq.keep_alive();
    head_ = breq.method() == bhttp::verb::head;
    version_ = breq.version();

    auto req = std::make_shared<Request>();
    req->method = std::string(breq.method_string());
    req->target = std::string(breq.target());
    req->peer = peer_;
    req->tls = tls_;
    for (const auto& f : breq) {
      std::string name(f.name_string());
      for (auto& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      req->headers.emplace_back(std::move(name), std::string(f.value()));
    }
    auto parsed = boost::urls::parse_origin_form(req->target);
    if (!parsed) {
      keep_alive_ = false;
      send(Response::problem(400, "malformed request target"));
      return;
    }
    const boost::urls::url_view& url = *parsed;
    req->path = std::string(url.path());
    std::vector<std::string> segments;
    for (auto s : url.segments()) segments.emplace_back(s);
    // "/a/" is {"a", ""}: keep the empty segment, so it stays a different path.
    for (auto p : url.params(boost::urls::encoding_opts(true, false, false)))
      req->query.emplace_back(p.key, p.has_value ? p.value : std::string());

    if (auto sm = impl_->stream_router.match(req->method, segments); sm.kind == Router::Match::Kind::Found) {
      if (!websocket::is_upgrade(breq)) {
        Response r = Response::problem(426, "this path is a WebSocket endpoint");
        r.headers.emplace_back("Upgrade", "websocket");
        send(std::move(r));
        return;
      }
      req->params = std::move(sm.params);
      req->route = std::move(sm.pattern);
      handle_stream_upgrade(std::move(breq), *req);
      return;
    }
    if (req->path == kEventsPath) {
      if (!websocket::is_upgrade(breq)) {
        Response r = Response::problem(426, "this path is a WebSocket endpoint");
        r.headers.emplace_back("Upgrade", "websocket");
        send(std::move(r));
        return;
      }
      req->route = std::string(kEventsPath);
      handle_upgrade(std::move(breq), *req);
      return;
    }
    req->body = std::move(breq.body());

    auto m = impl_->router.match(req->method, segments);
    if (m.kind == Router::Match::Kind::Found) {
      req->params = std::move(m.params);
      req->route = std::move(m.pattern);
      // A form or a text/plain fetch is a "simple" cross-site request even
      // for browsers that send no Origin: the API reads only its own types.
      const auto& extra = m.options->body_types;
      if (is_state_changing(req->method) &&
          !acceptable_body_type(req->header("content-type"), !req->body.empty(), extra)) {
        impl_->counters.refused_media_type.fetch_add(1, std::memory_order_relaxed);
        std::string types = "application/json, application/x-protobuf";
        for (const auto& e : extra) types += ", " + e;
        Response r = Response::problem(415, "the body of " + req->method + " " + req->path + " must be one of " + types);
        r.headers.emplace_back("Accept", types);
        send(std::move(r));
        return;
      }
      if (auto denied = authorize(*req)) {
        send(std::move(*denied));
        return;
      }
      run_handler(*m.handler, std::move(req), m.options->handler_timeout.value_or(impl_->cfg.handler_timeout));
      return;
    }
    const auto& cfg = impl_->cfg;
    if (m.kind == Router::Match::Kind::NotFound && !cfg.static_dir.empty() && is_static_path(segments)) {
      if (req->method != "GET" && req->method != "HEAD") {
        Response r = Response::problem(405, "static files are read with GET");
        r.headers.emplace_back("Allow", "GET, HEAD");
        send(std::move(r));
        return;
      }
      if (auto denied = authorize(*req)) {
        send(std::move(*denied));
        return;
      }
      Response r;
      if (load_static_file(cfg.static_dir, segments, cfg.max_static_file_bytes, r.body, r.content_type) ==
          StaticResult::Ok) {
        r.headers.emplace_back("Cache-Control", "no-cache");
        // The dashboard loads only its own files and talks only to this
        // server (REST and the WebSocket); no inline script.
        r.headers.emplace_back("Content-Security-Policy",
                               "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
                               "connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'self'");
        send(std::move(r));
      } else {
        send(Response::problem(404, "no such file: " + req->path));
      }
      return;
    }
    if (m.kind == Router::Match::Kind::MethodNotAllowed) {
      Response r = Response::problem(405, "method " + req->method + " is not allowed on " + req->path);
      r.headers.emplace_back("Allow", m.allow);
      send(std::move(r));
      return;
    }
    send(Response::problem(404, "no such resource: " + req->path));
  }

  std::optional<Response> authorize(Request& req) {
    if (!impl_->authorizer) return std::nullopt;
    try {
      auto denied = impl_->authorizer(req);
      req.authorized = !denied;
      return denied;
    } catch (const std::exception& e) {
      impl_->debug(std::string("authorizer threw: ") + e.what());
      return Response::problem(500, "authorization failed");
    }
  }

  // `timeout` zero: no handler timer (the route answers by itself).
  void run_handler(const Handler& handler, std::shared_ptr<Request> req, std::chrono::milliseconds timeout) {
    auto pending = std::make_shared<PendingReply>();
    pending->conn = weak_from_this();
    pending_ = pending;
    net::io_context& ioc = impl_->ioc;
    Responder responder = [pending, req, &ioc](Response r) {
      if (pending->done.exchange(true)) return;
      net::dispatch(ioc, [pending, r = std::move(r)]() mutable {
        if (auto c = pending->conn.lock()) c->reply(pending, std::move(r));
      });
    };
    auto self = shared_from_this();
    // The wait also keeps the connection alive while the handler runs; with
    // no timeout it never expires (reply() cancels it).
    if (timeout.count() > 0) {
      handler_timer_.expires_after(timeout);
    } else {
      handler_timer_.expires_at(SteadyTime::max());
    }
    handler_timer_.async_wait([self, pending](error_code ec) {
      if (ec || pending->done.exchange(true)) return;
      self->impl_->debug("handler for " + self->peer_ + " did not answer in time");
      self->reply(pending, Response::problem(500, "the request handler did not answer in time"));
    });
    try {
      handler(*req, std::move(responder));
    } catch (const std::exception& e) {
      impl_->debug(std::string("handler threw: ") + e.what());
      if (!pending->done.exchange(true)) reply(pending, Response::problem(500, "internal error"));
    }
  }

  void handle_upgrade(BeastRequest&& breq, Request& req) {
    keep_alive_ = false;  // any answer but 101 ends the connection
    // Host and Origin: checked with the header (screen()).
    if (auto denied = authorize(req)) {
      send(std::move(*denied));
      return;
    }
    bool binary = false;
    if (auto f = req.query_param("format")) {
      if (*f == "protobuf") {
        binary = true;
      } else if (*f != "json") {
        send(Response::problem(400, "format must be json or protobuf"));
        return;
      }
    }
    if (impl_->stopped) {
      send(Response::problem(503, "server stopping"));
      return;
    }
    upgrade(std::move(breq), binary, nullptr);
  }

  void handle_stream_upgrade(BeastRequest&& breq, Request& req) {
    keep_alive_ = false;
    if (auto denied = authorize(req)) {
      send(std::move(*denied));
      return;
    }
    if (impl_->stopped) {
      send(Response::problem(503, "server stopping"));
      return;
    }
    StreamAccept accept;
    try {
      accept = impl_->streams.find(req.route)->second(req);
    } catch (const std::exception& e) {
      impl_->debug(std::string("stream handler threw: ") + e.what());
      send(Response::problem(500, "internal error"));
      return;
    }
    if (!accept.source) {
      send(std::move(accept.refusal));
      return;
    }
    upgrade(std::move(breq), false, std::move(accept.source));
  }

  // Status line and header fields every answer carries.
  void fill_head(bhttp::response_header<>& res, const Response& r) const {
    res.version(version_ == 10 ? 10 : 11);
    res.result(static_cast<unsigned>(r.status));
    res.set(bhttp::field::server, "canopen-gateway");
    if (!r.body.empty() || r.status >= 200) res.set(bhttp::field::content_type, r.content_type);
    // Defaults a route may override: API answers are live data (never
    // cached by a proxy or browser), nothing is sniffed, framed or told
    // where it came from; over TLS browsers keep to HTTPS.
    res.set(bhttp::field::cache_control, "no-store");
    res.set("X-Content-Type-Options", "nosniff");
    res.set("X-Frame-Options", "DENY");
    res.set("Referrer-Policy", "no-referrer");
    if (tls_) res.set("Strict-Transport-Security", "max-age=31536000");
    for (const auto& [k, v] : r.headers) res.set(k, v);
  }

  // Builds the Beast response and hands it to the stream.
  void send(Response r) {
    if (r.stream) {
      keep_alive_ = false;  // a streamed body ends with the connection
      if (!head_) return start_stream(std::move(r));
    }
    impl_->counters.count_status(r.status);
    BeastResponse res;
    fill_head(res, r);
    res.keep_alive(keep_alive_ && !impl_->stopped);
    res.body() = std::move(r.body);
    res.prepare_payload();
    if (head_) res.body().clear();  // Content-Length stays that of the GET
    write(std::move(res));
  }

  // The header now, the body as the route writes it to the sink: chunked
  // for HTTP/1.1, raw until the close for HTTP/1.0.
  void start_stream(Response r) {
    impl_->counters.count_status(r.status);
    auto head = std::make_unique<StreamHead>();
    fill_head(*head, r);
    head->keep_alive(false);
    chunked_ = version_ != 10;
    head->chunked(chunked_);
    body_ = std::make_shared<StreamBody>(weak_from_this(), r.stream_buffer_bytes);
    write_stream_head(std::move(head));
    try {
      r.stream(body_);  // what it writes now waits for the header to go out
    } catch (const std::exception& e) {
      impl_->debug(std::string("stream handler threw: ") + e.what());
      body_->finish({});
    }
  }

 public:
  // Writes what the sink holds, one write at a time; after a finished
  // sink's last bytes, the end of the body.
  void pump_stream() {
    if (!body_ || !stream_started_ || stream_writing_ || body_->closed() || stream_ended_) return;
    if (body_->waiting() > 0) {
      stream_writing_ = true;
      write_stream_bytes(body_->take(), false);
    } else if (body_->finished()) {
      stream_writing_ = true;
      stream_ended_ = true;
      write_stream_bytes({}, true);
    }
  }

 protected:
  // The stream's write of the header or of bytes completed.
  void stream_written(error_code ec) {
    stream_writing_ = false;
    if (ec) return stream_gone();
    if (body_) body_->written();
    if (stream_ended_) return end_stream();
    pump_stream();
  }
  void stream_head_written(error_code ec) {
    if (ec) return stream_gone();
    stream_started_ = true;
    watch_client();
    pump_stream();
  }
  // The client went away (or a write failed): free the sink, tell the route.
  void stream_gone() {
    if (body_) body_->close();
    close_now();
  }

  using StreamHead = bhttp::response<bhttp::empty_body>;
  virtual void write(BeastResponse&& res) = 0;
  virtual void write_stream_head(std::unique_ptr<StreamHead> head) = 0;
  // `bytes` as the body's next piece, or (last) the end of the body.
  virtual void write_stream_bytes(std::string bytes, bool last) = 0;
  // Reads (and discards) until the client closes: how a client that went
  // away is noticed while the body is quiet.
  virtual void watch_client() = 0;
  // After the end of the body: close once the client has read it.
  virtual void end_stream() = 0;
  virtual void close_now() = 0;
  virtual void upgrade(BeastRequest&& req, bool binary, std::shared_ptr<StreamSource> source) = 0;

  std::shared_ptr<HttpServer::Impl> impl_;
  SlotPtr slot_;
  std::string peer_;
  bool tls_;
  std::optional<SteadyTime> idle_since_;
  bool keep_alive_ = true;
  bool head_ = false;
  unsigned version_ = 11;
  std::shared_ptr<PendingReply> pending_;
  net::steady_timer handler_timer_;
  std::uint64_t id_;
  // A streamed response (start_stream).
  std::shared_ptr<StreamBody> body_;
  bool chunked_ = true;
  bool stream_started_ = false;  // the header is out
  bool stream_writing_ = false;
  bool stream_ended_ = false;    // the end of the body is written or being written
};

void StreamBody::kick() {
  if (auto c = conn_.lock()) c->pump_stream();
}

template <class Stream>
class HttpSession final : public Connection {
 public:
  HttpSession(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, Stream&& stream, std::string peer)
      : Connection(std::move(impl), std::move(slot), std::move(peer), std::is_same_v<Stream, TlsStream>),
        stream_(std::move(stream)) {}

  void run() {
    registered();
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    if constexpr (std::is_same_v<Stream, TlsStream>) {
      set_idle(true);  // no request yet; whether a handshake has begun is unknown
      beast::get_lowest_layer(stream_).expires_after(impl_->cfg.read_timeout);
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
    beast::get_lowest_layer(stream_).expires_after(impl_->cfg.idle_timeout);
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
    beast::get_lowest_layer(stream_).expires_after(impl_->cfg.header_timeout);
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
    beast::get_lowest_layer(stream_).expires_after(impl_->cfg.read_timeout);
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
    beast::get_lowest_layer(stream_).expires_after(impl_->cfg.read_timeout);
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
    beast::get_lowest_layer(stream_).expires_after(impl_->cfg.read_timeout);
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
      beast::get_lowest_layer(stream_).expires_after(impl_->cfg.read_timeout);
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
    beast::get_lowest_layer(stream_).expires_after(kCloseGrace);
    if constexpr (!std::is_same_v<Stream, TlsStream>) {
      error_code ignored;
      stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    }
  }

  void upgrade(BeastRequest&& req, bool binary, std::shared_ptr<StreamSource> source) override {
    beast::get_lowest_layer(stream_).expires_never();
    upgraded_ = true;
    auto ws = std::make_shared<WsSession<Stream>>(impl_, slot_, std::move(stream_), binary, peer_);
    if (source) ws->set_source(std::move(source));
    ws->run(std::move(req));
  }

  // Half-closes so the client reads the whole response before the FIN (an
  // abrupt close with unread input would send a reset and could destroy it).
  void graceful_close() {
    auto self = std::static_pointer_cast<HttpSession>(shared_from_this());
    beast::get_lowest_layer(stream_).expires_after(kCloseGrace);
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

// ---------------------------------------------------------------------------
// Server.

void HttpServer::Impl::do_accept() {
  auto self = shared_from_this();
  acceptor.async_accept([self](error_code ec, tcp::socket socket) { self->on_accept(ec, std::move(socket)); });
}

void HttpServer::Impl::on_accept(error_code ec, tcp::socket socket) {
  if (stopped || ec == net::error::operation_aborted) return;
  if (ec) {
    // Out of descriptors and the like: retry later instead of spinning.
    if (log) log->warn("http: accept failed: " + ec.message());
    auto self = shared_from_this();
    accept_timer.expires_after(std::chrono::milliseconds(100));
    accept_timer.async_wait([self](error_code e) {
      if (!e && !self->stopped) self->do_accept();
    });
    return;
  }
  counters.accepted.fetch_add(1, std::memory_order_relaxed);
  error_code pec;
  const auto ep = socket.remote_endpoint(pec);
  error_code ignored;
  if (pec) {  // gone already
    socket.close(ignored);
    return do_accept();
  }
  std::string address = address_key(ep.address());
  const auto held = per_address.find(address);
  if (cfg.max_connections_per_address > 0 && held != per_address.end() &&
      held->second >= cfg.max_connections_per_address) {
    counters.rejected_per_address.fetch_add(1, std::memory_order_relaxed);
    socket.close(ignored);
    note_refusal(address, "client " + address + " has " + std::to_string(held->second) +
                              " connections open (http.max-connections-per-address): closing its new ones");
    return do_accept();
  }
  if (counters.active.load(std::memory_order_relaxed) >= cfg.max_connections && !evict_idle()) {
    counters.rejected_full.fetch_add(1, std::memory_order_relaxed);
    socket.close(ignored);
    note_refusal("", std::to_string(cfg.max_connections) +
                         " connections open, none idle (http.max-connections): closing new ones");
    return do_accept();
  }
  std::string peer = endpoint_string(ep);
  auto slot = std::make_shared<AddressSlot>(shared_from_this(), std::move(address));
  socket.set_option(tcp::no_delay(true), ignored);
  counters.active.fetch_add(1, std::memory_order_relaxed);
  if (tls) {
    auto s = std::make_shared<HttpSession<TlsStream>>(shared_from_this(), std::move(slot),
                                                      TlsStream(beast::tcp_stream(std::move(socket)), *tls),
                                                      std::move(peer));
    s->run();
  } else {
    auto s = std::make_shared<HttpSession<beast::tcp_stream>>(shared_from_this(), std::move(slot),
                                                              beast::tcp_stream(std::move(socket)), std::move(peer));
    s->run();
  }
  do_accept();
}

// Closes the connection that has waited longest for a request, if any.
bool HttpServer::Impl::evict_idle() {
  std::shared_ptr<Closable> oldest;
  SteadyTime since{};
  for (auto& [id, w] : connections) {
    auto c = w.lock();
    if (!c) continue;
    if (auto t = c->idle_since(); t && (!oldest || *t < since)) {
      oldest = std::move(c);
      since = *t;
    }
  }
  if (!oldest) return false;
  counters.evicted_idle.fetch_add(1, std::memory_order_relaxed);
  debug("server full: closing the longest idle connection for a new one");
  oldest->shutdown();
  return true;
}

// Logs the first refusal of an episode; the counters have every one.
void HttpServer::Impl::note_refusal(const std::string& key, const std::string& message) {
  const auto now = std::chrono::steady_clock::now();
  for (auto it = refusing.begin(); it != refusing.end();)
    it = now - it->second > kRefusalQuiet ? refusing.erase(it) : std::next(it);
  const auto [it, fresh] = refusing.try_emplace(key, now);
  it->second = now;
  if (fresh && log)
    log->warn("http: " + message + " (counted in /metrics; logged again after a minute without refusals)");
}

void HttpServer::Impl::stop() {
  if (stopped) return;
  stopped = true;
  error_code ignored;
  acceptor.close(ignored);
  accept_timer.cancel();
  std::vector<std::shared_ptr<Closable>> all;
  for (auto& [id, w] : connections)
    if (auto c = w.lock()) all.push_back(std::move(c));
  for (auto& c : all) c->shutdown();
}

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
