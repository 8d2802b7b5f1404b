// Streamed responses (Response::stream, BodySink): the header goes out at
// once and the body as the route produces it, in HTTP/1.1 chunks (RFC 9112
// 7.1) or raw to an HTTP/1.0 client; a client that goes away stops the
// route and frees the sink; one that does not read costs a bounded buffer.
// The client is a plain socket, so what is on the wire is what is tested.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/time.h>

#include <atomic>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/write.hpp>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>

#include "http/http_server.hpp"

namespace {

namespace net = boost::asio;
using tcp = net::ip::tcp;
using gateway::http::BodySink;
using gateway::http::HttpConfig;
using gateway::http::HttpServer;
using gateway::http::Request;
using gateway::http::Responder;
using gateway::http::Response;
using namespace std::chrono_literals;

// The server on its own thread; the route keeps the sink it was given.
class StreamServer {
 public:
  explicit StreamServer(std::size_t buffer_bytes = 1u << 20) {
    HttpConfig cfg;
    cfg.address = "127.0.0.1";
    cfg.port = 0;
    server_ = std::make_unique<HttpServer>(ioc_, cfg);
    server_->add_route("GET", "/stream", [this, buffer_bytes](const Request&, Responder respond) {
      Response r;
      r.content_type = "application/octet-stream";
      r.headers.emplace_back("Content-Disposition", "attachment; filename=\"x.bin\"");
      r.stream_buffer_bytes = buffer_bytes;
      r.stream = [this](std::shared_ptr<BodySink> s) {
        ++started;
        s->on_close = [this] {
          closed_seen = true;
          sink.reset();  // the route lets go; the connection's reference is all that is left
        };
        s->write("hello");
        weak = s;
        sink = std::move(s);
      };
      respond(std::move(r));
    });
    server_->start();
    thread_ = std::thread([this] { ioc_.run(); });
  }
  ~StreamServer() {
    on_io([this] {
      sink.reset();
      server_->stop();
      return 0;
    });
    guard_.reset();
    ioc_.stop();
    thread_.join();
  }
  std::uint16_t port() const { return server_->bound_port(); }

  // Runs f on the server's thread and waits for it.
  template <typename F>
  std::invoke_result_t<F> on_io(F f) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto fut = task.get_future();
    net::post(ioc_, [&task] { task(); });
    EXPECT_EQ(fut.wait_for(5s), std::future_status::ready);
    return fut.get();
  }
  static bool wait_until(const std::function<bool()>& pred) {
    const auto end = std::chrono::steady_clock::now() + 5s;
    while (!pred()) {
      if (std::chrono::steady_clock::now() > end) return false;
      std::this_thread::sleep_for(5ms);
    }
    return true;
  }

  // Route state, touched on the io thread (atomics read from the test's).
  std::shared_ptr<BodySink> sink;
  std::weak_ptr<BodySink> weak;
  std::atomic<int> started{0};
  std::atomic<bool> closed_seen{false};

 private:
  net::io_context ioc_;
  net::executor_work_guard<net::io_context::executor_type> guard_{ioc_.get_executor()};
  std::unique_ptr<HttpServer> server_;
  std::thread thread_;
};

// A blocking client whose reads give up after 5 s (SO_RCVTIMEO).
struct RawClient {
  explicit RawClient(std::uint16_t port, int rcvbuf = 0) : sock(io) {
    sock.open(tcp::v4());
    if (rcvbuf > 0) sock.set_option(net::socket_base::receive_buffer_size(rcvbuf));
    timeval tv{5, 0};
    ::setsockopt(sock.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    sock.connect({net::ip::make_address("127.0.0.1"), port});
  }
  void send_request(const std::string& method = "GET", const std::string& version = "HTTP/1.1") {
    net::write(sock, net::buffer(method + " /stream " + version + "\r\nHost: 127.0.0.1\r\n\r\n"));
  }
  // Reads until `needle` is in what was received; false on timeout or close.
  bool read_until(const std::string& needle) {
    boost::system::error_code ec;
    net::read_until(sock, net::dynamic_buffer(got), needle, ec);
    return !ec;
  }
  std::string read_to_close() {
    boost::system::error_code ec;
    net::read(sock, net::dynamic_buffer(got), ec);
    return got;
  }
  std::string head() const { return got.substr(0, got.find("\r\n\r\n") + 4); }
  net::io_context io;
  tcp::socket sock;
  std::string got;
};

// The body of a chunked message: the chunks' data, and whether the last
// chunk (size 0) ended it.
std::pair<std::string, bool> dechunk(std::string_view raw) {
  std::string out;
  std::size_t pos = 0;
  while (pos < raw.size()) {
    const auto eol = raw.find("\r\n", pos);
    if (eol == std::string_view::npos) break;
    const auto n = std::stoul(std::string(raw.substr(pos, eol - pos)), nullptr, 16);
    if (n == 0) return {out, raw.substr(eol) == "\r\n\r\n"};
    out += raw.substr(eol + 2, n);
    pos = eol + 2 + n + 2;
  }
  return {out, false};
}

TEST(StreamedResponse, ChunksArriveAsTheRouteWritesThem) {
  StreamServer srv;
  RawClient c(srv.port());
  c.send_request();
  // The header and the first piece arrive while the route still holds the body.
  ASSERT_TRUE(c.read_until("hello\r\n")) << c.got;
  const auto head = c.head();
  EXPECT_EQ(head.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << head;
  EXPECT_NE(head.find("Transfer-Encoding: chunked\r\n"), std::string::npos) << head;
  EXPECT_NE(head.find("Content-Type: application/octet-stream\r\n"), std::string::npos) << head;
  EXPECT_NE(head.find("Content-Disposition: attachment; filename=\"x.bin\"\r\n"), std::string::npos) << head;
  EXPECT_NE(head.find("Connection: close\r\n"), std::string::npos) << head;
  EXPECT_EQ(head.find("Content-Length"), std::string::npos) << head;
  EXPECT_EQ(c.got.substr(head.size()), "5\r\nhello\r\n");

  srv.on_io([&] { return srv.sink->write(", world"); });
  ASSERT_TRUE(c.read_until("world\r\n"));
  srv.on_io([&] {
    srv.sink->finish("!");
    EXPECT_FALSE(srv.sink->write("late")) << "nothing after finish";
    return 0;
  });
  const auto all = c.read_to_close();
  const auto [body, complete] = dechunk(std::string_view(all).substr(head.size()));
  EXPECT_EQ(body, "hello, world!");
  EXPECT_TRUE(complete) << "the last chunk ends the body";
  EXPECT_FALSE(srv.closed_seen) << "a finished body is no disconnect";
}

// A client that goes away: the route hears it at once, though it is not
// writing, and the sink is freed once the route lets go of it.
TEST(StreamedResponse, DisconnectClosesTheSinkAndFreesIt) {
  StreamServer srv;
  {
    RawClient c(srv.port());
    c.send_request();
    ASSERT_TRUE(c.read_until("hello\r\n"));
  }  // closed
  ASSERT_TRUE(StreamServer::wait_until([&] { return srv.closed_seen.load(); }));
  EXPECT_TRUE(StreamServer::wait_until([&] { return srv.on_io([&] { return srv.weak.expired(); }); }))
      << "the connection holds no sink after the close";
}

// A client that does not read: the sink takes at most its bound (plus what
// the sockets hold), then refuses, and the loop keeps running; what was
// taken arrives complete and in order when the client reads again.
TEST(StreamedResponse, ClientThatDoesNotReadCostsTheBoundThenWritesAreRefused) {
  constexpr std::size_t kBound = 64 * 1024;
  StreamServer srv(kBound);
  RawClient c(srv.port(), 4096);
  c.send_request();
  ASSERT_TRUE(c.read_until("hello\r\n"));
  std::string piece(1000, 'x');
  std::size_t taken = 0, refused = 0;
  std::uint32_t n = 0;
  // Numbered pieces until well past what kernel buffers and the bound hold.
  while (refused < 100 && n < 20000) {
    std::snprintf(piece.data(), 12, "%010u|", n++);
    const bool ok = srv.on_io([&] { return srv.sink->write(piece); });
    ok ? ++taken : ++refused;
  }
  EXPECT_EQ(refused, 100u) << "the sink never refused: unbounded";
  EXPECT_LT(taken * piece.size(), 16u << 20);
  srv.on_io([&] {
    srv.sink->finish();
    return 0;
  });
  const auto all = c.read_to_close();
  const auto [body, complete] = dechunk(std::string_view(all).substr(c.head().size()));
  EXPECT_TRUE(complete);
  ASSERT_EQ(body.size(), 5 + taken * piece.size());
  // In order, with no piece torn: the refused ones are simply missing.
  std::uint32_t prev = 0;
  for (std::size_t i = 0; i < taken; ++i) {
    const auto at = 5 + i * piece.size();
    EXPECT_EQ(body[at + 10], '|');
    const auto no = static_cast<std::uint32_t>(std::stoul(body.substr(at, 10)));
    if (i > 0) {
      EXPECT_GT(no, prev);
    }
    prev = no;
  }
}

// HTTP/1.0 has no chunks: the raw bytes, ended by the close. HEAD: the
// header fields only; the route's stream is not started.
TEST(StreamedResponse, Http10GetsRawBytesAndHeadGetsTheHeaderOnly) {
  StreamServer srv;
  {
    RawClient c(srv.port());
    c.send_request("GET", "HTTP/1.0");
    ASSERT_TRUE(c.read_until("hello"));
    srv.on_io([&] {
      srv.sink->write(" there");
      srv.sink->finish();
      return 0;
    });
    const auto all = c.read_to_close();
    EXPECT_EQ(all.find("Transfer-Encoding"), std::string::npos) << all;
    EXPECT_EQ(all.substr(all.find("\r\n\r\n") + 4), "hello there");
  }
  RawClient h(srv.port());
  h.send_request("HEAD");
  const auto all = h.read_to_close();
  EXPECT_EQ(all.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << all;
  EXPECT_EQ(all.substr(all.find("\r\n\r\n") + 4), "");
  EXPECT_EQ(srv.started, 1) << "only the GET started the stream";
}

}  // namespace
