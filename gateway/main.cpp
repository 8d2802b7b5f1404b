// canopen-gateway: reads the configuration (YAML file + the contract's
// flags), opens every CAN network (or the simulated demo network) and runs
// everything on one io_context: the CANopen stack, MQTT publishing and the
// HTTP/WebSocket server. See gateway/app/app.hpp.
#include <csignal>
#include <filesystem>
#include <cstdio>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include "app.hpp"
#include "canopen/socketcan/channel.hpp"
#include "cli.hpp"
#include "config.hpp"
#include "http_server.hpp"
#include "log.hpp"
#include "rest_api.hpp"

namespace {

constexpr int kExitConfig = 2;
constexpr int kExitCanUnavailable = 3;

// The dashboard: installed beside the binary (<prefix>/share/canopen-gateway/web),
// else the source tree's web/ (a build run from its checkout); "" = none.
std::filesystem::path default_web_root() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    auto installed = exe.parent_path().parent_path() / "share/canopen-gateway/web";
    if (std::filesystem::is_regular_file(installed / "index.html", ec)) return installed;
  }
  const std::filesystem::path source = CANOPEN_SOURCE_WEB_DIR;
  if (std::filesystem::is_regular_file(source / "index.html", ec)) return source;
  return {};
}

void print_error(const std::string& msg) { std::fprintf(stderr, "canopen-gateway: error: %s\n", msg.c_str()); }

int run(const gateway::CliOptions& opts) {
  gateway::Config config;
  try {
    config = gateway::merge(opts.config_file ? gateway::load_config(*opts.config_file) : gateway::Config{}, opts);
    // Before CAN is opened and anything listens: a state directory that
    // cannot be written is a configuration error, not a failure later.
    gateway::check_state_dirs(config);
  } catch (const gateway::ConfigError& e) {
    print_error(e.what());
    return kExitConfig;
  }
  gateway::Logger log(config.log_level);
  boost::asio::io_context io;

  std::unique_ptr<gateway::App> app;
  try {
    app = std::make_unique<gateway::App>(io, config, log);
  } catch (const gateway::ConfigError& e) {
    print_error(e.what());
    return kExitConfig;
  } catch (const canopen::socketcan::CanUnavailable& e) {
    print_error(e.what());
    return kExitCanUnavailable;
  }

  gateway::http::HttpConfig http_cfg;
  http_cfg.address = config.http.address;
  http_cfg.port = config.http.port;
  http_cfg.cert_file = config.http.cert_file;
  http_cfg.key_file = config.http.key_file;
  http_cfg.host_names = config.http.host_names;
  http_cfg.allowed_origins = config.http.allowed_origins;
  http_cfg.max_connections = config.http.max_connections;
  http_cfg.max_connections_per_address = config.http.max_connections_per_address;
  http_cfg.static_dir = config.http.web_root.empty() ? default_web_root() : std::filesystem::path(config.http.web_root);
  if (http_cfg.static_dir.empty()) log.warn("http: no dashboard files found; set http.web-root");
  std::unique_ptr<gateway::http::HttpServer> http;
  try {
    http = std::make_unique<gateway::http::HttpServer>(io, http_cfg, &log);
    app->add_consumer([srv = http.get()](const gateway::EncodedEventPtr& ev) { srv->publish(ev); });
    app->set_protobuf_demand([srv = http.get()] { return srv->binary_clients() > 0; });
    if (config.http.auth && config.http.tokens.empty())
      log.warn("http: no tokens configured: every local process may use the API as admin (loopback only)");
    http->set_authorizer(app->http_authorizer());
    gateway::register_api_routes(*http, *app);
    http->start();
  } catch (const std::exception& e) {
    print_error("http: cannot listen on " + config.http.address + ":" + std::to_string(config.http.port) + ": " +
                e.what());
    return kExitConfig;
  }
  log.info("HTTP/WebSocket on " + std::string(config.http.cert_file.empty() ? "http://" : "https://") +
           (config.http.address.find(':') != std::string::npos ? "[" + config.http.address + "]"
                                                                : config.http.address) +
           ":" + std::to_string(http->bound_port()) + " (events: /api/v1/events)");

  app->start();

  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int sig) {
    if (ec) return;
    log.info(std::string("received ") + (sig == SIGINT ? "SIGINT" : "SIGTERM") + ", shutting down");
    http->stop();
    app->stop();
    io.stop();
  });
  io.run();
  app.reset();
  http.reset();
  log.info("stopped");
  log.flush();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  gateway::CliOptions opts;
  try {
    opts = gateway::parse_cli(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const gateway::UsageError& e) {
    print_error(e.what());
    return kExitConfig;
  }
  if (opts.help) {
    std::fputs(gateway::usage_text().c_str(), stdout);
    return 0;
  }
  if (opts.version) {
    std::puts("canopen-gateway " CANOPEN_GATEWAY_VERSION);
    return 0;
  }
  try {
    return run(opts);
  } catch (const std::exception& e) {
    print_error(e.what());
    return 1;
  }
}
