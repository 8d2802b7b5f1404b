#include "mqtt/client.hpp"

#include <stdexcept>
#include <string_view>
#include <utility>

namespace gateway::mqtt {

namespace asio = boost::asio;

std::string normalize_server_uri(const std::string& uri) {
  static constexpr std::pair<std::string_view, std::string_view> kSchemes[] = {
      {"tcp://", "tcp://"}, {"ssl://", "ssl://"}, {"mqtt://", "tcp://"}, {"mqtts://", "ssl://"}};
  for (auto [from, to] : kSchemes) {
    if (uri.rfind(from, 0) == 0) {
      std::string rest = uri.substr(from.size());
      if (rest.empty() || rest[0] == ':' || rest[0] == '/')
        throw std::invalid_argument("MQTT URI without host: " + uri);
      return std::string(to) + rest;
    }
  }
  throw std::invalid_argument("MQTT URI must start with tcp://, ssl://, mqtt:// or mqtts://: " + uri);
}

Session::Options Client::common_session_options(const MqttConfig& c) {
  Session::Options o;
  o.mqtt_version = c.mqtt_version;
  o.client_id = c.client_id;
  o.username = c.username;
  o.password = c.password;
  o.keepalive = c.keepalive;
  o.connect_timeout = c.connect_timeout;
  return o;
}

Client::Client(asio::io_context& io, const MqttConfig& cfg, Options opts, ClientEvents& events, Logger& log)
    : io_(io), cfg_(cfg), prefix_(opts.log_prefix + ": "), connect_error_hint_(std::move(opts.connect_error_hint)),
      events_(events), log_(log), retry_timer_(io), session_timer_(io), session_(std::move(opts.session), *this) {
  for (const auto& u : cfg.uris()) {
    uris_.push_back(normalize_server_uri(u));
    endpoints_.push_back(parse_endpoint(uris_.back()));
  }
}

Client::~Client() = default;

void Client::start(std::weak_ptr<void> owner) {
  if (running_) return;
  owner_ = std::move(owner);
  running_ = true;
  connect();
}

bool Client::ensure_tls() {
  if (!endpoints_[current_].tls || tls_ctx_) return true;
  try {
    tls_ctx_ = make_tls_context(cfg_);
    return true;
  } catch (const std::exception& e) {
    log_.error(prefix_ + "TLS setup for " + uri() + " failed: " + e.what());
    return false;
  }
}

void Client::connect() {
  if (!running_ || connected_ || connecting_) return;
  if (!ensure_tls()) {
    schedule_retry();
    return;
  }
  events_.on_connecting();
  if (auto e = session_.open(std::chrono::steady_clock::now()); e != codec::Error::None) {
    log_.error(prefix_ + "cannot build CONNECT (" + connect_error_hint_ + "): " + codec::to_string(e));
    schedule_retry();
    return;
  }
  connecting_ = true;
  const std::uint64_t c = ++conn_gen_;
  // Each callback checks that its connection is still the current one, and
  // keeps the owner alive while it runs.
  auto current = [this, owner = owner_](std::uint64_t gen) -> std::shared_ptr<void> {
    auto keep = owner.lock();
    return keep && conn_ && conn_gen_ == gen ? keep : nullptr;
  };
  MqttConnection::Callbacks cb;
  // The connection writes the CONNECT appended here right after.
  cb.on_open = [this, current, c] {
    if (auto keep = current(c)) session_.transport_connected(conn_->out(), std::chrono::steady_clock::now());
  };
  cb.on_data = [this, current, c](std::string_view bytes) {
    if (auto keep = current(c)) {
      auto conn = conn_;  // the session may drop the connection meanwhile
      session_.received(conn->out(), bytes, std::chrono::steady_clock::now());
      // PUBACKs to incoming PUBLISHes and what the owner appended; nothing
      // left when the owner flushed in on_batch_end() already.
      if (conn_ == conn) conn->flush();
    }
  };
  cb.on_drained = [this, current, c] {
    if (auto keep = current(c)) {
      const auto now = std::chrono::steady_clock::now();
      events_.on_drained(session_.wrote(now), now);
    }
  };
  cb.on_closed = [this, current, c](const std::string& why) {
    if (auto keep = current(c)) session_.transport_closed(why);
  };
  conn_ = std::make_shared<MqttConnection>(io_, tls_ctx_.get(), cfg_.verify_server, std::move(cb));
  conn_->open(endpoints_[current_]);
}

void Client::drop_connection() {
  if (!conn_) return;
  writes_before_ += conn_->writes();
  conn_->close();
  conn_.reset();
}

void Client::schedule_retry() {
  if (!running_) return;
  const auto delay = reconnect_delay(cfg_, failures_);
  ++failures_;
  retry_timer_.expires_after(delay);
  retry_timer_.async_wait([this, owner = owner_](const boost::system::error_code& ec) {
    auto keep = owner.lock();
    if (ec || !keep) return;
    connect();
  });
}

void Client::next_broker() {
  if (uris_.size() < 2) return;
  current_ = (current_ + 1) % uris_.size();
  session_.reset_version();  // another broker may speak MQTT 5
}

void Client::retry_after_failure(const std::string& what) {
  const bool first_series = failures_ == 0;
  if (uris_.size() > 1 && ++tried_in_round_ < uris_.size()) {
    const std::string failed = uri();
    next_broker();
    if (first_series || log_.enabled(LogLevel::Debug))
      log_.warn(prefix_ + "connect to " + failed + " " + what + ", trying " + uri());
    connect();
    return;
  }
  tried_in_round_ = 0;
  if (first_series || log_.enabled(LogLevel::Debug))
    log_.warn(prefix_ + "connect to " + uri() + " " + what + ", retrying");
  next_broker();  // the next round starts where this one did
  schedule_retry();
}

void Client::went_down(Down cause, const std::string& why) {
  connected_ = false;
  connecting_ = false;
  events_.on_down(cause, why);
}

void Client::end_connection(const std::string& why) {
  session_.close();
  drop_connection();
  const bool was_connected = connected_;
  if (was_connected) log_.warn(prefix_ + "disconnected from " + uri() + ": " + why);
  went_down(Down::Ended, why);
  if (was_connected) next_broker();
  schedule_retry();
}

Client::Farewell Client::stop(std::chrono::milliseconds timeout,
                              const std::function<void(std::string& out)>& last_words) {
  if (!running_) return Farewell::NotConnected;
  running_ = false;
  retry_timer_.cancel();
  session_timer_.cancel();
  Farewell result = Farewell::NotConnected;
  if (conn_ && connected_ && last_words) {
    // One synchronous write (a TLS write started now could not be joined).
    final_.clear();
    last_words(final_);
    writes_before_ += conn_->writes();
    result = conn_->finish(final_, timeout) ? Farewell::Sent : Farewell::NotSent;
    conn_.reset();
  } else {
    drop_connection();
  }
  session_.close();
  connected_ = false;
  connecting_ = false;
  return result;
}

// --- SessionEvents ---------------------------------------------------------

// One timer for the session's deadline (connect timeout, keepalive).
void Client::on_deadline_changed() {
  const auto d = session_.deadline();
  if (!d) {
    session_timer_.cancel();
    return;
  }
  session_timer_.expires_at(*d);
  session_timer_.async_wait([this, owner = owner_](const boost::system::error_code& ec) {
    auto keep = owner.lock();
    if (ec || !keep) return;
    std::string unused;    // no connection: the session only times out
    const auto c = conn_;  // alive while the session may write to it
    session_.on_timer(c ? c->out() : unused, std::chrono::steady_clock::now());
    if (conn_) conn_->flush();
  });
}

void Client::on_connected(const BrokerLimits& limits) {
  connecting_ = false;
  if (!running_) {
    session_.close();
    drop_connection();
    return;
  }
  connected_ = true;
  failures_ = 0;
  tried_in_round_ = 0;
  if (connects_++ > 0) ++reconnects_;
  events_.on_up(limits);
}

void Client::on_refused(std::uint8_t code, bool fell_back) {
  connecting_ = false;
  drop_connection();
  went_down(Down::Refused, "connect refused (code " + std::to_string(code) + ")");
  if (!running_) return;
  if (fell_back) {
    log_.warn(prefix_ + "broker " + uri() + " refuses MQTT 5, falling back to 3.1.1");
    connect();
    return;
  }
  retry_after_failure("refused (code " + std::to_string(code) + ")");
}

// The connection failed before or after CONNACK, or the broker closed it
// (the session has forgotten what was in flight).
void Client::on_lost(const std::string& why, bool was_up, bool fell_back) {
  drop_connection();
  if (!was_up) {
    went_down(Down::Failed, why);
    if (!running_) return;
    if (fell_back) {
      log_.warn(prefix_ + "broker " + uri() + " closed the connection without a CONNACK to an MQTT 5 CONNECT (" + why +
                "): trying MQTT 3.1.1");
      connect();
      return;
    }
    retry_after_failure("failed: " + why);
    return;
  }
  // A guard only: on_connected() either connects or closes the session.
  if (!connected_) return;
  went_down(Down::Lost, why);
  if (!running_) return;
  next_broker();  // the lost one is likely gone: another member first
  schedule_retry();
}

}  // namespace gateway::mqtt
