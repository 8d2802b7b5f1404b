// HTTP connection: request -> route -> response (stream independent; see
// connection.hpp).
#include "http/connection.hpp"

#include <boost/asio/dispatch.hpp>
#include <boost/beast/http.hpp>
#include <boost/url/parse.hpp>
#include <boost/url/url_view.hpp>
#include <cctype>
#include <exception>
#include <utility>
#include <vector>

#include "http/event_stream.hpp"
#include "http/request_checks.hpp"
#include "http/router.hpp"
#include "http/static_files.hpp"

namespace gateway::http {

void StreamBody::kick() {
  if (auto c = conn_.lock()) c->pump_stream();
}

Connection::Connection(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, std::string peer, bool tls)
    : impl_(std::move(impl)),
      slot_(std::move(slot)),
      peer_(std::move(peer)),
      tls_(tls),
      handler_timer_(impl_->ioc),
      id_(impl_->next_id++) {
  impl_->connections.emplace(id_, std::weak_ptr<Closable>());
}

Connection::~Connection() {
  if (body_) body_->close();
  set_idle(false);
  impl_->connections.erase(id_);
  impl_->counters.active.fetch_sub(1, std::memory_order_relaxed);
}

void Connection::reply(const std::shared_ptr<PendingReply>& pending, Response r) {
  if (pending != pending_) return;
  pending_.reset();
  handler_timer_.cancel();
  send(std::move(r));
}

void Connection::set_idle(bool idle) {
  if (idle == idle_since_.has_value()) return;
  if (idle) {
    // An order, not a time: no clock read per request (a system call on
    // some kernels); eviction only needs which connection waited longest.
    idle_since_ = ++impl_->idle_order;
    impl_->counters.idle.fetch_add(1, std::memory_order_relaxed);
  } else {
    idle_since_.reset();
    impl_->counters.idle.fetch_sub(1, std::memory_order_relaxed);
  }
}

std::optional<Response> Connection::screen(const BeastRequest& breq) {
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

void Connection::handle(BeastRequest&& breq) {
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

std::optional<Response> Connection::authorize(Request& req) {
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

void Connection::run_handler(const Handler& handler, std::shared_ptr<Request> req, std::chrono::milliseconds timeout) {
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

void Connection::handle_upgrade(BeastRequest&& breq, Request& req) {
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

void Connection::handle_stream_upgrade(BeastRequest&& breq, Request& req) {
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

void Connection::fill_head(bhttp::response_header<>& res, const Response& r) const {
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

void Connection::send(Response r) {
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

void Connection::start_stream(Response r) {
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

void Connection::pump_stream() {
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

void Connection::stream_written(error_code ec) {
  stream_writing_ = false;
  if (ec) return stream_gone();
  if (body_) body_->written();
  if (stream_ended_) return end_stream();
  pump_stream();
}

void Connection::stream_head_written(error_code ec) {
  if (ec) return stream_gone();
  stream_started_ = true;
  watch_client();
  pump_stream();
}

void Connection::stream_gone() {
  if (body_) body_->close();
  close_now();
}

}  // namespace gateway::http
