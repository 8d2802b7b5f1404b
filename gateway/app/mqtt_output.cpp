#include "app/mqtt_output.hpp"

#include "messages/event_encoder.hpp"
#include "mqtt/client.hpp"
#include "mqtt/mqtt_metrics.hpp"

namespace gateway {

MqttOutput::MqttOutput(boost::asio::io_context& io, MqttConfig config, std::string gateway_id, Logger& log,
                       Status status, const std::vector<Node>& configured)
    : io_(io),
      config_(std::move(config)),
      gateway_id_(std::move(gateway_id)),
      log_(log),
      status_(std::move(status)) {
  const EncodeContext ctx{gateway_id_};
  for (const auto& n : configured) state_topics_.insert(node_topic(ctx, n.network, n.node, "state"));
}

MqttOutput::~MqttOutput() = default;

void MqttOutput::register_metrics(metrics::Registry& r) const {
  std::vector<std::string> brokers;
  for (const auto& u : config_.uris()) brokers.push_back(mqtt::normalize_server_uri(u));
  mqtt::register_metrics(
      r, publisher_, [this] { return requests_ ? requests_->counters().replies_refused : 0; }, brokers);
}

void MqttOutput::set_requests(std::unique_ptr<mqtt::MqttRequests> requests) { requests_ = std::move(requests); }

void MqttOutput::start() {
  // The publisher's settings as parsed; the rest is known only now.
  mqtt::MqttConfig mc = config_;
  mc.gateway_id = gateway_id_;
  // The Will is fixed at start: it carries the start time and uptime 0
  // (the broker publishes it when it notices the loss; only a clean stop
  // knows when it went offline).
  mc.online_payload = status_payload(true);
  mc.offline_payload = status_payload(false);
  auto* requests = requests_.get();
  mc.accept_requests = mc.accept_requests && requests != nullptr;
  mqtt::MqttPublisher::RequestSink sink;
  if (requests != nullptr) sink = [requests](const mqtt::codec::Publish& msg) { requests->on_publish(msg); };
  publisher_ = std::make_unique<mqtt::MqttPublisher>(io_, mc, log_, std::move(sink));
  if (requests != nullptr) requests->set_reply_sender(publisher_->reply_sender());
  publisher_->start();
  // Where to look, for a person: the broker and the topics to subscribe to.
  std::string brokers;
  for (const auto& u : config_.uris()) brokers += (brokers.empty() ? "" : ", ") + u;
  log_.info(std::string(config_.standby_uris.empty() ? "MQTT: broker " : "MQTT: brokers (tried in turn) ") + brokers +
            ", topic prefix canopen/" + gateway_id_ +
            "/ (subscribe to canopen/" + gateway_id_ + "/#)");
}

void MqttOutput::on_event(const EncodedEventPtr& ev) {
  if (ev->kind == EventKind::State) state_topics_.insert(ev->topic);
  if (ev->kind == EventKind::Heartbeat) {
    if (!config_.heartbeat) return;
    // The clock is read only for a heartbeat under the rate limit.
    if (config_.heartbeat_min_interval.count() > 0 &&
        !heartbeat_due(ev->network, ev->node, std::chrono::steady_clock::now()))
      return;
  }
  if (publisher_) publisher_->publish(ev);
}

bool MqttOutput::heartbeat_due(std::uint32_t network, std::uint8_t node, std::chrono::steady_clock::time_point now) {
  if (config_.heartbeat_min_interval.count() <= 0) return true;
  auto [it, fresh] = last_heartbeat_.try_emplace({network, node}, now);
  if (fresh) return true;
  if (now - it->second < config_.heartbeat_min_interval) return false;
  it->second = now;
  return true;
}

mqtt::MqttPublisher::Farewell MqttOutput::farewell() const {
  mqtt::MqttPublisher::Farewell last;
  const auto qos = static_cast<std::uint8_t>(config_.qos_for(EventKind::State));
  for (const auto& topic : state_topics_) last.messages.push_back({topic, std::string(), qos, true});
  last.offline_payload = status_payload(false);
  return last;
}

void MqttOutput::stop() {
  if (publisher_) publisher_->stop(std::chrono::seconds(2), farewell());
}

std::string MqttOutput::status_payload(bool online) const {
  GatewayStatusInfo status;
  status.online = online;
  status.version = status_.version;
  status.node_id = status_.node_id;
  status.networks = status_.networks;
  status.timestamp = std::chrono::system_clock::now();
  status.uptime_ms = static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - status_.started_at)
          .count());
  auto e = encode_status(status, EncodeContext{gateway_id_});
  return config_.format == PayloadFormat::Protobuf ? e->binary : e->json;
}

}  // namespace gateway
