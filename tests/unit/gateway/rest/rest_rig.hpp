// Test rig for the REST tests: the whole gateway (App) on the simulated
// demo network (nodes 5: CiA 402 drive, 10 and 11: CiA 401 I/O) with an
// HttpServer carrying the API as canopen-gateway installs it
// (install_http_api(), app/front_ends.hpp) on an ephemeral 127.0.0.1 port.
// The client is a plain blocking socket on its own thread (one request per
// connection, "Connection: close"; no Beast); the test thread runs the
// io_context meanwhile.
#pragma once

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/json.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "app/app.hpp"
#include "app/front_ends.hpp"
#include "log.hpp"
#include "rest/rest_api.hpp"
#include "unit/gateway/rest/http_fetch.hpp"

namespace gateway::test {

using namespace std::chrono_literals;
namespace json = boost::json;

using testing::fetch;
using testing::HttpReply;

struct RestRig {
  // `configure` may change the demo configuration (e.g. turn auth on with
  // tokens). The rate limit is off unless it sets one. The log goes to
  // `log_to` (default stderr, errors only; given: info and up, for audit
  // lines); `static_dir` serves a dashboard. `before_start` runs after the
  // App is built and before it starts (e.g. to change a simulated device).
  explicit RestRig(std::chrono::milliseconds emcy_period = {}, const std::function<void(Config&)>& configure = {},
                   std::FILE* log_to = nullptr, const std::filesystem::path& static_dir = {},
                   const std::function<void(App&)>& before_start = {}) {
    CliOptions cli;
    cli.demo = true;
    cli.gateway_id = "test";
    Config c = merge(Config{}, cli);
    c.state_dir.clear();  // keep no seq between tests (seq_store.hpp)
    if (emcy_period.count() > 0) c.networks.at(0).simulation.emcy_period = emcy_period;
    c.http.rate_limit = 0;
    if (configure) configure(c);
    log = log_to != nullptr ? std::make_unique<Logger>(LogLevel::Info, log_to) : std::make_unique<Logger>(LogLevel::Error);
    app = std::make_unique<App>(io, c, *log);
    // The front ends as canopen-gateway makes them (app/front_ends.hpp).
    serve_mqtt_requests(*app, *log);
    add_sparkplug(io, *app, *log);
    http::HttpConfig hc;
    hc.address = "127.0.0.1";
    hc.port = 0;
    hc.static_dir = static_dir;
    server = std::make_unique<http::HttpServer>(io, hc);
    // The authorizer and the routes as canopen-gateway installs them (demo:
    // auth off, everyone admin).
    install_http_api(*server, *app);
    if (before_start) before_start(*app);
    app->start();
    server->start();
    port = server->bound_port();
  }
  ~RestRig() {
    server->stop();
    app->stop();
    io.run_for(50ms);
  }

  template <typename Pred>
  bool run_until(Pred pred, std::chrono::milliseconds limit = 10s) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!pred() && std::chrono::steady_clock::now() < end) io.run_for(10ms);
    return pred();
  }

  // `limit`: how long to wait for the answer (a large upload under ASan on
  // a loaded machine takes long; this is a deadline, not a timing assertion).
  HttpReply request(std::string method, std::string target, std::string body = {},
                    std::vector<std::string> headers = {}, std::chrono::milliseconds limit = 10s) {
    const bool typed = std::any_of(headers.begin(), headers.end(),
                                   [](const std::string& h) { return h.rfind("Content-Type:", 0) == 0; });
    if (!body.empty() && !typed) headers.push_back("Content-Type: application/json");
    auto f = std::async(std::launch::async, fetch, port, method, target, body, headers);
    auto ready = [&] { return f.wait_for(0s) == std::future_status::ready; };
    const bool done = run_until(ready, limit);
    EXPECT_TRUE(done) << method << " " << target << ": no answer";
    if (!done) {
      // Closing every connection ends the client's read, so the future
      // (whose destructor waits for the thread) does not block the test.
      server->stop();
      run_until(ready, 5s);
      return {};
    }
    return f.get();
  }

  bool operational(std::uint8_t node) const {
    const auto* n = app->cache().node(1, node);
    return n != nullptr && n->state == canopen::NmtState::Operational;
  }
  bool all_operational() const { return operational(5) && operational(10) && operational(11); }

  boost::asio::io_context io;
  std::unique_ptr<Logger> log;
  std::unique_ptr<App> app;
  std::unique_ptr<http::HttpServer> server;
  std::uint16_t port = 0;
};

}  // namespace gateway::test
