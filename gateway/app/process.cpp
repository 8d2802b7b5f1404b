#include "app/process.hpp"

#include <algorithm>
#include <pthread.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include "app/app.hpp"
#include "ascii/ascii_listen.hpp"
#include "ascii/ascii_server.hpp"
#include "canopen/socketcan/channel.hpp"
#include "app/composition.hpp"
#include "config/config.hpp"
#include "app/front_ends.hpp"
#include "http/http_server.hpp"
#include "log.hpp"
#include "mqtt/client.hpp"
#include "mqtt/mqtt_connection.hpp"
#include "mqtt/publisher.hpp"

namespace gateway {

namespace {

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

}  // namespace

// Checked before anything starts, so a bad URI is a configuration error.
void check_mqtt_uris(const Config& c) {
  // Every broker of a list, each once when normalized (mqtt://a and tcp://a are one).
  auto check = [](const mqtt::MqttConfig& m, const std::string& origin) {
    std::vector<std::string> seen;
    for (const auto& uri : m.uris()) {
      try {
        auto normalized = mqtt::normalize_server_uri(uri);
        (void)mqtt::parse_endpoint(normalized);
        if (std::find(seen.begin(), seen.end(), normalized) != seen.end())
          throw std::invalid_argument("'" + uri + "' is the same broker as another URI of the list");
        seen.push_back(std::move(normalized));
      } catch (const std::invalid_argument& e) {
        throw ConfigError(origin + ": " + e.what());
      }
    }
  };
  if (c.mqtt.enabled) check(c.mqtt, c.mqtt.uri_origin);
  if (c.sparkplug.enabled) check(c.sparkplug.mqtt, c.sparkplug.uri_origin);
}

namespace {

// Why the listener could not be opened, for a person: the errno in words
// and what usually helps, without the library's internals.
std::string listen_failure(const std::system_error& e) {
  const auto ec = e.code();
  if (ec == std::errc::address_in_use) return "address already in use (is another gateway running?)";
  if (ec == std::errc::permission_denied)
    return "permission denied (ports below 1024 need root or CAP_NET_BIND_SERVICE)";
  if (ec == std::errc::address_not_available) return "address not available (not an address of this machine)";
  return ec.message();
}

// A host for URLs a person can paste: the listen address, or for a
// wildcard listener this machine's name (which the Host check accepts).
std::string url_host(const std::string& address) {
  if (address == "0.0.0.0" || address == "::") {
    char name[256] = {};
    if (::gethostname(name, sizeof name - 1) == 0 && name[0] != '\0' && std::string(name) != "(none)" &&
        std::string(name).find_first_of(" /:[]@") == std::string::npos)
      return name;
    return "127.0.0.1";
  }
  return address.find(':') != std::string::npos ? "[" + address + "]" : address;
}

// One line per thing a person may open, with its URL.
void log_listeners(Logger& log, const Config& config, unsigned port) {
  const auto& h = config.http;
  const bool tls = !h.cert_file.empty();
  const std::string authority = url_host(h.address) + ":" + std::to_string(port);
  const std::string base = (tls ? "https://" : "http://") + authority;
  std::string scope;
  if (h.address == "0.0.0.0") scope = "listening on 0.0.0.0, every IPv4 address of this machine";
  else if (h.address == "::") scope = "listening on ::, every address of this machine";
  else if (h.loopback()) scope = "this machine only";
  else scope = "listening on " + h.address;
  const bool token = h.anonymous_role() == Role::None;
  log.info("HTTP/WebSocket on " + base + " (" + scope + ")");
  log.info("dashboard: " + base + "/");
  log.info("REST API: " + base + "/api/v1/ (OpenAPI description: " + base + "/api/v1/openapi.json" +
           (token ? "; needs a bearer token)" : ")"));
  log.info("events (WebSocket): " + std::string(tls ? "wss://" : "ws://") + authority + "/api/v1/events" +
           (token ? " (needs a bearer token)" : ""));
  log.info("metrics: " + base + "/metrics" + (token ? " (needs a bearer token)" : ""));
}

}  // namespace

void print_error(const std::string& msg) {
  std::fprintf(stderr, "canopen-gateway: error: %s\n", printable(msg).c_str());
}

int run_gateway(const CliOptions& opts) {
  Config config;
  try {
    config = merge(opts.config_file ? load_config(*opts.config_file) : Config{}, opts);
    check_mqtt_uris(config);
    // Before CAN is opened and anything listens: a state directory that
    // cannot be written is a configuration error, not a failure later.
    check_state_dirs(config);
  } catch (const ConfigError& e) {
    print_error(e.what());
    return kExitConfig;
  }
  Logger log(config.log_level);
  // One thread runs it (the guide's one loop): hint 1 lets a handler's
  // post() go to that thread's own queue instead of waking the reactor
  // (an epoll_ctl and an extra epoll_wait per post; issue 28 item 5).
  // Other threads may still post: the hint keeps the locking.
  boost::asio::io_context io{1};

  std::unique_ptr<App> app;
  try {
    // The composition root: one unit per network, its channel opened.
    auto networks = compose_networks(io, config, log);
    app = std::make_unique<App>(io, config, log, std::move(networks));
    // MQTT requests on the App's MQTT session, the Sparkplug B edge node on
    // its own: front ends on the same request core (its /metrics families
    // before the HTTP server's, as always).
    serve_mqtt_requests(*app, log);
    add_sparkplug(io, *app, log);
  } catch (const std::invalid_argument& e) {
    print_error(std::string("sparkplug: ") + e.what());
    return kExitConfig;
  } catch (const ConfigError& e) {
    print_error(e.what());
    return kExitConfig;
  } catch (const canopen::socketcan::CanUnavailable& e) {
    print_error(e.what());
    return kExitCanUnavailable;
  }

  // The server's part of the configuration, as parsed.
  http::HttpConfig http_cfg = config.http;
  if (http_cfg.static_dir.empty()) http_cfg.static_dir = default_web_root();
  if (http_cfg.static_dir.empty()) log.warn("http: no dashboard files found; set http.web-root");
  std::unique_ptr<http::HttpServer> http;
  try {
    http = std::make_unique<gateway::http::HttpServer>(io, http_cfg, &log);
  } catch (const std::exception& e) {
    // TLS files that do not load (the rest was checked with the configuration).
    print_error((config.http.tls_origin.empty() ? std::string("http") : config.http.tls_origin) + ": " + e.what());
    return kExitConfig;
  }
  connect_event_stream(*http, *app);
  if (config.http.auth && config.http.tokens.empty())
    log.warn("http: no tokens configured: every local process may use the API as admin (loopback only)");
  install_http_api(*http, *app);
  try {
    http->start();
  } catch (const std::system_error& e) {
    print_error(config.http.listen_origin + ": " + listen_failure(e));
    return kExitConfig;
  }
  log_listeners(log, config, http->bound_port());

  // The CiA 309-3 ASCII interface, after HTTP: the same request core.
  std::unique_ptr<ascii::Server> ascii;
  if (config.ascii.enabled) {
    // lss_* through the request core's LSS commands (role admin).
    ascii = make_ascii_server(io, *app, log);
    try {
      ascii->start();
    } catch (const std::system_error& e) {
      print_error(config.ascii.listen_origin + ": " + listen_failure(e));
      return kExitConfig;
    }
    const std::string where = ascii->local_address();
    log.info("CiA 309-3 ASCII on " + where + " (" +
             (where.rfind("unix:", 0) == 0 ? std::string("unix socket, mode 0660")
              : config.ascii.allow_remote && !gateway::ascii::parse_listen_address(where)->local()
                  ? std::string("reachable from other machines: no authentication")
                  : std::string("this machine only")) +
             "; clients act as " + std::string(to_string(config.ascii.role.value_or(Role::Operator))) + ")");
  }

  app->start();

  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int sig) {
    if (ec) return;
    log.info(std::string("received ") + (sig == SIGINT ? "SIGINT" : "SIGTERM") + ", shutting down");
    if (ascii) ascii->stop();
    http->stop();
    app->stop();
    io.stop();
  });
  io.run();
  // Stopping: a second SIGTERM (timeout(1) and systemd signal the process
  // group as well as the process) must not turn the clean stop into a kill
  // once the signal_set is gone and the default action is back.
  sigset_t stopping;
  sigemptyset(&stopping);
  sigaddset(&stopping, SIGINT);
  sigaddset(&stopping, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stopping, nullptr);  // covers the moment between the next two lines
  signals.clear();
  std::signal(SIGINT, SIG_IGN);
  std::signal(SIGTERM, SIG_IGN);
  ascii.reset();
  app.reset();
  http.reset();
  log.info("stopped");
  log.flush();
  return 0;
}

}  // namespace gateway
