// Internal to the HTTP server (not installed).
// HTTP connection: request -> route -> response (stream independent). The
// stream's own part is HttpSession (http_session.cpp).
#pragma once

#include <atomic>
#include <boost/beast/http/empty_body.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "http/beast_types.hpp"
#include "http/http_types.hpp"
#include "http/server_impl.hpp"

namespace gateway::http {

class Connection;

// State shared between a pending request and its Responder.
struct PendingReply {
  std::weak_ptr<Connection> conn;
  std::atomic<bool> done{false};
};

// The sink of a streamed response: what the route wrote and the
// connection has not yet taken (at most `limit` bytes, plus the bytes in
// flight), finished or not, closed or not. The connection pulls from it.
class StreamBody final : public BodySink {
 public:
  StreamBody(std::weak_ptr<Connection> conn, std::size_t limit) : conn_(std::move(conn)), limit_(limit) {}

  bool write(std::string_view bytes) override {
    if (closed_ || finished_) return false;
    if (bytes.empty()) return true;
    // One piece larger than the bound still goes when nothing waits.
    if (waiting() > 0 && waiting() + bytes.size() > limit_) return false;
    pending_.append(bytes);
    kick();
    return true;
  }
  void finish(std::string_view tail) override {
    if (closed_ || finished_) return;
    finished_ = true;
    on_close = nullptr;
    pending_.append(tail);
    kick();
  }
  bool closed() const override { return closed_; }

  // Connection side.
  std::size_t waiting() const { return pending_.size() + in_flight_; }
  bool finished() const { return finished_; }
  // The bytes to write next (all that waits), counted until written().
  std::string take() {
    std::string out;
    out.swap(pending_);
    in_flight_ = out.size();
    return out;
  }
  void written() { in_flight_ = 0; }
  void close() {
    if (closed_) return;
    closed_ = true;
    pending_ = {};
    in_flight_ = 0;
    if (auto f = std::move(on_close)) {
      on_close = nullptr;
      f();
    }
  }

 private:
  void kick();

  std::weak_ptr<Connection> conn_;
  std::size_t limit_;
  std::string pending_;
  std::size_t in_flight_ = 0;
  bool finished_ = false;
  bool closed_ = false;
};

class Connection : public Closable, public std::enable_shared_from_this<Connection> {
 public:
  Connection(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, std::string peer, bool tls);
  ~Connection() override;

  void registered() { impl_->connections[id_] = weak_from_this(); }
  std::optional<std::uint64_t> idle_since() const override { return idle_since_; }
  bool from_address(const std::string& key) const override { return slot_ && slot_->address() == key; }

  // Sends `r` for the current request; ignored when it is not `pending`.
  void reply(const std::shared_ptr<PendingReply>& pending, Response r);

 protected:
  // Waiting for a request (true) or not. Staying idle keeps the first time.
  void set_idle(bool idle);
  // The checks a request's header must pass before its body is read: a
  // refusal to send (the caller then closes the connection), or nullopt.
  std::optional<Response> screen(const BeastRequest& breq);
  void handle(BeastRequest&& breq);
  std::optional<Response> authorize(Request& req);
  // `timeout` zero: no handler timer (the route answers by itself).
  void run_handler(const Handler& handler, std::shared_ptr<Request> req, std::chrono::milliseconds timeout);
  void handle_upgrade(BeastRequest&& breq, Request& req);
  void handle_stream_upgrade(BeastRequest&& breq, Request& req);
  // Status line and header fields every answer carries.
  void fill_head(bhttp::response_header<>& res, const Response& r) const;
  // Builds the Beast response and hands it to the stream.
  void send(Response r);
  // The header now, the body as the route writes it to the sink: chunked
  // for HTTP/1.1, raw until the close for HTTP/1.0.
  void start_stream(Response r);

 public:
  // Writes what the sink holds, one write at a time; after a finished
  // sink's last bytes, the end of the body.
  void pump_stream();

 protected:
  // The stream's write of the header or of bytes completed.
  void stream_written(error_code ec);
  void stream_head_written(error_code ec);
  // The client went away (or a write failed): free the sink, tell the route.
  void stream_gone();

  using StreamHead = bhttp::response<bhttp::empty_body>;
  virtual void write(BeastResponse&& res) = 0;
  virtual void write_stream_head(std::unique_ptr<StreamHead> head) = 0;
  // `bytes` as the body's next piece, or (last) the end of the body.
  virtual void write_stream_bytes(std::string bytes, bool last) = 0;
  // Reads (and discards) until the client closes: how a client that went
  // away is noticed while the body is quiet.
  virtual void watch_client() = 0;
  // After the end of the body: close once the client has read it.
  virtual void end_stream() = 0;
  virtual void close_now() = 0;
  virtual void upgrade(BeastRequest&& req, bool binary, std::shared_ptr<StreamSource> source) = 0;

  std::shared_ptr<HttpServer::Impl> impl_;
  SlotPtr slot_;
  std::string peer_;
  bool tls_;
  std::optional<std::uint64_t> idle_since_;  // Impl::idle_order when it became idle
  bool keep_alive_ = true;
  bool head_ = false;
  unsigned version_ = 11;
  std::shared_ptr<PendingReply> pending_;
  net::steady_timer handler_timer_;
  std::uint64_t id_;
  // A streamed response (start_stream).
  std::shared_ptr<StreamBody> body_;
  bool chunked_ = true;
  bool stream_started_ = false;  // the header is out
  bool stream_writing_ = false;
  bool stream_ended_ = false;    // the end of the body is written or being written
};

}  // namespace gateway::http
