// The Sparkplug B edge node on the network: one EdgeSession (sans-I/O,
// edge_session.hpp) run over its own mqtt::Client (mqtt/client.hpp, the
// publisher's client type, its own connection, on the caller's io_context),
// beside the native publisher (contract "Sparkplug B"; facts A.4).
//
// Connection: its own client id, clean session / clean start with MQTT 5
// Session Expiry 0, the Will from EdgeSession::connect_params() before every
// CONNECT attempt (NDEATH, QoS 1, not retained; a new bdSeq per attempt,
// kept in <state-dir>/sparkplug-bdseq), MQTT 5 with fallback to 3.1.1 or
// 3.1.1 only, TLS and credentials as the native session has them, the
// connect timeout, keepalive and reconnect backoff (reconnect_min doubling
// to reconnect_max) of mqtt::MqttConfig. On CONNACK the EdgeSession's
// SUBSCRIBEs (NCMD, DCMD, STATE) and births go out; every incoming PUBLISH
// goes to EdgeSession::received(), and a write it returns to on_command.
// When the EdgeSession ends the session itself (Primary Host offline), the
// DISCONNECT is written, the connection closed once it drained, and the
// client connects again with backoff.
//
// Delivery: everything the EdgeSession hands out is written at once, QoS 0
// (NDEATH QoS 1) and never queued: Sparkplug has no backlog; a message
// given while not connected is dropped (the EdgeSession keeps the values
// for the next birth). Backpressure: while more than max_buffered bytes
// wait for the socket, NDATA/DDATA are dropped (counted), and once the
// socket has drained the whole birth sequence is sent again
// (EdgeSession::rebirth), so hosts get current values instead of a seq gap
// they would have to ask a rebirth for (facts A.6). Births and deaths are
// never dropped.
//
// stop(): EdgeSession::stop (NDEATH with the Will's bdSeq, then DISCONNECT:
// under MQTT 5 with reason 0x04 "Disconnect with Will Message", so the
// broker publishes the Will as well, a duplicate hosts ignore by bdSeq;
// under 3.1.1 the DISCONNECT discards the Will, so the explicit NDEATH is
// the only one; facts A.4.6), written and flushed blocking the io thread up
// to `timeout`, then the connection is closed. If that cannot be done the
// socket is just closed and the broker publishes the Will.
//
// Thread safety: every member function on the io thread (the thread that
// runs `io`); no threads of its own. The io_context and logger MUST outlive
// the client. Only stop() (and the destructor) block.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>

#include "log.hpp"
#include "mqtt/mqtt_config.hpp"
#include "sparkplug/edge_session.hpp"

namespace gateway::metrics {
class Registry;
}

namespace gateway::sparkplug {

struct EdgeClientConfig {
  EdgeSession::Options session;  // group id, edge node id, Primary Host
  // server_uri (tcp:// ssl:// mqtt:// mqtts://), client_id, username,
  // password, TLS files, mqtt_version, keepalive, connect_timeout,
  // reconnect_min/max. The queue, status and QoS fields are not used.
  mqtt::MqttConfig mqtt;
  std::filesystem::path state_dir;  // for sparkplug-bdseq; "" = not kept (tests)
  // Unwritten bytes above which NDATA/DDATA are dropped.
  std::size_t max_buffered = 4u << 20;
};

class EdgeClient {
 public:
  // Message types by index in Counters::published_by_type.
  enum class Type : std::uint8_t { NBIRTH, NDEATH, DBIRTH, DDEATH, NDATA, DDATA };
  static constexpr std::size_t kTypes = 6;
  static const char* type_name(Type t);

  struct Counters {
    std::uint64_t published = 0;  // PUBLISHes written (all types)
    std::array<std::uint64_t, kTypes> published_by_type{};
    std::uint64_t bytes = 0;      // payload bytes of those
    std::uint64_t rebirths = 0;   // NBIRTHs repeated on a connection (NCMD, own rebirth)
    std::uint64_t commands = 0;   // NCMD/DCMD received (rebirth requests included)
    std::uint64_t dropped = 0;    // NDATA/DDATA dropped: not connected, or backpressure
    std::uint64_t connects = 0;   // CONNACKs accepted
    std::uint64_t reconnects = 0; // connects after the first
  };

  // Checks the ids (std::invalid_argument, as EdgeSession) and the URI
  // (std::invalid_argument, as normalize_server_uri). Does not connect.
  EdgeClient(boost::asio::io_context& io, EdgeClientConfig cfg, Logger& log);
  ~EdgeClient();
  EdgeClient(const EdgeClient&) = delete;
  EdgeClient& operator=(const EdgeClient&) = delete;

  void start();
  // See above. Afterwards nothing is sent and nothing reconnects.
  void stop(std::chrono::milliseconds timeout = std::chrono::seconds(2));

  // --- the seam to the CANopen side (app/sparkplug_output) --------------
  // The edge node's state machine: call its CANopen-side functions with a
  // list, then send() that list.
  EdgeSession& edge();
  const EdgeSession& edge() const;
  // Carries out what an EdgeSession call appended, in order, when
  // connected; drops it otherwise. Clears `out`.
  void send(std::vector<Outgoing>& out);
  // UTC ms since 1970 (system_clock): the `now` of EdgeSession calls.
  std::uint64_t now_ms() const;
  // NCMD/DCMD writes as EdgeSession::received() returned them, on the io
  // thread; set before start().
  std::function<void(WriteCommand)> on_command;

  // --- state (REST, /metrics) ---------------------------------------------
  bool connected() const;
  int mqtt_version() const;  // 5 or 4 while connected, else 0
  std::string broker() const;  // the connected broker's URI (normalized); "" when not connected
  Counters counters() const;
  const EdgeClientConfig& config() const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

// "offline" "waiting-for-host" "online" (born) "stopping": the state as
// GET /api/v1/gateway names it.
const char* state_name(EdgeSession::State s);

// The client's /metrics families (canopen_gateway_sparkplug_*), read at
// every render() from the slot as its owner holds it (empty: zeros). The
// slot MUST outlive the registry's render() calls. brokers: the configured
// URIs, normalized, one canopen_gateway_sparkplug_broker_connected{uri}
// series each.
void register_metrics(metrics::Registry& r, const std::unique_ptr<EdgeClient>& client,
                      const std::vector<std::string>& brokers = {});

}  // namespace gateway::sparkplug
