// Test support for the MQTT tests: a real mosquitto child process on a free
// port, a Paho subscriber that records what arrives, and an io thread that
// runs the publisher as the gateway does.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <mqtt/async_client.h>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace mqtt_test {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr const char* kMosquitto = "/usr/sbin/mosquitto";

inline bool have_mosquitto() { return ::access(kMosquitto, X_OK) == 0; }

// A client's log (the publisher's or the Sparkplug edge client's) says the
// broker refused its credentials in a CONNACK: MQTT 5 reason 134 "bad user
// name or password" or 135 "not authorized" (mosquitto's answer).
inline bool says_credentials_refused(const std::string& log) {
  return log.find("refused (code 134)") != std::string::npos || log.find("refused (code 135)") != std::string::npos;
}

// A broker that takes only TLS and a password (the TLS tests): writes
// cert.pem/key.pem (self-signed for 127.0.0.1, made with openssl) and a
// mosquitto password file with `user` in `dir`, and returns the
// mosquitto.conf lines that use them (Broker::extra_conf). "" when openssl
// or mosquitto_passwd failed.
inline std::string tls_password_conf(const std::string& dir, const std::string& user, const std::string& password) {
  const std::string mk = "openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 1 "
                         "-subj /CN=127.0.0.1 -addext subjectAltName=IP:127.0.0.1 -keyout " + dir +
                         "/key.pem -out " + dir + "/cert.pem > /dev/null 2>&1 && "
                         "chmod 644 " + dir + "/key.pem && "
                         "mosquitto_passwd -b -c " + dir + "/passwd " + user + " " + password + " > /dev/null 2>&1";
  if (std::system(mk.c_str()) != 0) return {};
  return "certfile " + dir + "/cert.pem\nkeyfile " + dir + "/key.pem\npassword_file " + dir + "/passwd\n";
}

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "mqtt-test-XXXXXX").string();
    path_ = ::mkdtemp(tmpl.data());
    fs::permissions(path_, fs::perms::all, fs::perm_options::add);  // mosquitto may change user
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

inline int free_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

inline bool port_open(int port) {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  ::close(fd);
  return ok;
}

// mosquitto on 127.0.0.1:<free port>, persistence in its temp dir when
// asked (so persistent subscriber sessions survive a restart).
class Broker {
 public:
  explicit Broker(bool persistence = false) : port_(free_port()), persistence_(persistence) {}
  ~Broker() { stop(); }

  int port() const { return port_; }
  // Lines appended to mosquitto.conf (after the listener, so listener
  // options such as certfile apply to it), e.g. TLS or a password file.
  std::string extra_conf;
  bool allow_anonymous = true;
  std::string uri() const { return "tcp://127.0.0.1:" + std::to_string(port_); }

  bool start() {
    const auto conf = dir_.path() / "mosquitto.conf";
    {
      std::ofstream f(conf);
      const passwd* pw = ::getpwuid(::getuid());
      f << "listener " << port_ << " 127.0.0.1\n"
        << "allow_anonymous " << (allow_anonymous ? "true" : "false") << "\n"
        << "persistence " << (persistence_ ? "true" : "false") << "\n"
        << "persistence_location " << dir_.path().string() << "/\n"
        << "autosave_interval 0\n"
        << "max_queued_messages 100000\n"
        << "user " << (pw != nullptr ? pw->pw_name : "root") << "\n"
        << extra_conf;
    }
    const auto log = (dir_.path() / "mosquitto.log").string();
    pid_ = ::fork();
    if (pid_ == 0) {
      int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      ::execl(kMosquitto, "mosquitto", "-c", conf.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // Ready when it accepts connections; a free port taken meanwhile shows
    // as the child exiting.
    for (auto deadline = std::chrono::steady_clock::now() + 10s; std::chrono::steady_clock::now() < deadline;) {
      if (port_open(port_)) return true;
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return false;
      }
      std::this_thread::sleep_for(20ms);
    }
    return false;
  }

  // SIGTERM lets mosquitto save its persistence file; waits for the exit.
  void stop(int sig = SIGTERM) {
    if (pid_ <= 0) return;
    ::kill(pid_, sig);
    int status = 0;
    for (int i = 0; i < 500; ++i) {
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return;
      }
      std::this_thread::sleep_for(10ms);
    }
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }

  std::string log() const {
    std::ifstream f(dir_.path() / "mosquitto.log");
    return std::string(std::istreambuf_iterator<char>(f), {});
  }

 private:
  TempDir dir_;
  int port_;
  bool persistence_;
  pid_t pid_ = -1;
};

// A Paho client recording every message; reconnects by itself and
// re-subscribes on every connect.
class Subscriber {
 public:
  struct Options {
    int version = MQTTVERSION_3_1_1;
    bool clean = true;  // false: persistent session (and session expiry on 5)
  };

  Subscriber(const std::string& uri, const std::string& id, std::vector<std::string> filters, Options o)
      : filters_(std::move(filters)), opts_(o), cli_(uri, id, ::mqtt::create_options(o.version)) {
    cli_.set_message_callback([this](::mqtt::const_message_ptr m) {
      std::lock_guard lk(mu_);
      // DUP set: the broker delivers again a message this subscriber already
      // got, because the broker restarted before its PUBACK was stored
      // (broker -> subscriber QoS 1). Not the publisher's doing: a resend
      // by the publisher is a new PUBLISH and arrives without DUP.
      if (m->is_duplicate()) return;
      msgs_.push_back(std::move(m));
      cv_.notify_all();
    });
    cli_.set_connected_handler([this](const std::string&) {
      {
        std::lock_guard lk(mu_);
        ++connects_;
      }
      for (const auto& f : filters_) cli_.subscribe(f, 1, nullptr, suback_);
    });
  }
  ~Subscriber() {
    try {
      cli_.disconnect()->wait_for(2s);
    } catch (...) {
    }
  }

  bool connect() {
    ::mqtt::connect_options co;
    co.set_mqtt_version(opts_.version);
    if (opts_.version == MQTTVERSION_5) {
      co.set_clean_start(opts_.clean);
      if (!opts_.clean) co.set_properties({::mqtt::property(::mqtt::property::SESSION_EXPIRY_INTERVAL, 3600)});
    } else {
      co.set_clean_session(opts_.clean);
    }
    co.set_automatic_reconnect(std::chrono::milliseconds(50), std::chrono::milliseconds(300));
    co.set_keep_alive_interval(5);
    try {
      cli_.connect(co)->wait_for(10s);
    } catch (const std::exception&) {
      return false;
    }
    // Subscriptions are sent from the connected handler; wait for SUBACK.
    return wait([&] { return subacks_ >= filters_.size(); }, 10s);
  }

  int connects() {
    std::lock_guard lk(mu_);
    return connects_;
  }

  bool wait_count(std::size_t n, std::chrono::milliseconds timeout) {
    return wait([&] { return msgs_.size() >= n; }, timeout);
  }
  bool wait_topic(const std::string& topic, std::chrono::milliseconds timeout) {
    return wait([&] {
      for (auto& m : msgs_)
        if (m->get_topic() == topic) return true;
      return false;
    }, timeout);
  }

  std::vector<::mqtt::const_message_ptr> messages() {
    std::lock_guard lk(mu_);
    return msgs_;
  }
  std::vector<::mqtt::const_message_ptr> on_topic(const std::string& topic) {
    std::vector<::mqtt::const_message_ptr> out;
    for (auto& m : messages())
      if (m->get_topic() == topic) out.push_back(m);
    return out;
  }

  ::mqtt::async_client& client() { return cli_; }

 private:
  template <class Pred>
  bool wait(Pred p, std::chrono::milliseconds timeout) {
    std::unique_lock lk(mu_);
    return cv_.wait_for(lk, timeout, p);
  }

  struct SubAck : ::mqtt::iaction_listener {
    explicit SubAck(Subscriber& s) : self(s) {}
    void on_success(const ::mqtt::token&) override {
      std::lock_guard lk(self.mu_);
      ++self.subacks_;
      self.cv_.notify_all();
    }
    void on_failure(const ::mqtt::token&) override {}
    Subscriber& self;
  };

  std::vector<std::string> filters_;
  Options opts_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<::mqtt::const_message_ptr> msgs_;
  int connects_ = 0;
  SubAck suback_{*this};
  std::size_t subacks_ = 0;
  ::mqtt::async_client cli_;  // last: destroyed first, before what its callbacks use
};

// An io_context on its own thread, as the gateway's io thread.
class IoThread {
 public:
  IoThread() : guard_(io_.get_executor()), thread_([this] { io_.run(); }) {}
  ~IoThread() {
    guard_.reset();
    io_.stop();
    thread_.join();
  }
  boost::asio::io_context& io() { return io_; }

  template <class F>
  auto call(F f) -> decltype(f()) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto fut = task.get_future();
    boost::asio::post(io_, [&task] { task(); });
    return fut.get();
  }

 private:
  boost::asio::io_context io_;
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> guard_;
  std::thread thread_;
};

// Polls pred (on the caller's thread) until true or timeout.
template <class Pred>
bool eventually(Pred pred, std::chrono::milliseconds timeout = 15s) {
  for (auto deadline = std::chrono::steady_clock::now() + timeout; std::chrono::steady_clock::now() < deadline;) {
    if (pred()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return pred();
}

}  // namespace mqtt_test

#include <poll.h>

#include <atomic>

namespace mqtt_test {

// A listening TCP socket on 127.0.0.1 and an ephemeral port (stored in `port`).
inline int listen_on_loopback(int& port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  port = ntohs(a.sin_port);
  ::listen(fd, 16);
  return fd;
}

// A TCP relay in front of the broker that plays an MQTT 3.1.1-only broker:
// a CONNECT with protocol level 5 gets CONNACK "unsupported protocol
// version" (0x84) and is closed; anything else is relayed to the broker.
class V311OnlyProxy {
 public:
  // How it refuses an MQTT 5 CONNECT: CONNACK 0x84, or closing the
  // connection without a CONNACK (as RabbitMQ's MQTT plugin does).
  enum class Refusal { Connack, Close };
  explicit V311OnlyProxy(int broker_port, Refusal how = Refusal::Connack) : broker_port_(broker_port), how_(how) {
    listen_fd_ = listen_on_loopback(port_);
    acceptor_ = std::thread([this] { accept_loop(); });
  }
  ~V311OnlyProxy() {
    stop_ = true;
    ::shutdown(listen_fd_, SHUT_RDWR);
    acceptor_.join();
    for (auto& t : conns_) t.join();
    ::close(listen_fd_);
  }
  int port() const { return port_; }
  int refused_v5() const { return refused_.load(); }

 private:
  void accept_loop() {
    while (!stop_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      int c = ::accept(listen_fd_, nullptr, nullptr);
      if (c < 0) continue;
      conns_.emplace_back([this, c] { serve(c); });
    }
  }

  void serve(int c) {
    std::string buf;
    char tmp[4096];
    // Read until the protocol level byte (after the "MQTT" name) is in.
    std::size_t at = std::string::npos;
    for (;;) {
      at = buf.find("MQTT");
      if ((at != std::string::npos && buf.size() >= at + 5) || stop_) break;
      pollfd p{c, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) {
        if (stop_) break;
        continue;
      }
      ssize_t n = ::read(c, tmp, sizeof tmp);
      if (n <= 0) break;
      buf.append(tmp, static_cast<std::size_t>(n));
    }
    if (at == std::string::npos || buf.size() < at + 5) {
      ::close(c);
      return;
    }
    if (buf[at + 4] == 5) {
      ++refused_;
      const char connack[] = {0x20, 0x03, 0x00, static_cast<char>(0x84), 0x00};
      if (how_ == Refusal::Connack) (void)!::write(c, connack, sizeof connack);
      ::close(c);
      return;
    }
    int b = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(broker_port_));
    if (::connect(b, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        ::write(b, buf.data(), buf.size()) != static_cast<ssize_t>(buf.size())) {
      ::close(b);
      ::close(c);
      return;
    }
    pollfd ps[2] = {{c, POLLIN, 0}, {b, POLLIN, 0}};
    while (!stop_) {
      if (::poll(ps, 2, 100) <= 0) continue;
      bool done = false;
      for (int i = 0; i < 2 && !done; ++i) {
        if (ps[i].revents == 0) continue;
        ssize_t n = ::read(ps[i].fd, tmp, sizeof tmp);
        if (n <= 0 || ::write(ps[1 - i].fd, tmp, static_cast<std::size_t>(n)) != n) done = true;
      }
      if (done) break;
    }
    ::close(b);
    ::close(c);
  }

  int broker_port_;
  Refusal how_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<int> refused_{0};
  std::thread acceptor_;
  std::vector<std::thread> conns_;  // accept thread only, joined at the end
};

// A TCP server on 127.0.0.1 that plays a broken broker: `on_accept(fd)` runs
// for each new connection (e.g. read the CONNECT, write a CONNACK, or do
// nothing); afterwards whatever a connection sends is read and ignored.
class FakeBroker {
 public:
  explicit FakeBroker(std::function<void(int fd)> on_accept = {}) : on_accept_(std::move(on_accept)) {
    listen_fd_ = listen_on_loopback(port_);
    thread_ = std::thread([this] { run(); });
  }
  ~FakeBroker() {
    stop_ = true;
    thread_.join();
    ::close(listen_fd_);
  }
  FakeBroker(const FakeBroker&) = delete;
  FakeBroker& operator=(const FakeBroker&) = delete;

  std::string uri() const { return "tcp://127.0.0.1:" + std::to_string(port_); }
  int accepted() const { return accepted_.load(); }

 private:
  void run() {
    std::vector<int> conns;
    while (!stop_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (::poll(&p, 1, 50) > 0) {
        const int cfd = ::accept(listen_fd_, nullptr, nullptr);
        if (cfd >= 0) {
          ++accepted_;
          conns.push_back(cfd);
          if (on_accept_) on_accept_(cfd);
        }
      }
      for (int cfd : conns) {
        char buf[512];
        pollfd q{cfd, POLLIN, 0};
        if (::poll(&q, 1, 0) > 0) (void)!::read(cfd, buf, sizeof buf);
      }
    }
    for (int cfd : conns) ::close(cfd);
  }

  std::function<void(int)> on_accept_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<int> accepted_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace mqtt_test
