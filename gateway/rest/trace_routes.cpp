#include "rest/trace_routes.hpp"

#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cmath>
#include <ctime>
#include <memory>

#include "core/format.hpp"
#include "trace/network_trace.hpp"
#include "rest/route_checks.hpp"

namespace gateway {

namespace {

using http::Request;
using http::Responder;
using http::Response;
using trace::NetworkTrace;

// The network of the path: its tap, or the problem to answer.
std::shared_ptr<NetworkTrace> path_tap(const status::View& status, const Request& req, Response& problem) {
  std::uint32_t net = 0;
  if (auto err = check_net(status, req, net)) {
    problem = std::move(*err);
    return nullptr;
  }
  return status.frame_tap(net);  // every configured network has one
}

// One trace WebSocket client: its filter and bounded queue, fed by the tap.
class TraceSession final : public http::StreamSource, public std::enable_shared_from_this<TraceSession> {
 public:
  explicit TraceSession(std::weak_ptr<NetworkTrace> tap) : tap_(std::move(tap)), queue_({}) {}
  ~TraceSession() override { on_close(); }

  void attach() {
    auto tap = tap_.lock();
    if (!tap) return;
    id_ = tap->add_client({[this](std::uint32_t id) { return filter_.matches(id); },
                           [this](const trace::Message& m) {
                             // Queued or dropped and counted; the bus path never waits.
                             queue_.push_frame(m);
                             if (wake) wake();
                           }});
  }

  std::shared_ptr<const std::string> next() override {
    if (queue_.empty()) return queue_.take_lost();  // caught up: how many it missed
    return queue_.pop();
  }

  void on_message(std::string_view text) override {
    std::string error;
    if (filter_.parse(text, error)) {
      queue_.push_control("{\"subscribed\":" + filter_.to_json() + "}");
    } else {
      queue_.push_control("{\"error\":" + Response::problem(400, error).body + "}");
    }
  }

  void on_close() override {
    if (id_ == 0) return;
    if (auto tap = tap_.lock()) tap->remove(id_);
    id_ = 0;
  }

 private:
  std::weak_ptr<NetworkTrace> tap_;
  trace::IdFilter filter_;
  trace::TraceQueue queue_;
  std::uint64_t id_ = 0;
};

http::StreamAccept trace_stream(const status::View& status, const Request& req) {
  http::StreamAccept out;
  auto tap = path_tap(status, req, out.refusal);
  if (!tap) return out;
  if (tap->clients() >= kMaxTraceClients) {
    out.refusal = Response::problem(503, "network " + std::string(req.param("net")) + " already has " +
                                             std::to_string(kMaxTraceClients) + " trace clients");
    out.refusal.headers.emplace_back("Retry-After", "5");
    return out;
  }
  auto session = std::make_shared<TraceSession>(tap);
  session->attach();
  out.source = std::move(session);
  return out;
}

// A number of seconds in the query: 1..max.
std::optional<std::uint32_t> query_seconds(std::string_view name, std::string_view text, std::uint32_t max,
                                           std::string& error) {
  const auto n = core::parse_decimal(text);
  if (!n || *n == 0 || *n > max) {
    error = std::string(name) + " must be a number of seconds 1.." + std::to_string(max) + ", not '" +
            std::string(text) + "'";
    return std::nullopt;
  }
  return n;
}

std::string utc_stamp(trace::WallTime t) {
  const std::time_t secs = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%dT%H%M%SZ", &tm);
  return buf;
}

// "canopen-net1-20261124T112857Z.pcapng"
std::string capture_name(const std::string& net, bool candump) {
  return "canopen-net" + net + "-" + utc_stamp(std::chrono::system_clock::now()) + (candump ? ".log" : ".pcapng");
}

Response capture_head(bool candump, const std::string& net) {
  Response r;
  r.status = 200;
  r.content_type = candump ? "text/plain; charset=utf-8" : "application/x-pcapng";
  r.headers.emplace_back("Content-Disposition", "attachment; filename=\"" + capture_name(net, candump) + "\"");
  return r;
}

Response capture_file(const NetworkTrace& tap, const std::vector<trace::Traced>& frames, bool candump,
                      const std::string& net) {
  Response r = capture_head(candump, net);
  const auto& iface = tap.settings().interface;
  if (candump) {
    r.body.reserve(frames.size() * 40);
    for (const auto& t : frames) r.body += trace::candump_line(t, iface);
  } else {
    r.body = trace::pcapng::file(frames, iface, "canopen-gateway");
  }
  return r;
}

// The next S seconds, streamed: each frame is written to the response as
// the tap sees it. A client that does not read fills the response's
// buffer, then frames are dropped and counted (in pcapng, the closing
// Interface Statistics Block says how many); one that goes away ends the
// recording at once.
class LiveCapture : public std::enable_shared_from_this<LiveCapture> {
 public:
  LiveCapture(boost::asio::io_context& io, std::weak_ptr<NetworkTrace> tap, std::shared_ptr<http::BodySink> sink,
              bool candump)
      : tap_(std::move(tap)), sink_(std::move(sink)), timer_(io), candump_(candump) {}
  ~LiveCapture() { stop(); }  // the io_context went first
  LiveCapture(const LiveCapture&) = delete;
  LiveCapture& operator=(const LiveCapture&) = delete;

  void start(std::chrono::seconds duration) {
    auto tap = tap_.lock();
    if (!tap) return sink_->finish();
    iface_ = tap->settings().interface;
    if (!candump_)
      sink_->write(trace::pcapng::section_header("canopen-gateway") + trace::pcapng::interface_description(iface_));
    id_ = tap->add_recorder([this](const trace::Traced& t) { on_frame(t); });
    sink_->on_close = [weak = weak_from_this()] {
      if (auto self = weak.lock()) self->stop();
    };
    timer_.expires_after(duration);
    timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec) return;  // stopped: the client went away
      self->stop();
      std::string tail;
      if (!self->candump_) {
        tail = trace::pcapng::interface_statistics(
            std::chrono::system_clock::now(), self->received_, self->dropped_,
            self->dropped_ == 0 ? std::string()
                                : std::to_string(self->dropped_) + " frames dropped: the client did not read fast enough");
      }
      self->sink_->finish(tail);
    });
  }

 private:
  void on_frame(const trace::Traced& t) {
    ++received_;
    if (!sink_->write(candump_ ? trace::candump_line(t, iface_) : trace::pcapng::enhanced_packet(t))) ++dropped_;
  }
  // No more frames (never called from inside the recorder callback).
  void stop() {
    timer_.cancel();
    if (id_ == 0) return;
    if (auto tap = tap_.lock()) tap->remove(id_);
    id_ = 0;
  }

  std::weak_ptr<NetworkTrace> tap_;
  std::shared_ptr<http::BodySink> sink_;
  boost::asio::steady_timer timer_;
  bool candump_;
  std::string iface_;
  std::uint64_t id_ = 0;
  std::uint64_t received_ = 0, dropped_ = 0;
};

void capture(const status::View& status, boost::asio::io_context& io, const Request& req, Responder respond) {
  Response problem;
  auto tap = path_tap(status, req, problem);
  if (!tap) return respond(std::move(problem));
  bool candump = false;
  if (auto f = req.query_param("format")) {
    if (*f == "candump") candump = true;
    else if (*f != "pcapng") return respond(Response::problem(400, "format must be pcapng or candump, not '" + std::string(*f) + "'"));
  }
  const auto last = req.query_param("last");
  const auto seconds = req.query_param("seconds");
  if (last && seconds) return respond(Response::problem(400, "give last or seconds, not both"));
  std::string error;
  const std::string net(req.param("net"));
  if (!seconds) {
    // The ring: the last S seconds (all it holds without last=).
    std::uint32_t s = static_cast<std::uint32_t>(tap->ring().limits().ring.count());
    if (last) {
      const auto n = query_seconds("last", *last, 86400, error);
      if (!n) return respond(Response::problem(400, error));
      s = *n;
    }
    const auto frames = tap->ring().since(std::chrono::system_clock::now() - std::chrono::seconds(s));
    return respond(capture_file(*tap, frames, candump, net));
  }
  const auto n = query_seconds("seconds", *seconds, kMaxCaptureSeconds, error);
  if (!n) return respond(Response::problem(400, error));
  // Answered at once (so no handler timeout applies); the body follows.
  Response r = capture_head(candump, net);
  r.stream_buffer_bytes = kCaptureStreamBuffer;
  r.stream = [&io, weak = std::weak_ptr<NetworkTrace>(tap), candump,
              duration = std::chrono::seconds(*n)](std::shared_ptr<http::BodySink> sink) {
    std::make_shared<LiveCapture>(io, weak, std::move(sink), candump)->start(duration);
  };
  respond(std::move(r));
}

}  // namespace

boost::json::object bus_load_json(const NetworkTrace& tap) {
  boost::json::object o;
  const auto now = std::chrono::steady_clock::now();
  const auto& load = tap.load();
  auto pct = [&](std::chrono::seconds w) -> boost::json::value {
    const auto p = load.percent(w, now);
    if (!p) return nullptr;
    return std::round(*p * 10.0) / 10.0;
  };
  o["percent1s"] = pct(std::chrono::seconds(1));
  o["percent10s"] = pct(std::chrono::seconds(10));
  if (load.bitrate() != 0) {
    o["bitrate"] = load.bitrate();
  } else {
    o["bitrate"] = nullptr;
    o["reason"] = "no bitrate configured for this network";
  }
  return o;
}

boost::json::object capture_json(const NetworkTrace& tap) {
  boost::json::object o;
  const auto& ring = tap.ring();
  o["ringSeconds"] = ring.limits().ring.count();
  o["maxBytes"] = ring.limits().max_bytes;
  o["frames"] = ring.size();
  o["bytes"] = ring.bytes();
  return o;
}

void register_trace_routes(http::HttpServer& server, const status::View& status, boost::asio::io_context& io) {
  const auto* s = &status;
  server.add_stream_route("/api/v1/networks/{net}/trace", [s](const Request& req) { return trace_stream(*s, req); });
  server.add_route("GET", "/api/v1/networks/{net}/capture", [s, io = &io](const Request& req, Responder respond) {
    capture(*s, *io, req, std::move(respond));
  });
}

}  // namespace gateway
