// Internal to the HTTP server (not installed).
// WebSocket client: queue, filter and policy (stream independent). The
// stream's own part is WsSession (websocket_session.cpp).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "http/beast_types.hpp"
#include "http/event_stream.hpp"
#include "http/server_impl.hpp"

namespace gateway::http {

class WsClient : public Closable, public std::enable_shared_from_this<WsClient> {
 public:
  WsClient(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, bool binary, std::string peer);
  ~WsClient() override;

  void deliver(const EncodedEventPtr& ev);

  void shutdown() override { begin_close(websocket::close_reason(websocket::close_code::going_away, "server stopping")); }

  // Serve `source` instead of the event stream (before run()).
  void set_source(std::shared_ptr<StreamSource> source) { source_ = std::move(source); }

 protected:
  // Called once the handshake succeeded.
  void opened();
  void on_text_message(std::string_view text);
  void on_binary_message();
  void push(SendQueue::Item item);
  void maybe_write();
  void on_write(error_code ec);
  void begin_close(websocket::close_reason reason);
  // The connection is gone (read or write failed, or closed).
  void closed();
  void release_source();

  virtual void start_write(std::string_view payload, bool binary) = 0;
  // Sends a close frame, closing the socket if that takes too long.
  virtual void start_close(websocket::close_reason reason) = 0;
  virtual void force_close() = 0;

  std::shared_ptr<HttpServer::Impl> impl_;
  SlotPtr slot_;
  bool binary_;
  std::string peer_;
  SendQueue queue_;
  EventFilter filter_;
  SendQueue::Item current_;  // being written; kept alive for the write
  std::shared_ptr<StreamSource> source_;          // a stream route's client: messages from here
  std::shared_ptr<const std::string> source_msg_;  // being written
  bool source_released_ = false;
  bool open_ = false;
  bool closing_ = false;
  bool writing_ = false;
  bool registered_ = false;
  std::uint64_t id_;
};

}  // namespace gateway::http
