// The gateway's MQTT output: the publisher (mqtt/publisher.hpp) and, when
// the composition root handed one over (set_requests()), the request front
// end its session carries (mqtt_requests/mqtt_requests.hpp), which events of the
// stream go to it (heartbeats: mqtt.heartbeat, and at most one per node per
// mqtt.heartbeat-min-interval), the gateway status payloads (the online
// status and the Will at start, the offline status of a clean stop), and
// at a clean stop the retained node state topics deleted, so no retained
// message claims a node runs once the gateway is gone.
//
// Thread safety: io_context thread only. The io_context and the logger
// MUST outlive the output.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <boost/asio/io_context.hpp>

#include "config/config.hpp"
#include "event_message.hpp"
#include "log.hpp"
#include "mqtt_requests/mqtt_requests.hpp"
#include "mqtt/publisher.hpp"
#include "metrics/registry.hpp"

namespace gateway {

class MqttOutput {
 public:
  // What the status payloads say about the gateway.
  struct Status {
    std::string version;
    std::uint8_t node_id = 127;           // the first network's own node-ID
    std::vector<std::uint32_t> networks;  // the configured network numbers
    std::chrono::steady_clock::time_point started_at;  // uptime counts from here
  };
  // A configured node, whose retained state topic a clean stop deletes
  // even when no state of it was published in this run.
  struct Node {
    std::uint32_t network = 0;
    std::uint8_t node = 0;
  };
  // Builds nothing that touches the broker or the queue yet (start()).
  MqttOutput(boost::asio::io_context& io, MqttConfig config, std::string gateway_id, Logger& log, Status status,
             const std::vector<Node>& configured);
  ~MqttOutput();
  MqttOutput(const MqttOutput&) = delete;
  MqttOutput& operator=(const MqttOutput&) = delete;

  // The MQTT families of /metrics (mqtt/mqtt_metrics.hpp), read from the
  // publisher once start() built it (0 before). Call once; the output MUST
  // outlive the registry's render() calls.
  void register_metrics(metrics::Registry& r) const;

  // The request front end the publisher hands the request topics' PUBLISHes
  // to and whose replies it sends. Before start(); without one the
  // publisher does not subscribe to the request topics.
  void set_requests(std::unique_ptr<mqtt::MqttRequests> requests);
  // Builds the publisher (opening its queue: throws what MqttPublisher's
  // constructor throws) with the online status and the Will as of now, and
  // starts connecting.
  void start();
  // A pipeline event: state topics are remembered for the stop; heartbeats
  // pass the switch and the rate limit; then it is published (after
  // start(); before, nothing is sent).
  void on_event(const EncodedEventPtr& ev);
  // The heartbeat rate limit (mqtt.heartbeat-min-interval): whether node
  // `node`'s heartbeat on `network` at `now` goes out, which then counts as
  // its last one. Always true with no minimum interval.
  bool heartbeat_due(std::uint32_t network, std::uint8_t node, std::chrono::steady_clock::time_point now);
  // What a clean stop sends last: every configured node's and every
  // published state topic deleted (an empty retained message at the state
  // kind's QoS; not a state of the contract's list, which would be a claim
  // about the node), and the offline status as of now.
  mqtt::MqttPublisher::Farewell farewell() const;
  // After start(): the queued messages the window allows and the farewell,
  // blocking the io thread up to 2 s (MqttPublisher::stop). Once.
  void stop();

  // The gateway status (mqtt.format) as of now: time and uptime.
  std::string status_payload(bool online) const;
  // nullptr before start().
  const mqtt::MqttPublisher* publisher() const { return publisher_.get(); }

 private:
  boost::asio::io_context& io_;
  MqttConfig config_;
  std::string gateway_id_;
  Logger& log_;
  Status status_;
  std::set<std::string> state_topics_;
  // When each node's last heartbeat went out, by (network, node).
  std::map<std::pair<std::uint32_t, std::uint8_t>, std::chrono::steady_clock::time_point> last_heartbeat_;
  std::unique_ptr<mqtt::MqttRequests> requests_;  // before the publisher: its replies go through it
  std::unique_ptr<mqtt::MqttPublisher> publisher_;
};

}  // namespace gateway
