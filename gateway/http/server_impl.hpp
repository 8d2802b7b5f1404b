// Internal to the HTTP server (not installed; its own .cpp files only): the
// state the listener, the HTTP and WebSocket sessions and HttpServer share.
// No Beast here (beast_types.hpp has the Beast types).
#pragma once

#include <array>
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <unistd.h>
#include <unordered_map>
#include <utility>
#include <vector>

#include "http/http_server.hpp"
#include "http/request_checks.hpp"
#include "http/router.hpp"
#include "log.hpp"

namespace gateway::http {

namespace net = boost::asio;
using tcp = net::ip::tcp;
using error_code = boost::system::error_code;

constexpr std::string_view kEventsPath = "/api/v1/events";
constexpr auto kCloseGrace = std::chrono::seconds(2);

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
  // When it began waiting for a request, as a number that grows with time
  // (nullopt: busy, or not an HTTP connection): such a connection may be
  // closed for a new one, the one waiting longest (the lowest) first.
  virtual std::optional<std::uint64_t> idle_since() const { return std::nullopt; }
  // Whether it is a connection from client address `key` (address_key).
  virtual bool from_address(const std::string& /*key*/) const { return false; }
};

// "address:port", IPv6 addresses in brackets.
std::string endpoint_string(const tcp::endpoint& ep);

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
  std::uint64_t idle_order = 0;  // Connection::idle_since(): counts idle starts
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
  // Closes the longest idle connection (of client address `key`, or of any
  // when it is null); false when there is none.
  bool evict_idle(const std::string* key = nullptr);
  void note_refusal(const std::string& key, const std::string& message);
  void stop();
};

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
  const std::string& address() const { return address_; }

 private:
  std::shared_ptr<HttpServer::Impl> impl_;
  std::string address_;
};

using SlotPtr = std::shared_ptr<AddressSlot>;

}  // namespace gateway::http
