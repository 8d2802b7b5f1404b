// Test rig of the ASCII server tests (ascii_server_test.cpp, ascii_lss_test.cpp):
// the whole gateway on the simulated demo network with an ascii::Server on
// an ephemeral 127.0.0.1 port, and a non-blocking client socket, so the test
// thread runs the gateway's io_context while it waits for answers.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "app/app.hpp"
#include "ascii/ascii_server.hpp"
#include "support/memory_log.hpp"

namespace gateway::ascii::test {

using namespace std::chrono_literals;

// A client socket (TCP "127.0.0.1:PORT" or "unix:/path"), read without
// blocking so the test thread can run the gateway's io_context meanwhile.
class Client {
 public:
  explicit Client(const std::string& where) {
    if (where.starts_with("unix:")) {
      fd_ = ::socket(AF_UNIX, SOCK_STREAM, 0);
      sockaddr_un a{};
      a.sun_family = AF_UNIX;
      const std::string path = where.substr(5);
      std::copy(path.begin(), path.end(), a.sun_path);
      connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    } else {
      fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_port = htons(static_cast<std::uint16_t>(std::stoi(where.substr(where.rfind(':') + 1))));
      a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    }
    ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) | O_NONBLOCK);
  }
  ~Client() { ::close(fd_); }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  bool connected() const { return connected_; }
  // Sends what the socket takes now; returns how much.
  std::size_t send_some(std::string_view data) {
    const auto n = ::send(fd_, data.data(), data.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    return n > 0 ? static_cast<std::size_t>(n) : 0;
  }
  void send(std::string_view data) {
    while (!data.empty()) {
      const auto n = send_some(data);
      data.remove_prefix(n);
      if (n == 0) ::poll(nullptr, 0, 1);
    }
  }
  void shutdown_write() { ::shutdown(fd_, SHUT_WR); }
  // Keeps what the kernel takes from this client small, so a server that
  // stops reading shows as a send that stops (not hidden by big buffers).
  void small_send_buffer() {
    const int size = 64 * 1024;
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
  }
  // Takes what arrived; false once the server closed the connection.
  bool poll() {
    char buf[65536];
    for (;;) {
      const auto n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n > 0) {
        received.append(buf, static_cast<std::size_t>(n));
        continue;
      }
      if (n == 0) closed = true;
      return !closed;
    }
  }
  std::size_t answers() const {
    std::size_t n = 0;
    for (auto p = received.find("\r\n"); p != std::string::npos; p = received.find("\r\n", p + 2)) ++n;
    return n;
  }

  std::string received;
  bool closed = false;

 private:
  int fd_ = -1;
  bool connected_ = false;
};

struct Rig {
  explicit Rig(const std::function<void(ServerConfig&)>& configure = {}) {
    CliOptions cli;
    cli.demo = true;
    cli.gateway_id = "test";
    Config c = merge(Config{}, cli);
    log = std::make_unique<Logger>(LogLevel::Info, memlog.file);
    app = std::make_unique<App>(io, c, *log);
    app->start();
    ServerConfig sc;
    sc.listen = "127.0.0.1:0";
    sc.networks = static_cast<std::uint32_t>(c.networks.size());
    if (configure) configure(sc);
    server = std::make_unique<Server>(io, sc, app->requests(), log.get());
    server->start();
    EXPECT_TRUE(run_until([&] { return operational(5); })) << "the demo drive boots";
  }
  ~Rig() {
    server->stop();
    app->stop();
  }

  template <typename Pred>
  bool run_until(Pred pred, std::chrono::milliseconds limit = 10s) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!pred() && std::chrono::steady_clock::now() < end) io.run_for(2ms);
    return pred();
  }
  bool operational(std::uint8_t node) const {
    const auto* n = app->cache().node(1, node);
    return n != nullptr && n->state == canopen::NmtState::Operational;
  }
  bool in_state(std::uint8_t node, canopen::NmtState s) const {
    const auto* n = app->cache().node(1, node);
    return n != nullptr && n->state == s;
  }

  std::unique_ptr<Client> connect() { return std::make_unique<Client>(server->local_address()); }

  // Sends `lines` and returns the answers once `count` of them ("\r\n") came.
  std::string exchange(Client& c, const std::string& lines, std::size_t count) {
    c.received.clear();
    c.send(lines);
    EXPECT_TRUE(run_until([&] {
      c.poll();
      return c.answers() >= count;
    })) << "answers so far: " << c.received;
    std::string out;
    out.swap(c.received);
    return out;
  }

  MemoryLog memlog;
  boost::asio::io_context io;
  std::unique_ptr<Logger> log;
  std::unique_ptr<App> app;
  std::unique_ptr<Server> server;
};

}  // namespace gateway::ascii::test
