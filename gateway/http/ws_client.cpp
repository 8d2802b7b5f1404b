// WebSocket client: queue, filter and policy (stream independent; see
// ws_client.hpp).
#include "http/ws_client.hpp"

#include <chrono>
#include <string>
#include <string_view>
#include <utility>

#include "http/http_types.hpp"

namespace gateway::http {

WsClient::WsClient(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, bool binary, std::string peer)
    : impl_(std::move(impl)),
      slot_(std::move(slot)),
      binary_(binary),
      peer_(std::move(peer)),
      queue_(SendQueue::Limits{impl_->cfg.ws_queue_max_messages, impl_->cfg.ws_queue_max_bytes,
                               impl_->cfg.ws_stall_timeout}),
      id_(impl_->next_id++) {
  impl_->counters.active.fetch_add(1, std::memory_order_relaxed);
}

WsClient::~WsClient() {
  release_source();
  impl_->connections.erase(id_);
  impl_->ws_clients.erase(id_);
  if (registered_) impl_->counters.ws_clients.fetch_sub(1, std::memory_order_relaxed);
  if (registered_ && binary_) impl_->counters.ws_binary_clients.fetch_sub(1, std::memory_order_relaxed);
  impl_->counters.active.fetch_sub(1, std::memory_order_relaxed);
}

void WsClient::deliver(const EncodedEventPtr& ev) {
  if (!open_ || closing_ || !filter_.matches(*ev)) return;
  // Encoded without protobuf (nobody wanted it when it was encoded, e.g.
  // just before this client connected): nothing to send it.
  if (binary_ && ev->binary.empty() && ev->ws_binary.empty()) return;
  push(SendQueue::Item{ev, {}, binary_});
}

void WsClient::opened() {
  open_ = true;
  registered_ = true;
  impl_->connections.emplace(id_, weak_from_this());
  if (source_) {
    source_->wake = [w = weak_from_this()] {
      if (auto self = w.lock()) self->maybe_write();
    };
  } else {
    impl_->ws_clients.emplace(id_, weak_from_this());  // publish() reaches it
  }
  impl_->counters.ws_clients.fetch_add(1, std::memory_order_relaxed);
  if (binary_) impl_->counters.ws_binary_clients.fetch_add(1, std::memory_order_relaxed);
  impl_->counters.ws_total.fetch_add(1, std::memory_order_relaxed);
  impl_->counters.count_status(101);
  impl_->debug("ws client " + peer_ + " connected" + (binary_ ? " (protobuf)" : ""));
  if (source_) maybe_write();  // what the source queued during the handshake
}

void WsClient::on_text_message(std::string_view text) {
  if (source_) {
    source_->on_message(text);
    maybe_write();
    return;
  }
  std::string error;
  std::string reply;
  if (filter_.parse(text, error)) {
    reply = "{\"subscribed\":" + filter_.to_json() + "}";
  } else {
    reply = "{\"error\":" + Response::problem(400, error).body + "}";
  }
  push(SendQueue::Item{nullptr, std::move(reply), false});
}

void WsClient::on_binary_message() {
  if (source_) {
    source_->on_message("binary frame");  // not JSON: the source answers with its error
    maybe_write();
    return;
  }
  push(SendQueue::Item{
      nullptr, "{\"error\":" + Response::problem(400, "filter messages are JSON text frames").body + "}", false});
}

void WsClient::push(SendQueue::Item item) {
  if (closing_) return;
  const auto before = queue_.dropped();
  const auto r = queue_.push(std::move(item), std::chrono::steady_clock::now());
  impl_->counters.ws_dropped.fetch_add(queue_.dropped() - before, std::memory_order_relaxed);
  if (r == SendQueue::Result::Close) {
    impl_->counters.ws_closed_slow.fetch_add(1, std::memory_order_relaxed);
    impl_->debug("ws client " + peer_ + " too slow, closing (dropped " + std::to_string(queue_.dropped()) + ")");
    begin_close(websocket::close_reason(websocket::close_code::policy_error, "slow consumer"));
    return;
  }
  maybe_write();
}

void WsClient::maybe_write() {
  if (source_ && !writing_ && !closing_ && open_) {
    source_msg_ = source_->next();
    if (!source_msg_) return;
    writing_ = true;
    start_write(*source_msg_, false);
    return;
  }
  if (writing_ || closing_ || queue_.empty()) return;
  current_ = queue_.pop();
  writing_ = true;
  start_write(current_.payload(), current_.binary);
}

void WsClient::on_write(error_code ec) {
  writing_ = false;
  current_ = {};
  source_msg_.reset();
  if (ec) {
    closed();
    return;
  }
  impl_->counters.ws_sent.fetch_add(1, std::memory_order_relaxed);
  maybe_write();
}

void WsClient::begin_close(websocket::close_reason reason) {
  if (closing_) return;
  closing_ = true;
  queue_.clear();
  release_source();
  if (!open_) {
    force_close();
    return;
  }
  start_close(reason);
}

void WsClient::closed() {
  closing_ = true;
  queue_.clear();
  release_source();
  if (open_) {
    open_ = false;
    impl_->ws_clients.erase(id_);
  }
}

void WsClient::release_source() {
  if (!source_ || source_released_) return;
  source_released_ = true;
  source_->wake = nullptr;
  source_->on_close();
}

}  // namespace gateway::http
