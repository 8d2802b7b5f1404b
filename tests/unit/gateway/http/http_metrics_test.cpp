// The HTTP server's metrics as it registers them (gateway/http/http_metrics.hpp):
// the families /metrics has always had, read from stats() at scrape time.
#include "http/http_metrics.hpp"

#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <chrono>
#include <string>
#include <thread>
#include <utility>

namespace gateway::http {
namespace {

namespace asio = boost::asio;

// The HTTP server's part of /metrics for fixed values.
std::string http_part(const metrics::HttpServerMetrics& m) {
  metrics::Registry r;
  metrics::register_http_server(r, [m] { return m; });
  return r.render();
}

TEST(HttpMetrics, RegisteredFamiliesFollowTheServer) {
  asio::io_context ioc;
  HttpConfig cfg;
  cfg.port = 0;
  HttpServer server(ioc, cfg);
  server.add_route("GET", "/ok", [](const Request&, Responder respond) {
    Response r;
    r.status = 200;
    respond(std::move(r));
  });
  metrics::Registry r;
  register_metrics(r, server);

  EXPECT_EQ(r.render(), http_part(metrics::HttpServerMetrics{}));

  server.start();
  auto guard = asio::make_work_guard(ioc);
  std::thread io([&] { ioc.run(); });
  {
    asio::io_context client_io;
    asio::ip::tcp::socket sock(client_io);
    sock.connect({asio::ip::make_address("127.0.0.1"), server.bound_port()});
    const std::string req = "GET /ok HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(server.bound_port()) +
                            "\r\nConnection: close\r\n\r\n";
    asio::write(sock, asio::buffer(req));
    boost::system::error_code ec;
    std::string reply;
    asio::read(sock, asio::dynamic_buffer(reply), ec);  // until the server closes
    EXPECT_EQ(reply.substr(0, 12), "HTTP/1.1 200");
  }
  // The count is taken when the response is written and the connection is
  // closed after it, on the io thread: wait for both (bounded), so the
  // snapshot below and the render after it see the same, settled stats.
  const auto settled = [&] {
    const HttpStats s = server.stats();
    return !s.responses_by_status.empty() && s.connections_active == 0;
  };
  for (int i = 0; i < 500 && !settled(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const HttpStats stats = server.stats();
  metrics::HttpServerMetrics after;
  after.responses_by_status = stats.responses_by_status;
  after.connections = to_metrics(stats).connections;
  const std::string text = r.render();
  EXPECT_EQ(text, http_part(after));
  EXPECT_NE(text.find("canopen_gateway_http_responses_total{code=\"200\"} 1\n"), std::string::npos);
  guard.reset();
  asio::post(ioc, [&] { server.stop(); });
  io.join();
}

}  // namespace
}  // namespace gateway::http
