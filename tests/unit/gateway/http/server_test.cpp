// HttpServer over real sockets on 127.0.0.1 (ephemeral port): the server
// runs its io_context on a thread; the tests drive Beast clients with their
// own io_context and a deadline on every operation, so nothing can hang.
#include "http/http_server.hpp"

#include "log.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <boost/json/parse.hpp>
#include <boost/json/serialize.hpp>
#include <boost/json/value.hpp>
#include <boost/json/value_to.hpp>
#include <atomic>
#include <deque>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <optional>
#include <random>
#include <system_error>
#include <thread>

namespace net = boost::asio;
namespace beast = boost::beast;
namespace bhttp = beast::http;
namespace websocket = beast::websocket;
namespace fs = std::filesystem;
using tcp = net::ip::tcp;
using error_code = boost::system::error_code;
using namespace std::chrono_literals;
using gateway::EncodedEvent;
using gateway::EncodedEventPtr;
using gateway::EventKind;
using gateway::http::HttpConfig;
using gateway::http::HttpServer;
using gateway::http::Request;
using gateway::http::Responder;
using gateway::http::Response;
using gateway::http::StreamAccept;
using gateway::http::StreamSource;

namespace {

// --- server side ------------------------------------------------------------

class TestServer {
 public:
  explicit TestServer(HttpConfig cfg, const std::function<void(HttpServer&)>& setup = {},
                      gateway::Logger* log = nullptr) {
    cfg.address = "127.0.0.1";
    cfg.port = 0;
    server_ = std::make_unique<HttpServer>(ioc_, std::move(cfg), log);
    if (setup) setup(*server_);
    server_->start();
    thread_ = std::thread([this] { ioc_.run(); });
  }
  ~TestServer() {
    on_io([this] { server_->stop(); });
    guard_.reset();
    ioc_.stop();
    thread_.join();
    server_.reset();
  }

  std::uint16_t port() const { return server_->bound_port(); }
  HttpServer& server() { return *server_; }
  net::io_context& ioc() { return ioc_; }

  // Runs f on the server's thread and waits for it.
  void on_io(std::function<void()> f) {
    std::promise<void> done;
    net::post(ioc_, [&] {
      f();
      done.set_value();
    });
    ASSERT_EQ(done.get_future().wait_for(5s), std::future_status::ready);
  }

  void publish(EncodedEventPtr ev) {
    on_io([&] { server_->publish(ev); });
  }

  // Polls `pred` (on this thread; stats() is thread-safe) until true or 5 s.
  bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds limit = 5s) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!pred()) {
      if (std::chrono::steady_clock::now() > end) return false;
      std::this_thread::sleep_for(5ms);
    }
    return true;
  }

 private:
  net::io_context ioc_;
  net::executor_work_guard<net::io_context::executor_type> guard_{ioc_.get_executor()};
  std::unique_ptr<HttpServer> server_;
  std::thread thread_;
};

EncodedEventPtr make_event(EventKind kind, std::uint32_t net, std::uint8_t node, std::uint64_t seq,
                           std::size_t pad = 0) {
  auto e = std::make_shared<EncodedEvent>();
  e->kind = kind;
  e->network = net;
  e->node = node;
  e->seq = seq;
  boost::json::object o;
  o["kind"] = to_string(kind);
  o["network"] = net;
  o["node"] = node;
  o["seq"] = seq;
  if (pad) o["pad"] = std::string(pad, 'x');
  e->json = boost::json::serialize(o);
  e->binary = std::string("\x08") + static_cast<char>(seq & 0x7f) + std::string(3, '\0');
  return e;
}

// --- client side ------------------------------------------------------------

// Runs client operations with a deadline: start(handler) starts one async
// operation; on timeout `cancel` is called and the operation awaited.
class Driver {
 public:
  net::io_context ioc;

  template <class Start>
  error_code run(Start&& start, const std::function<void()>& cancel, std::chrono::milliseconds limit = 5s) {
    std::optional<error_code> result;
    start([&result](error_code ec, auto&&...) { result = ec; });
    ioc.restart();
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!result && std::chrono::steady_clock::now() < end) ioc.run_one_until(end);
    if (!result) {
      cancel();
      ioc.restart();
      while (!result) ioc.run_one();
      return net::error::timed_out;
    }
    return *result;
  }
};

class HttpClient : public Driver {
 public:
  // `from`: the client's own address (any of 127/8 is loopback on Linux),
  // to be a different client address than 127.0.0.1.
  explicit HttpClient(std::uint16_t port, const char* from = nullptr) : stream(ioc), host("127.0.0.1:" + std::to_string(port)) {
    if (from != nullptr) {
      stream.socket().open(tcp::v4());
      stream.socket().bind({net::ip::make_address(from), 0});
    }
    ec = run([&](auto h) { stream.socket().async_connect({net::ip::make_address("127.0.0.1"), port}, h); }, cancel());
  }

  bhttp::response<bhttp::string_body> request(bhttp::verb verb, std::string target, std::string body = {},
                                              std::vector<std::pair<std::string, std::string>> fields = {}) {
    bhttp::request<bhttp::string_body> req{verb, target, 11};
    req.set(bhttp::field::host, host);
    for (auto& [k, v] : fields) req.set(k, v);
    if (!body.empty() || verb == bhttp::verb::put || verb == bhttp::verb::post) {
      req.body() = std::move(body);
      req.prepare_payload();
    }
    bhttp::response<bhttp::string_body> res;
    ec = run([&](auto h) { bhttp::async_write(stream, req, h); }, cancel());
    if (ec) return res;
    bhttp::response_parser<bhttp::string_body> parser;
    parser.body_limit(64u << 20);
    if (verb == bhttp::verb::head) parser.skip(true);
    ec = run([&](auto h) { bhttp::async_read(stream, buffer, parser, h); }, cancel());
    if (!ec) res = parser.release();
    return res;
  }

  bhttp::response<bhttp::string_body> get(std::string target) { return request(bhttp::verb::get, std::move(target)); }

  // Writes raw bytes, then reads whatever comes until EOF (bounded).
  std::string raw(const std::string& bytes, std::chrono::milliseconds limit = 3s) {
    ec = run([&](auto h) { net::async_write(stream, net::buffer(bytes), h); }, cancel());
    if (ec) return {};
    std::string out;
    std::array<char, 4096> buf{};
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      std::size_t n = 0;
      ec = run([&](auto h) {
            stream.async_read_some(net::buffer(buf), [&n, h](error_code e, std::size_t k) mutable {
              n = k;
              h(e);
            });
          },
          cancel(), std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()));
      out.append(buf.data(), n);
      if (ec) break;
    }
    return out;
  }

  std::function<void()> cancel() {
    return [this] { stream.socket().close(); };
  }

  beast::tcp_stream stream;
  std::string host;  // the Host header of request()
  beast::flat_buffer buffer;
  error_code ec;
};

class WsClient : public Driver {
 public:
  explicit WsClient(std::uint16_t port, std::string target = "/api/v1/events",
                    std::optional<std::string> origin = std::nullopt, int rcvbuf = 0, std::string host = {})
      : ws(ioc) {
    auto& sock = beast::get_lowest_layer(ws).socket();
    if (rcvbuf > 0) {
      sock.open(tcp::v4());
      sock.set_option(net::socket_base::receive_buffer_size(rcvbuf));
    }
    ec = run([&](auto h) { sock.async_connect({net::ip::make_address("127.0.0.1"), port}, h); }, cancel());
    if (ec) return;
    ws.set_option(websocket::stream_base::decorator([origin](websocket::request_type& req) {
      if (origin) req.set(bhttp::field::origin, *origin);
    }));
    ws.control_callback([this](websocket::frame_type t, beast::string_view) {
      if (t == websocket::frame_type::ping) ++pings;
    });
    if (host.empty()) host = "127.0.0.1:" + std::to_string(port);
    ec = run([&](auto h) { ws.async_handshake(response, host, target, h); }, cancel());
  }

  // Reads one message; its text in `out`.
  error_code read(std::string& out, std::chrono::milliseconds limit = 5s) {
    beast::flat_buffer b;
    ec = run([&](auto h) { ws.async_read(b, h); }, cancel(), limit);
    out = beast::buffers_to_string(b.data());
    return ec;
  }

  error_code send(const std::string& text) {
    ws.text(true);
    return ec = run([&](auto h) { ws.async_write(net::buffer(text), h); }, cancel());
  }

  std::function<void()> cancel() {
    return [this] { beast::get_lowest_layer(ws).socket().close(); };
  }

  websocket::stream<beast::tcp_stream> ws;
  websocket::response_type response;
  error_code ec;
  int pings = 0;
};

boost::json::value parse_json(const std::string& s) {
  error_code ec;
  auto v = boost::json::parse(s, ec);
  EXPECT_FALSE(ec) << s;
  return v;
}

// Handler that answers with the request's params, query and some headers.
void echo(const Request& req, Responder done) {
  boost::json::object o;
  boost::json::object params;
  for (auto& [k, v] : req.params) params[k] = v;
  boost::json::array query;
  for (auto& [k, v] : req.query) query.push_back(boost::json::array{boost::json::string(k), boost::json::string(v)});
  o["method"] = req.method;
  o["path"] = req.path;
  o["params"] = std::move(params);
  o["query"] = std::move(query);
  o["body"] = req.body;
  o["accept"] = std::string(req.header("Accept").value_or(""));
  o["peer_local"] = req.peer.rfind("127.0.0.1:", 0) == 0;
  done(Response::json(boost::json::serialize(o)));
}

HttpConfig quick_config() {
  HttpConfig c;
  c.read_timeout = 3s;
  c.idle_timeout = 5s;
  return c;
}

}  // namespace

// --- HTTP -----------------------------------------------------------------

TEST(HttpServer, RoutesWithPathParamsAndQuery) {
  TestServer ts(quick_config(), [](HttpServer& s) {
    s.add_route("GET", "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}", echo);
    s.add_route("PUT", "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}", echo);
  });
  HttpClient c(ts.port());
  ASSERT_FALSE(c.ec) << c.ec.message();
  auto res = c.request(bhttp::verb::get, "/api/v1/networks/1/nodes/5/sdo/1017/0?type=u16&x=a+b%21&flag", {},
                       {{"Accept", "application/json"}});
  ASSERT_FALSE(c.ec) << c.ec.message();
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res[bhttp::field::content_type], "application/json");
  auto v = parse_json(res.body());
  EXPECT_EQ(v.at("params").at("net"), "1");
  EXPECT_EQ(v.at("params").at("node"), "5");
  EXPECT_EQ(v.at("params").at("index"), "1017");
  EXPECT_EQ(v.at("params").at("sub"), "0");
  EXPECT_EQ(boost::json::serialize(v.at("query")), R"([["type","u16"],["x","a b!"],["flag",""]])");
  EXPECT_EQ(v.at("accept"), "application/json");
  EXPECT_EQ(v.at("peer_local"), true);
  // API answers are live data: never cached, never sniffed; no HSTS on plain HTTP.
  EXPECT_EQ(res[bhttp::field::cache_control], "no-store");
  EXPECT_EQ(res["X-Content-Type-Options"], "nosniff");
  EXPECT_EQ(res["Referrer-Policy"], "no-referrer");
  EXPECT_EQ(res.count("Strict-Transport-Security"), 0u);

  res = c.request(bhttp::verb::put, "/api/v1/networks/2/nodes/%31%30/sdo/0x6040/0", R"({"value":6})",
                  {{"Content-Type", "application/json"}});
  EXPECT_EQ(res.result_int(), 200u);
  v = parse_json(res.body());
  EXPECT_EQ(v.at("method"), "PUT");
  EXPECT_EQ(v.at("params").at("node"), "10");  // percent-decoded
  EXPECT_EQ(v.at("body"), R"({"value":6})");
}

// Issue 13: an address the server cannot listen on is a std::system_error
// carrying the errno, which main.cpp words for people; what() has no Boost
// source location or function signature.
TEST(HttpServer, ListenFailureIsASystemErrorWithTheErrno) {
  TestServer first(quick_config());
  net::io_context ioc;
  auto start_error = [&](const std::string& address, std::uint16_t port) -> std::optional<std::system_error> {
    HttpConfig cfg = quick_config();
    cfg.address = address;
    cfg.port = port;
    HttpServer s(ioc, cfg);
    try {
      s.start();
    } catch (const std::system_error& e) {
      return e;
    }
    return std::nullopt;
  };
  auto in_use = start_error("127.0.0.1", first.port());
  ASSERT_TRUE(in_use) << "a second listener on the same port";
  EXPECT_EQ(in_use->code(), std::errc::address_in_use);
  EXPECT_EQ(std::string(in_use->what()), "bind: " + std::make_error_code(std::errc::address_in_use).message());
  // 192.0.2.1 (TEST-NET-1) is no address of this machine.
  auto foreign = start_error("192.0.2.1", 0);
  ASSERT_TRUE(foreign);
  EXPECT_EQ(foreign->code(), std::errc::address_not_available);
  for (const auto& e : {*in_use, *foreign}) {
    EXPECT_THAT(e.what(), ::testing::Not(::testing::HasSubstr("boost")));
    EXPECT_THAT(e.what(), ::testing::Not(::testing::HasSubstr("/usr/include")));
  }
}

TEST(HttpServer, UnknownPathIs404AndWrongMethodIs405) {
  TestServer ts(quick_config(), [](HttpServer& s) { s.add_route("GET", "/api/v1/gateway", echo); });
  HttpClient c(ts.port());
  auto res = c.get("/api/v1/nope");
  EXPECT_EQ(res.result_int(), 404u);
  EXPECT_EQ(res[bhttp::field::content_type], "application/problem+json");
  auto v = parse_json(res.body());
  EXPECT_EQ(v.at("status"), 404);
  EXPECT_EQ(v.at("title"), "Not Found");
  EXPECT_TRUE(v.at("detail").is_string());

  res = c.request(bhttp::verb::delete_, "/api/v1/gateway");
  EXPECT_EQ(res.result_int(), 405u);
  EXPECT_EQ(res[bhttp::field::content_type], "application/problem+json");
  EXPECT_EQ(res[bhttp::field::allow], "GET, HEAD");
  EXPECT_EQ(parse_json(res.body()).at("status"), 405);

  // HEAD runs the GET route without a body.
  res = c.request(bhttp::verb::head, "/api/v1/gateway");
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_TRUE(res.body().empty());
  EXPECT_NE(res[bhttp::field::content_length], "0");

  auto st = ts.server().stats();
  EXPECT_EQ(st.responses_by_status[404], 1u);
  EXPECT_EQ(st.responses_by_status[405], 1u);
  EXPECT_EQ(st.responses_by_status[200], 1u);
}

TEST(HttpServer, BodyOverLimitIs413) {
  HttpConfig cfg = quick_config();
  cfg.max_body_bytes = 1024;
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("POST", "/x", echo); });
  {
    HttpClient c(ts.port());
    auto res = c.request(bhttp::verb::post, "/x", std::string(1024, 'a'), {{"Content-Type", "application/json"}});
    EXPECT_EQ(res.result_int(), 200u);
    res = c.request(bhttp::verb::post, "/x", std::string(1025, 'a'), {{"Content-Type", "application/json"}});
    EXPECT_EQ(res.result_int(), 413u);
    EXPECT_EQ(res[bhttp::field::content_type], "application/problem+json");
    EXPECT_FALSE(res.keep_alive());
  }
  {
    // Announced length alone is enough; the body is never read.
    HttpClient c(ts.port());
    auto out = c.raw("POST /x HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 100000000\r\n\r\n");
    EXPECT_EQ(out.rfind("HTTP/1.1 413 ", 0), 0u) << out;
  }
  {
    HttpClient c(ts.port());
    auto out = c.raw("POST /x HTTP/1.1\r\nHost: 127.0.0.1\r\nTransfer-Encoding: chunked\r\n\r\n800\r\n" +
                     std::string(0x800, 'b') + "\r\n0\r\n\r\n");
    EXPECT_EQ(out.rfind("HTTP/1.1 413 ", 0), 0u) << out;
  }
}

// An upload route (a DCF, a program image) takes its own body limit and
// media type; every other route keeps the server's.
TEST(HttpServer, RouteOptionsGiveOneRouteItsOwnBodyLimitAndMediaType) {
  HttpConfig cfg = quick_config();
  cfg.max_body_bytes = 1024;
  gateway::http::RouteOptions upload;
  upload.max_body_bytes = 4096;
  upload.body_types = {"application/octet-stream"};
  TestServer ts(cfg, [&](HttpServer& s) {
    s.add_route("POST", "/x", echo);
    s.add_route("PUT", "/upload", echo, upload);
  });
  auto send = [&](bhttp::verb v, const char* target, std::size_t n, const char* type) {
    HttpClient c(ts.port());
    return c.request(v, target, std::string(n, 'a'), {{"Content-Type", type}});
  };
  EXPECT_EQ(send(bhttp::verb::put, "/upload", 4096, "application/octet-stream").result_int(), 200u);
  auto big = send(bhttp::verb::put, "/upload", 4097, "application/octet-stream");
  EXPECT_EQ(big.result_int(), 413u);
  EXPECT_THAT(big.body(), ::testing::HasSubstr("4096 bytes"));
  EXPECT_EQ(send(bhttp::verb::post, "/x", 2000, "application/json").result_int(), 413u) << "the server's limit";
  // Media types: the route's extra one there only; text/plain nowhere.
  auto plain = send(bhttp::verb::put, "/upload", 10, "text/plain");
  EXPECT_EQ(plain.result_int(), 415u);
  EXPECT_EQ(plain[bhttp::field::accept], "application/json, application/x-protobuf, application/octet-stream");
  EXPECT_EQ(send(bhttp::verb::post, "/x", 10, "application/octet-stream").result_int(), 415u);
}

// A route without handler timeout answers whenever it is done (each step of
// a program download has its own timeout); the others keep the server's.
TEST(HttpServer, RouteWithoutHandlerTimeoutAnswersLate) {
  HttpConfig cfg = quick_config();
  cfg.handler_timeout = 100ms;
  gateway::http::RouteOptions unlimited;
  unlimited.handler_timeout = std::chrono::milliseconds(0);
  std::promise<Responder> parked;
  TestServer ts(cfg, [&](HttpServer& s) {
    s.add_route("GET", "/long", [&](const Request&, Responder done) { parked.set_value(std::move(done)); }, unlimited);
  });
  std::thread late([&] {
    auto done = parked.get_future().get();
    std::this_thread::sleep_for(400ms);  // past the server's handler_timeout
    done(Response::json("{\"ok\":true}"));
  });
  HttpClient c(ts.port());
  auto res = c.get("/long");
  late.join();
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res.body(), "{\"ok\":true}");
}

TEST(HttpServer, HeaderOverLimitIs431AndGarbageIs400) {
  HttpConfig cfg = quick_config();
  cfg.max_header_bytes = 1024;
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("GET", "/x", echo); });
  {
    HttpClient c(ts.port());
    auto out = c.raw("GET /x HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: " + std::string(2000, 'h') + "\r\n\r\n");
    EXPECT_EQ(out.rfind("HTTP/1.1 431 ", 0), 0u) << out;
  }
  {
    HttpClient c(ts.port());
    auto out = c.raw("GET /x HTTP/1.1\r\nHost a\r\n\r\n");
    EXPECT_EQ(out.rfind("HTTP/1.1 400 ", 0), 0u) << out;
  }
}

TEST(HttpServer, KeepAliveServesSeveralRequestsOnOneConnection) {
  TestServer ts(quick_config(), [](HttpServer& s) { s.add_route("GET", "/n/{i}", echo); });
  HttpClient c(ts.port());
  for (int i = 0; i < 20; ++i) {
    auto res = c.get("/n/" + std::to_string(i));
    ASSERT_FALSE(c.ec) << i << " " << c.ec.message();
    ASSERT_EQ(res.result_int(), 200u);
    EXPECT_TRUE(res.keep_alive());
    EXPECT_EQ(boost::json::value_to<std::string>(parse_json(res.body()).at("params").at("i")), std::to_string(i));
  }
  EXPECT_EQ(ts.server().stats().connections_accepted, 1u);
}

TEST(HttpServer, IdleKeepAliveConnectionIsClosed) {
  HttpConfig cfg = quick_config();
  cfg.idle_timeout = 300ms;
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("GET", "/x", echo); });
  HttpClient c(ts.port());
  EXPECT_EQ(c.get("/x").result_int(), 200u);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(ts.wait_until([&] { return ts.server().stats().connections_active == 0; }));
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 200ms);
}

TEST(HttpServer, AsyncHandlerAnswersLaterWithoutBlockingTheLoop) {
  std::vector<Responder> parked;
  TestServer* tsp = nullptr;
  TestServer ts(quick_config(), [&](HttpServer& s) {
    s.add_route("GET", "/slow/{ms}", [&](const Request& req, Responder done) {
      // Answer from a timer on the loop, as an SDO round trip would.
      auto t = std::make_shared<net::steady_timer>(tsp->ioc(), std::chrono::milliseconds(std::stoi(std::string(req.param("ms")))));
      t->async_wait([t, &req, done](error_code) { done(Response::json("{\"late\":\"" + std::string(req.param("ms")) + "\"}")); });
    });
    s.add_route("GET", "/fast", echo);
    s.add_route("GET", "/never", [&](const Request&, Responder done) { parked.push_back(std::move(done)); });
  });
  tsp = &ts;
  HttpClient slow(ts.port());
  std::future<bhttp::response<bhttp::string_body>> slow_res =
      std::async(std::launch::async, [&] { return slow.get("/slow/300"); });
  // Meanwhile another connection is served at once.
  HttpClient fast(ts.port());
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(fast.get("/fast").result_int(), 200u);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 250ms);
  auto r = slow_res.get();
  EXPECT_EQ(r.result_int(), 200u);
  EXPECT_EQ(r.body(), R"({"late":"300"})");

  // A Responder called after its connection is gone is a harmless no-op,
  // from any thread. (While a handler is pending the server does not read,
  // so the connection ends here through stop().)
  HttpClient gone(ts.port());
  bhttp::request<bhttp::string_body> req{bhttp::verb::get, "/never", 11};
  req.set(bhttp::field::host, gone.host);
  gone.ec = gone.run([&](auto h) { bhttp::async_write(gone.stream, req, h); }, gone.cancel());
  ASSERT_FALSE(gone.ec);
  ASSERT_TRUE(ts.wait_until([&] {
    bool has = false;
    ts.on_io([&] { has = !parked.empty(); });
    return has;
  }));
  ts.on_io([&] { ts.server().stop(); });
  ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().connections_active == 0; }));
  Responder late;
  ts.on_io([&] { late = parked.front(); });
  late(Response::json("{}"));
  late(Response::json("{}"));  // twice: ignored
  ts.on_io([] {});
  EXPECT_EQ(ts.server().stats().responses_by_status.count(500), 0u);
}

TEST(HttpServer, HandlerThatNeverAnswersGets500AfterTimeout) {
  HttpConfig cfg = quick_config();
  cfg.handler_timeout = 200ms;
  std::vector<Responder> parked;
  TestServer ts(cfg, [&](HttpServer& s) {
    s.add_route("GET", "/never", [&](const Request&, Responder done) { parked.push_back(std::move(done)); });
  });
  HttpClient c(ts.port());
  auto res = c.get("/never");
  EXPECT_EQ(res.result_int(), 500u);
  EXPECT_EQ(res[bhttp::field::content_type], "application/problem+json");
  // The connection still works.
  EXPECT_EQ(c.get("/nothing").result_int(), 404u);
}

TEST(HttpServer, AuthorizerRunsBeforeRoutes) {
  int handled = 0;
  TestServer ts(quick_config(), [&](HttpServer& s) {
    s.add_route("GET", "/secret", [&](const Request& r, Responder done) {
      ++handled;
      echo(r, std::move(done));
    });
    s.set_authorizer([](const Request& r) -> std::optional<Response> {
      if (r.header("authorization") == std::optional<std::string_view>("Bearer ok")) return std::nullopt;
      auto res = Response::problem(401, "missing credentials");
      res.headers.emplace_back("WWW-Authenticate", "Bearer");
      return res;
    });
  });
  HttpClient c(ts.port());
  auto res = c.get("/secret");
  EXPECT_EQ(res.result_int(), 401u);
  EXPECT_EQ(res[bhttp::field::www_authenticate], "Bearer");
  res = c.request(bhttp::verb::get, "/secret", {}, {{"Authorization", "Bearer ok"}});
  EXPECT_EQ(res.result_int(), 200u);
  ts.on_io([] {});
  EXPECT_EQ(handled, 1);
  // WebSocket upgrade goes through it too.
  WsClient ws(ts.port());
  EXPECT_EQ(ws.response.result_int(), 401u);
}

// --- connection limits --------------------------------------------------------

// At max_connections a new client closes the connection that has waited
// longest for a request, instead of being locked out.
TEST(HttpServer, AtMaxConnectionsTheLongestIdleConnectionMakesRoom) {
  HttpConfig cfg = quick_config();
  cfg.max_connections = 2;
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("GET", "/x", echo); });
  HttpClient a(ts.port());
  EXPECT_EQ(a.get("/x").result_int(), 200u);
  HttpClient b(ts.port());
  EXPECT_EQ(b.get("/x").result_int(), 200u);
  ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().connections_idle == 2; }));
  HttpClient c(ts.port());
  EXPECT_EQ(c.get("/x").result_int(), 200u);
  a.get("/x");
  EXPECT_TRUE(a.ec) << "the longest idle connection was closed";
  EXPECT_EQ(b.get("/x").result_int(), 200u);
  const auto st = ts.server().stats();
  EXPECT_EQ(st.connections_evicted_idle, 1u);
  EXPECT_EQ(st.connections_rejected, 0u);
}

// Connections busy with a request are not idle: with no idle one to close,
// a new connection is closed at once.
TEST(HttpServer, AtMaxConnectionsWithNoneIdleTheNewOneIsClosed) {
  HttpConfig cfg = quick_config();
  cfg.max_connections = 2;
  std::vector<Responder> parked;
  TestServer ts(cfg, [&](HttpServer& s) {
    s.add_route("GET", "/never", [&](const Request&, Responder done) { parked.push_back(std::move(done)); });
  });
  HttpClient a(ts.port()), b(ts.port());
  for (HttpClient* c : {&a, &b}) {
    bhttp::request<bhttp::string_body> req{bhttp::verb::get, "/never", 11};
    req.set(bhttp::field::host, c->host);
    ASSERT_FALSE(c->run([&](auto h) { bhttp::async_write(c->stream, req, h); }, c->cancel()));
  }
  ASSERT_TRUE(ts.wait_until([&] {
    std::size_t n = 0;
    ts.on_io([&] { n = parked.size(); });
    return n == 2;
  }));
  HttpClient c(ts.port());
  c.get("/never");
  EXPECT_TRUE(c.ec);
  EXPECT_NE(c.ec, net::error::timed_out) << "closed at once, not left waiting";
  const auto st = ts.server().stats();
  EXPECT_EQ(st.connections_rejected_full, 1u);
  EXPECT_EQ(st.connections_rejected, 1u);
  EXPECT_EQ(st.connections_evicted_idle, 0u);
}

// Contract "REST and WebSocket": one client address holding its whole
// share with requests in progress does not lock out another address; its
// extra connections are closed at once and logged once, not once each.
TEST(HttpServer, OneClientAddressCannotHoldTheServer) {
  HttpConfig cfg = quick_config();
  cfg.max_connections_per_address = 3;
  std::FILE* log_file = std::tmpfile();
  ASSERT_NE(log_file, nullptr);
  {
    gateway::Logger log(gateway::LogLevel::Info, log_file);
    std::vector<Responder> parked;
    TestServer ts(
        cfg,
        [&](HttpServer& s) {
          s.add_route("GET", "/x", echo);
          s.add_route("GET", "/never", [&](const Request&, Responder done) { parked.push_back(std::move(done)); });
        },
        &log);
    std::vector<std::unique_ptr<HttpClient>> held;
    for (int i = 0; i < 3; ++i) {
      held.push_back(std::make_unique<HttpClient>(ts.port()));
      HttpClient& c = *held.back();
      bhttp::request<bhttp::string_body> req{bhttp::verb::get, "/never", 11};
      req.set(bhttp::field::host, c.host);
      ASSERT_FALSE(c.run([&](auto h) { bhttp::async_write(c.stream, req, h); }, c.cancel()));
    }
    ASSERT_TRUE(ts.wait_until([&] {
      std::size_t n = 0;
      ts.on_io([&] { n = parked.size(); });
      return n == 3;
    }));
    for (int i = 0; i < 4; ++i) {
      HttpClient extra(ts.port());
      extra.get("/x");
      EXPECT_TRUE(extra.ec) << i;
      EXPECT_NE(extra.ec, net::error::timed_out) << "closed at once, not left waiting";
    }
    HttpClient other(ts.port(), "127.0.0.2");
    ASSERT_FALSE(other.ec) << other.ec.message();
    EXPECT_EQ(other.get("/x").result_int(), 200u);
    const auto st = ts.server().stats();
    EXPECT_EQ(st.connections_rejected_per_address, 4u);
    EXPECT_EQ(st.connections_rejected_full, 0u);
    EXPECT_EQ(st.connections_evicted_idle, 0u) << "busy connections are never closed for a new one";
    ts.on_io([&] { parked.clear(); });
  }
  std::rewind(log_file);
  std::string text;
  for (int ch; (ch = std::fgetc(log_file)) != EOF;) text.push_back(static_cast<char>(ch));
  std::fclose(log_file);
  std::size_t lines = 0;
  for (auto p = text.find("client 127.0.0.1 has 3 connections open"); p != std::string::npos;
       p = text.find("client 127.0.0.1 has 3 connections open", p + 1))
    ++lines;
  EXPECT_EQ(lines, 1u) << text;
}

// Issue 27 item 10 (contract "REST and WebSocket"): many idle keep-alive
// connections from one address (every client behind one reverse proxy)
// do not lock that address out: at its cap, its longest idle connection
// makes room, as at the global cap; another address's are never touched.
TEST(HttpServer, AtAnAddressCapItsLongestIdleConnectionMakesRoom) {
  HttpConfig cfg = quick_config();
  cfg.max_connections_per_address = 3;
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("GET", "/x", echo); });
  HttpClient elsewhere(ts.port(), "127.0.0.2");
  EXPECT_EQ(elsewhere.get("/x").result_int(), 200u);
  std::vector<std::unique_ptr<HttpClient>> held;
  for (int i = 0; i < 3; ++i) {
    held.push_back(std::make_unique<HttpClient>(ts.port()));
    EXPECT_EQ(held.back()->get("/x").result_int(), 200u) << i;
  }
  ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().connections_idle == 4; }));
  std::vector<std::unique_ptr<HttpClient>> newcomers;
  for (int i = 0; i < 2; ++i) {
    newcomers.push_back(std::make_unique<HttpClient>(ts.port()));
    EXPECT_EQ(newcomers.back()->get("/x").result_int(), 200u) << "not locked out: " << i;
  }
  for (std::size_t i = 0; i < 2; ++i) {
    held[i]->get("/x");
    EXPECT_TRUE(held[i]->ec) << "the longest idle connections of that address were closed: " << i;
  }
  EXPECT_EQ(held[2]->get("/x").result_int(), 200u);
  EXPECT_EQ(elsewhere.get("/x").result_int(), 200u) << "another address's idle connection is kept";
  const auto st = ts.server().stats();
  EXPECT_EQ(st.connections_evicted_idle, 2u);
  EXPECT_EQ(st.connections_rejected, 0u);
}

// A client that sends its header a little at a time is closed after
// header_timeout, long before idle_timeout.
TEST(HttpServer, SlowHeaderIsClosedAfterHeaderTimeout) {
  HttpConfig cfg = quick_config();
  cfg.header_timeout = 300ms;
  cfg.idle_timeout = 60s;
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("GET", "/x", echo); });
  net::io_context io;
  tcp::socket slow(io);
  slow.connect({net::ip::make_address("127.0.0.1"), ts.port()});
  std::atomic<bool> done{false};
  std::thread trickle([&] {
    error_code ec;
    net::write(slow, net::buffer(std::string_view("GET /x HTTP/1.1\r\nHost: 127.0.0.1\r\n")), ec);
    for (int i = 0; i < 400 && !done && !ec; ++i) {
      net::write(slow, net::buffer(std::string_view("X-Slow: 1\r\n")), ec);
      std::this_thread::sleep_for(10ms);
    }
  });
  EXPECT_TRUE(ts.wait_until([&] { return ts.server().stats().header_timeouts == 1; }));
  EXPECT_TRUE(ts.wait_until([&] { return ts.server().stats().connections_active == 0; }));
  done = true;
  trickle.join();
  // Others are served as usual.
  HttpClient c(ts.port());
  EXPECT_EQ(c.get("/x").result_int(), 200u);
}

// --- strictness ------------------------------------------------------------------

// Every ambiguous way to frame a request gets 400 and the connection ends:
// what follows (here a smuggled second request) is never parsed.
TEST(HttpServer, AmbiguousFramingIs400AndClosesTheConnection) {
  int handled = 0;
  TestServer ts(quick_config(), [&](HttpServer& s) {
    s.add_route("POST", "/x", [&](const Request& r, Responder done) {
      ++handled;
      echo(r, std::move(done));
    });
    s.add_route("GET", "/smuggled", [&](const Request& r, Responder done) {
      ++handled;
      echo(r, std::move(done));
    });
  });
  const std::string head = "POST /x HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n";
  const std::string smuggled = "GET /smuggled HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  for (const std::string fields : {"Transfer-Encoding: xchunked\r\n",
                                   "Transfer-Encoding: chunked, identity\r\n",
                                   "Transfer-Encoding: identity\r\n",
                                   "Transfer-Encoding: chunked\r\nTransfer-Encoding: chunked\r\n",
                                   "Transfer-Encoding: chunked\r\nContent-Length: 5\r\n",
                                   "Content-Length: 5\r\nTransfer-Encoding: chunked\r\n",
                                   "Content-Length: 0\r\nContent-Length: 5\r\n",
                                   "Content-Length: 5\r\nAuthorization: Bearer a\r\nAuthorization: Bearer b\r\n",
                                   "Content-Length: 5\r\nHost: 127.0.0.1\r\n"}) {
    HttpClient c(ts.port());
    const auto out = c.raw(head + fields + "\r\n0\r\n\r\n" + smuggled);
    EXPECT_EQ(out.rfind("HTTP/1.1 400 ", 0), 0u) << fields << out;
    EXPECT_EQ(out.find("HTTP/1.1 ", 1), std::string::npos) << fields << "a second answer: " << out;
    EXPECT_TRUE(c.ec) << fields << "still open";
  }
  // HTTP/1.0 has no chunked coding.
  HttpClient old(ts.port());
  auto out = old.raw("POST /x HTTP/1.0\r\nTransfer-Encoding: chunked\r\nContent-Type: application/json\r\n\r\n0\r\n\r\n");
  EXPECT_EQ(out.rfind("HTTP/1.", 0), 0u) << out;
  EXPECT_EQ(out.find(" 400 "), 8u) << out;
  ts.on_io([] {});
  EXPECT_EQ(handled, 0);
  EXPECT_GE(ts.server().stats().refused_framing, 1u);

  // Exactly "chunked", in any case and with spaces, is fine and the
  // connection stays usable.
  HttpClient c(ts.port());
  out = c.raw(head + "Transfer-Encoding:  Chunked \r\n\r\n2\r\n{}\r\n0\r\n\r\n" + smuggled, 1s);
  EXPECT_EQ(out.rfind("HTTP/1.1 200 ", 0), 0u) << out;
  EXPECT_NE(out.find("HTTP/1.1 200 ", 1), std::string::npos) << "the pipelined request is answered too: " << out;
  ts.on_io([] {});
  EXPECT_EQ(handled, 2);
}

// --- browsers: Host and Origin ------------------------------------------------

// What any web page the operator opens could send to the no-token loopback
// gateway is refused; the dashboard's own requests, scripts and listed
// origins are not.
TEST(Browsers, CrossSiteWritesAreRefusedSameOriginAccepted) {
  HttpConfig cfg = quick_config();
  cfg.allowed_origins = {"https://scada.example"};
  int handled = 0;
  TestServer ts(cfg, [&](HttpServer& s) {
    s.add_route("POST", "/api/v1/networks/{net}/nodes/{node}/nmt", [&](const Request& r, Responder done) {
      ++handled;
      echo(r, std::move(done));
    });
    s.add_route("GET", "/api/v1/gateway", echo);
  });
  const std::string nmt = "/api/v1/networks/1/nodes/0/nmt";
  const std::string stop = R"({"command":"stop"})";
  const std::string own = "http://127.0.0.1:" + std::to_string(ts.port());
  const auto post = [&](std::vector<std::pair<std::string, std::string>> fields) {
    HttpClient c(ts.port());
    return c.request(bhttp::verb::post, nmt, stop, std::move(fields));
  };
  // A form or a text/plain fetch from another site (no CORS preflight).
  auto res = post({{"Content-Type", "text/plain;charset=UTF-8"}, {"Origin", "https://evil.example"}});
  EXPECT_EQ(res.result_int(), 403u) << res.body();
  EXPECT_EQ(res[bhttp::field::content_type], "application/problem+json");
  EXPECT_FALSE(res.keep_alive());
  // A JSON one too, with or without a token.
  EXPECT_EQ(post({{"Content-Type", "application/json"}, {"Origin", "https://evil.example"}}).result_int(), 403u);
  EXPECT_EQ(post({{"Content-Type", "application/json"},
                  {"Origin", "https://evil.example"},
                  {"Authorization", "Bearer t"}})
                .result_int(),
            403u);
  // Another service on this machine, or the right host over another scheme, is another origin.
  EXPECT_EQ(post({{"Content-Type", "application/json"}, {"Origin", "http://127.0.0.1:1"}}).result_int(), 403u);
  EXPECT_EQ(post({{"Content-Type", "application/json"}, {"Origin", "https://127.0.0.1:" + std::to_string(ts.port())}})
                .result_int(),
            403u);
  EXPECT_EQ(post({{"Content-Type", "application/json"}, {"Origin", "null"}}).result_int(), 403u);
  // Browsers that send no Origin: a form or text body is not an API call.
  EXPECT_EQ(post({{"Content-Type", "text/plain"}}).result_int(), 415u);
  EXPECT_EQ(post({{"Content-Type", "application/x-www-form-urlencoded"}}).result_int(), 415u);
  EXPECT_EQ(post({}).result_int(), 415u);
  ts.on_io([] {});
  EXPECT_EQ(handled, 0);

  // The dashboard (same origin), a listed origin, a script (no Origin).
  EXPECT_EQ(post({{"Content-Type", "application/json"}, {"Origin", own}}).result_int(), 200u);
  EXPECT_EQ(post({{"Content-Type", "application/json"}, {"Origin", "https://scada.example"}}).result_int(), 200u);
  EXPECT_EQ(post({{"Content-Type", "application/json"}}).result_int(), 200u);
  // Reading with a foreign Origin changes nothing (and the browser keeps
  // the answer from the page: no CORS headers).
  HttpClient c(ts.port());
  res = c.request(bhttp::verb::get, "/api/v1/gateway", {}, {{"Origin", "https://evil.example"}});
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res.count(bhttp::field::access_control_allow_origin), 0u);
  ts.on_io([] {});
  EXPECT_EQ(handled, 3);
  const auto st = ts.server().stats();
  EXPECT_EQ(st.refused_origin, 6u);
  EXPECT_EQ(st.refused_media_type, 3u);
}

class StaticFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() / ("http_static_" + std::to_string(std::random_device{}()));
    fs::create_directories(base_ / "web" / "css");
    std::ofstream(base_ / "web" / "index.html") << "<!doctype html><title>gw</title>";
    std::ofstream(base_ / "web" / "app.js") << "console.log(1);";
    std::ofstream(base_ / "web" / "css" / "site.css") << "body{}";
    std::ofstream(base_ / "web" / ".hidden") << "h";
    std::ofstream(base_ / "secret.txt") << "SECRET";
    fs::create_symlink(base_ / "secret.txt", base_ / "web" / "link.txt");
  }
  void TearDown() override { fs::remove_all(base_); }
  fs::path base_;
};

TEST_F(StaticFiles, ServesDashboardWithContentTypesAndRefusesTraversal) {
  HttpConfig cfg = quick_config();
  cfg.static_dir = base_ / "web";
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("GET", "/api/v1/gateway", echo); });
  HttpClient c(ts.port());
  auto res = c.get("/");
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res[bhttp::field::content_type], "text/html; charset=utf-8");
  EXPECT_EQ(res.body(), "<!doctype html><title>gw</title>");
  // The dashboard may load only its own files and talk only to this server.
  EXPECT_THAT(std::string(res["Content-Security-Policy"]), ::testing::HasSubstr("default-src 'self'"));
  EXPECT_THAT(std::string(res["Content-Security-Policy"]), ::testing::HasSubstr("frame-ancestors 'none'"));
  EXPECT_EQ(res["X-Frame-Options"], "DENY");
  res = c.get("/static/app.js");
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res[bhttp::field::content_type], "text/javascript; charset=utf-8");
  res = c.get("/static/css/site.css");
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res[bhttp::field::content_type], "text/css; charset=utf-8");
  res = c.request(bhttp::verb::head, "/static/app.js");
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res[bhttp::field::content_length], "15");
  EXPECT_EQ(c.get("/api/v1/gateway").result_int(), 200u);

  for (const char* bad : {"/static/../secret.txt", "/static/%2e%2e/secret.txt", "/static/css/..%2F..%2Fsecret.txt",
                          "/static/css%2F..%2F..%2Fsecret.txt", "/static/.hidden", "/static/link.txt",
                          "/static/css", "/static/nope.js", "/static//etc/passwd", "/static/%00"}) {
    HttpClient b(ts.port());
    auto r = b.get(bad);
    EXPECT_EQ(r.result_int(), 404u) << bad;
    EXPECT_EQ(r.body().find("SECRET"), std::string::npos) << bad;
  }
  res = c.request(bhttp::verb::post, "/");
  EXPECT_EQ(res.result_int(), 405u);
  EXPECT_EQ(res[bhttp::field::allow], "GET, HEAD");
}

// DNS rebinding: a page whose own name now resolves to this gateway sends
// its name as Host. Refused on every path: files, API, event stream.
TEST_F(StaticFiles, ForeignHostIsRefusedForFilesApiAndWebSocket) {
  HttpConfig cfg = quick_config();
  cfg.static_dir = base_ / "web";
  cfg.host_names = {"gw.plant.example"};
  TestServer ts(cfg, [](HttpServer& s) { s.add_route("GET", "/api/v1/networks/{net}/nodes/{node}/sdo/{i}/{s}", echo); });
  const std::string port = std::to_string(ts.port());
  const std::string sdo = "/api/v1/networks/1/nodes/5/sdo/1018/1";
  for (const std::string& target : std::vector<std::string>{"/", "/static/app.js", sdo}) {
    HttpClient c(ts.port());
    auto res = c.request(bhttp::verb::get, target, {}, {{"Host", "rebind.attacker.example:" + port}});
    EXPECT_EQ(res.result_int(), 421u) << target;
    EXPECT_EQ(res[bhttp::field::content_type], "application/problem+json") << target;
    EXPECT_EQ(res.body().find("<!doctype"), std::string::npos) << target;
    EXPECT_FALSE(res.keep_alive()) << target;
  }
  WsClient ws(ts.port(), "/api/v1/events", std::nullopt, 0, "rebind.attacker.example:" + port);
  EXPECT_TRUE(ws.ec);
  EXPECT_EQ(ws.response.result_int(), 421u);
  EXPECT_EQ(ts.server().stats().ws_clients, 0u);

  // The gateway's own names.
  for (const std::string& host : std::vector<std::string>{"127.0.0.1:" + port, "localhost:" + port, "LOCALHOST",
                                                         "[::1]:" + port, "gw.plant.example"}) {
    HttpClient c(ts.port());
    EXPECT_EQ(c.request(bhttp::verb::get, sdo, {}, {{"Host", host}}).result_int(), 200u) << host;
  }
  // HTTP/1.1 without Host, or a malformed one: 400; HTTP/1.0 needs none.
  HttpClient none(ts.port());
  auto out = none.raw("GET / HTTP/1.1\r\n\r\n");
  EXPECT_EQ(out.rfind("HTTP/1.1 400 ", 0), 0u) << out;
  HttpClient bad(ts.port());
  out = bad.raw("GET / HTTP/1.1\r\nHost: a b\r\n\r\n");
  EXPECT_EQ(out.rfind("HTTP/1.1 400 ", 0), 0u) << out;
  HttpClient old(ts.port());
  out = old.raw("GET / HTTP/1.0\r\n\r\n");
  EXPECT_EQ(out.rfind("HTTP/1.0 200 ", 0), 0u) << out;
  EXPECT_EQ(ts.server().stats().refused_host, 6u);
}

// --- WebSocket ------------------------------------------------------------

TEST(WebSocket, ReceivesPublishedEventsAsJsonText) {
  TestServer ts(quick_config());
  WsClient ws(ts.port());
  ASSERT_FALSE(ws.ec) << ws.ec.message();
  ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().ws_clients == 1; }));
  for (std::uint64_t i = 1; i <= 3; ++i) ts.publish(make_event(EventKind::Tpdo, 1, 5, i));
  for (std::uint64_t i = 1; i <= 3; ++i) {
    std::string msg;
    ASSERT_FALSE(ws.read(msg)) << ws.ec.message();
    EXPECT_TRUE(ws.ws.got_text());
    EXPECT_EQ(parse_json(msg).at("seq"), i);
  }
  // Plain GET on the event path: 426.
  HttpClient c(ts.port());
  auto res = c.get("/api/v1/events");
  EXPECT_EQ(res.result_int(), 426u);
}

TEST(WebSocket, FilterSelectsNetworkNodeAndKind) {
  TestServer ts(quick_config());
  WsClient ws(ts.port());
  ASSERT_FALSE(ws.ec);
  ASSERT_FALSE(ws.send(R"({"networks":[1],"nodes":[5,10],"kinds":["tpdo","emcy"]})"));
  std::string ack;
  ASSERT_FALSE(ws.read(ack));
  EXPECT_EQ(ack, R"({"subscribed":{"networks":[1],"nodes":[5,10],"kinds":["emcy","tpdo"]}})");

  ts.publish(make_event(EventKind::Tpdo, 1, 5, 1));       // yes
  ts.publish(make_event(EventKind::Tpdo, 2, 5, 2));       // other network
  ts.publish(make_event(EventKind::Tpdo, 1, 6, 3));       // other node
  ts.publish(make_event(EventKind::Heartbeat, 1, 5, 4));  // other kind
  ts.publish(make_event(EventKind::Bus, 1, 0, 5));        // node 0 not listed
  ts.publish(make_event(EventKind::Emcy, 1, 10, 6));      // yes
  std::string msg;
  ASSERT_FALSE(ws.read(msg));
  EXPECT_EQ(parse_json(msg).at("seq"), 1);
  ASSERT_FALSE(ws.read(msg));
  EXPECT_EQ(parse_json(msg).at("seq"), 6);

  // A bad filter is answered with an error and leaves the old one in place.
  ASSERT_FALSE(ws.send(R"({"kinds":["bogus"]})"));
  ASSERT_FALSE(ws.read(msg));
  auto err = parse_json(msg);
  EXPECT_EQ(err.at("error").at("status"), 400);
  ts.publish(make_event(EventKind::Heartbeat, 1, 5, 7));
  ts.publish(make_event(EventKind::Tpdo, 1, 10, 8));
  ASSERT_FALSE(ws.read(msg));
  EXPECT_EQ(parse_json(msg).at("seq"), 8);
}

TEST(WebSocket, ProtobufModeSendsBinaryFrames) {
  TestServer ts(quick_config());
  WsClient ws(ts.port(), "/api/v1/events?format=protobuf");
  ASSERT_FALSE(ws.ec);
  ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().ws_clients == 1; }));
  auto ev = make_event(EventKind::Emcy, 1, 5, 42);
  ts.publish(ev);
  std::string msg;
  ASSERT_FALSE(ws.read(msg));
  EXPECT_FALSE(ws.ws.got_text());
  EXPECT_EQ(msg, ev->binary);
  // Unknown format: 400.
  WsClient bad(ts.port(), "/api/v1/events?format=xml");
  EXPECT_EQ(bad.response.result_int(), 400u);
}

TEST(WebSocket, OriginCheck) {
  HttpConfig cfg = quick_config();
  cfg.allowed_origins = {"https://dash.example"};
  TestServer ts(cfg);
  WsClient evil(ts.port(), "/api/v1/events", "https://evil.example");
  EXPECT_TRUE(evil.ec);
  EXPECT_EQ(evil.response.result_int(), 403u);
  WsClient listed(ts.port(), "/api/v1/events", "https://dash.example");
  EXPECT_FALSE(listed.ec) << listed.ec.message();
  // Same origin as the Host header (the dashboard served by this server).
  WsClient same(ts.port(), "/api/v1/events", "http://127.0.0.1:" + std::to_string(ts.port()));
  EXPECT_FALSE(same.ec) << same.ec.message();
  WsClient none(ts.port());  // not a browser
  EXPECT_FALSE(none.ec);
  // Cross-site WebSocket hijacking from another local service, or from the
  // right host over another scheme.
  WsClient other_port(ts.port(), "/api/v1/events", "http://127.0.0.1:1");
  EXPECT_EQ(other_port.response.result_int(), 403u);
  WsClient other_scheme(ts.port(), "/api/v1/events", "https://127.0.0.1:" + std::to_string(ts.port()));
  EXPECT_EQ(other_scheme.response.result_int(), 403u);
  EXPECT_EQ(ts.server().stats().responses_by_status[403], 3u);
}

TEST(WebSocket, StalledClientDoesNotHoldUpOthers) {
  HttpConfig cfg = quick_config();
  // Slack for the fast reader: 1024 messages = 0.5 s behind (a loaded CI
  // machine); the stalled one fills its queue and buffers in ~0.6 s.
  cfg.ws_queue_max_messages = 1024;
  cfg.ws_stall_timeout = 300ms;
  cfg.ws_socket_send_buffer = 16 * 1024;
  TestServer ts(cfg);
  // Connects, then never reads, with a tiny receive buffer.
  WsClient stalled(ts.port(), "/api/v1/events", std::nullopt, 4096);
  ASSERT_FALSE(stalled.ec);
  WsClient fast(ts.port());
  ASSERT_FALSE(fast.ec);
  ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().ws_clients == 2; }));

  constexpr std::uint64_t kTotal = 3000;
  std::vector<std::uint64_t> got;
  std::thread reader([&] {
    std::string msg;
    while (got.size() < kTotal && !fast.read(msg, 10s)) got.push_back(parse_json(msg).at("seq").to_number<std::uint64_t>());
  });
  // Paced like a busy bus: 10 x 1 KiB every 5 ms (~2 MB/s), on the loop.
  std::promise<void> published;
  auto timer = std::make_shared<net::steady_timer>(ts.ioc());
  auto seq = std::make_shared<std::uint64_t>(0);
  std::function<void()> tick = [&, timer, seq] {
    for (int i = 0; i < 10 && *seq < kTotal; ++i) ts.server().publish(make_event(EventKind::Tpdo, 1, 5, ++*seq, 1000));
    if (*seq >= kTotal) return published.set_value();
    timer->expires_after(5ms);
    timer->async_wait([&](error_code) { tick(); });
  };
  net::post(ts.ioc(), tick);
  ASSERT_EQ(published.get_future().wait_for(15s), std::future_status::ready);
  reader.join();
  ASSERT_EQ(got.size(), kTotal);
  for (std::uint64_t i = 0; i < kTotal; ++i) ASSERT_EQ(got[i], i + 1);  // nothing lost for the fast one
  auto st = ts.server().stats();
  EXPECT_GT(st.ws_messages_dropped, 0u);
  EXPECT_EQ(st.ws_clients_closed_slow, 1u);
  EXPECT_TRUE(ts.wait_until([&] { return ts.server().stats().ws_clients == 1; }));
}

// A stream route (HttpServer::add_stream_route, used by the bus trace): a
// plain GET is 426; the handler may refuse with its own answer; an
// accepted session writes what its source queues, in order, whenever the
// source wakes it, hands client messages to the source and tells it once
// when the connection is gone.
TEST(WebSocket, StreamRouteServesItsSource) {
  struct Source : StreamSource {
    std::deque<std::string> queued;
    std::vector<std::string> received;
    int closes = 0;
    std::shared_ptr<const std::string> next() override {
      if (queued.empty()) return nullptr;
      auto m = std::make_shared<const std::string>(queued.front());
      queued.pop_front();
      return m;
    }
    void on_message(std::string_view text) override {
      received.emplace_back(text);
      queued.push_back("echo " + std::string(text));
    }
    void on_close() override { ++closes; }
  };
  auto source = std::make_shared<Source>();
  source->queued = {"one", "two"};  // queued before the handshake
  TestServer ts(quick_config(), [&](HttpServer& s) {
    s.add_stream_route("/s/{name}", [&](const Request& req) {
      StreamAccept a;
      if (req.param("name") == "ok") a.source = source;
      else a.refusal = Response::problem(404, "no such stream");
      return a;
    });
  });
  EXPECT_EQ(ts.server().routes().back(), (std::pair<std::string, std::string>{"GET", "/s/{name}"}));
  HttpClient plain(ts.port());
  EXPECT_EQ(plain.request(bhttp::verb::get, "/s/ok").result_int(), 426u);
  WsClient refused(ts.port(), "/s/nope");
  EXPECT_TRUE(refused.ec);
  EXPECT_EQ(refused.response.result_int(), 404u);

  WsClient c(ts.port(), "/s/ok");
  ASSERT_FALSE(c.ec) << c.ec.message();
  std::string m;
  ASSERT_FALSE(c.read(m));
  EXPECT_EQ(m, "one");
  ASSERT_FALSE(c.read(m));
  EXPECT_EQ(m, "two");
  ts.on_io([&] {
    source->queued.push_back("three");
    source->wake();
  });
  ASSERT_FALSE(c.read(m));
  EXPECT_EQ(m, "three");
  ASSERT_FALSE(c.send("hello"));
  ASSERT_FALSE(c.read(m));
  EXPECT_EQ(m, "echo hello");
  c.ws.close(websocket::close_code::normal);
  EXPECT_TRUE(ts.wait_until([&] {
    int closes = 0;
    ts.on_io([&] { closes = source->closes; });
    return closes == 1;
  }));
  ts.on_io([&] { EXPECT_EQ(source->received, std::vector<std::string>{"hello"}); });
}

TEST(WebSocket, PingKeepAlive) {
  HttpConfig cfg = quick_config();
  cfg.ws_ping_interval = 150ms;
  TestServer ts(cfg);
  WsClient alive(ts.port());
  WsClient silent(ts.port());  // never reads, so never answers a ping
  ASSERT_FALSE(alive.ec);
  ASSERT_FALSE(silent.ec);
  ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().ws_clients == 2; }));
  // Reading answers pings (Beast does); nothing else arrives meanwhile.
  auto reading = std::async(std::launch::async, [&] {
    std::string msg;
    return alive.read(msg, 1500ms);
  });
  // The silent client is dropped after about two intervals; the answering
  // one stays.
  EXPECT_TRUE(ts.wait_until([&] { return ts.server().stats().ws_clients == 1; }, 1200ms));
  EXPECT_EQ(reading.get(), net::error::timed_out);
  EXPECT_GE(alive.pings, 2);
}

TEST(WebSocket, StopClosesClientsWithGoingAway) {
  auto ts = std::make_unique<TestServer>(quick_config());
  WsClient ws(ts->port());
  ASSERT_FALSE(ws.ec);
  ASSERT_TRUE(ts->wait_until([&] { return ts->server().stats().ws_clients == 1; }));
  ts->on_io([&] { ts->server().stop(); });
  std::string msg;
  EXPECT_EQ(ws.read(msg), websocket::error::closed);
  EXPECT_EQ(ws.ws.reason().code, websocket::close_code::going_away);
}

// --- TLS --------------------------------------------------------------------

namespace {

// Self-signed EC certificate for "localhost"/127.0.0.1, written as PEM.
void make_self_signed(const fs::path& cert, const fs::path& key) {
  EVP_PKEY* pkey = EVP_EC_gen("P-256");
  ASSERT_NE(pkey, nullptr);
  X509* x = X509_new();
  X509_set_version(x, 2);
  ASN1_INTEGER_set(X509_get_serialNumber(x), 1);
  X509_gmtime_adj(X509_getm_notBefore(x), -60);
  X509_gmtime_adj(X509_getm_notAfter(x), 3600);
  X509_set_pubkey(x, pkey);
  X509_NAME* name = X509_get_subject_name(x);
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC, reinterpret_cast<const unsigned char*>("localhost"), -1, -1,
                             0);
  X509_set_issuer_name(x, name);
  ASSERT_GT(X509_sign(x, pkey, EVP_sha256()), 0);
  FILE* f = std::fopen(cert.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  PEM_write_X509(f, x);
  std::fclose(f);
  f = std::fopen(key.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  PEM_write_PrivateKey(f, pkey, nullptr, nullptr, 0, nullptr, nullptr);
  std::fclose(f);
  X509_free(x);
  EVP_PKEY_free(pkey);
}

}  // namespace

class Tls : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("http_tls_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
    make_self_signed(dir_ / "cert.pem", dir_ / "key.pem");
  }
  void TearDown() override { fs::remove_all(dir_); }
  HttpConfig config() {
    HttpConfig c = quick_config();
    c.cert_file = dir_ / "cert.pem";
    c.key_file = dir_ / "key.pem";
    return c;
  }
  fs::path dir_;
};

TEST_F(Tls, HttpsAndWssWorkAndPlainHttpIsRefused) {
  TestServer ts(config(), [](HttpServer& s) { s.add_route("GET", "/api/v1/gateway", echo); });
  net::ssl::context ctx(net::ssl::context::tls_client);
  ctx.load_verify_file((dir_ / "cert.pem").string());
  ctx.set_verify_mode(net::ssl::verify_peer);

  {
    Driver d;
    beast::ssl_stream<beast::tcp_stream> s(d.ioc, ctx);
    auto cancel = [&] { beast::get_lowest_layer(s).socket().close(); };
    ASSERT_FALSE(d.run([&](auto h) { beast::get_lowest_layer(s).socket().async_connect({net::ip::make_address("127.0.0.1"), ts.port()}, h); }, cancel));
    auto ec = d.run([&](auto h) { s.async_handshake(net::ssl::stream_base::client, h); }, cancel);
    ASSERT_FALSE(ec) << ec.message();
    for (int i = 0; i < 2; ++i) {  // keep-alive over TLS
      bhttp::request<bhttp::string_body> req{bhttp::verb::get, "/api/v1/gateway", 11};
      req.set(bhttp::field::host, "localhost");
      ASSERT_FALSE(d.run([&](auto h) { bhttp::async_write(s, req, h); }, cancel));
      beast::flat_buffer buf;
      bhttp::response<bhttp::string_body> res;
      ASSERT_FALSE(d.run([&](auto h) { bhttp::async_read(s, buf, res, h); }, cancel));
      EXPECT_EQ(res.result_int(), 200u);
      EXPECT_EQ(parse_json(res.body()).at("path"), "/api/v1/gateway");
      EXPECT_EQ(res["Strict-Transport-Security"], "max-age=31536000");  // browsers stay on HTTPS
    }
  }
  {
    Driver d;
    websocket::stream<beast::ssl_stream<beast::tcp_stream>> ws(d.ioc, ctx);
    auto cancel = [&] { beast::get_lowest_layer(ws).socket().close(); };
    ASSERT_FALSE(d.run([&](auto h) { beast::get_lowest_layer(ws).socket().async_connect({net::ip::make_address("127.0.0.1"), ts.port()}, h); }, cancel));
    ASSERT_FALSE(d.run([&](auto h) { ws.next_layer().async_handshake(net::ssl::stream_base::client, h); }, cancel));
    auto ec = d.run([&](auto h) { ws.async_handshake("localhost", "/api/v1/events", h); }, cancel);
    ASSERT_FALSE(ec) << ec.message();
    ASSERT_TRUE(ts.wait_until([&] { return ts.server().stats().ws_clients == 1; }));
    ts.publish(make_event(EventKind::Emcy, 1, 5, 9));
    beast::flat_buffer buf;
    ASSERT_FALSE(d.run([&](auto h) { ws.async_read(buf, h); }, cancel));
    EXPECT_EQ(parse_json(beast::buffers_to_string(buf.data())).at("seq"), 9);
  }
  {
    HttpClient plain(ts.port());
    ASSERT_FALSE(plain.ec);
    auto out = plain.raw("GET /api/v1/gateway HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    EXPECT_EQ(out.find("HTTP/1.1 200"), std::string::npos) << out;
    EXPECT_EQ(out.find("/api/v1/gateway"), std::string::npos);
    EXPECT_TRUE(plain.ec);  // closed by the server
    EXPECT_TRUE(ts.wait_until([&] { return ts.server().stats().tls_handshake_failures >= 1; }));
  }
}

TEST(TlsConfig, BadFilesAreRefusedAtConstruction) {
  net::io_context ioc;
  HttpConfig c;
  c.cert_file = "/nonexistent/cert.pem";
  c.key_file = "/nonexistent/key.pem";
  EXPECT_THROW(HttpServer(ioc, c), std::runtime_error);
  c.key_file.clear();
  EXPECT_THROW(HttpServer(ioc, c), std::runtime_error);
}
