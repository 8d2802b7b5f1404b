// The MQTT publisher's settings (MqttPublisher, publisher.hpp), the one
// place their defaults live. The YAML configuration (config/config.hpp)
// parses straight into this struct; the gateway's own MQTT keys extend it
// there.
//
// Pure data; no threads, no I/O.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "event_message.hpp"
#include "mqtt/disk_queue.hpp"

namespace gateway::mqtt {

enum class PayloadFormat : std::uint8_t { Json, Protobuf };

// Where an event kind's messages wait (outbound_queue.hpp): disk (written
// and synced), outage (memory while the broker is connected, disk while it
// is not), memory (never on storage).
enum class StorageMode : std::uint8_t { Disk, Outage, Memory };

constexpr std::size_t kEventKindCount = static_cast<std::size_t>(kLastEventKind) + 1;  // EventKind values

// One value per EventKind, indexed by the kind or its number.
template <class T>
struct PerKind : std::array<T, kEventKindCount> {
  using std::array<T, kEventKindCount>::operator[];
  T& operator[](EventKind k) { return (*this)[static_cast<std::size_t>(k)]; }
  const T& operator[](EventKind k) const { return (*this)[static_cast<std::size_t>(k)]; }
};

// Default QoS per EventKind: 1 for status, bus, state, emcy, boot and
// transfer (state a subscriber must not miss), 0 for the high-rate heartbeat, tpdo, pdo,
// sync and time.
constexpr PerKind<std::uint8_t> kDefaultQos = {{1, 1, 1, 0, 1, 0, 0, 0, 0, 1, 1}};

struct MqttConfig {
  std::string server_uri;   // tcp:// ssl:// mqtt:// mqtts:// (host[:port])
  // More brokers (a cluster's other members, a standby), tried in turn
  // after server_uri; the same client id, credentials and TLS files.
  std::vector<std::string> standby_uris;
  std::string client_id;    // MUST be unique on the broker
  std::string username;     // empty: none
  std::string password;
  // TLS (ssl:// and mqtts://): PEM files; empty ca_file = system trust store.
  std::string ca_file, cert_file, key_file, key_password;
  bool verify_server = true;
  int mqtt_version = 5;  // 5: MQTT 5 with fallback to 3.1.1; 4: 3.1.1 only
  std::chrono::seconds keepalive{30};
  std::chrono::seconds connect_timeout{10};
  std::chrono::milliseconds reconnect_min{250};
  std::chrono::milliseconds reconnect_max{10'000};
  std::string gateway_id;   // topics canopen/<gateway_id>/...
  // The status payloads (GatewayStatus, proto3 JSON or binary as the caller
  // wants); the defaults are minimal stand-ins.
  std::string online_payload = R"({"state":"online"})";
  std::string offline_payload = R"({"state":"offline"})";  // the Will
  PerKind<std::uint8_t> qos = kDefaultQos;  // by EventKind
  PayloadFormat format = PayloadFormat::Json;
  // By EventKind; nullopt: storage_for()'s default.
  PerKind<std::optional<StorageMode>> storage{};
  // queue.dir MUST be set; one directory per publisher.
  DiskQueueOptions queue = [] {
    DiskQueueOptions q;
    q.max_bytes = 256ULL << 20;
    q.max_messages = 1'000'000;
    return q;
  }();
  // The memory tier (`outage` messages while connected, `memory` ones).
  std::uint64_t memory_max_bytes = 16ull << 20;
  std::uint64_t memory_max_messages = 100'000;
  // fdatasync of the queue's unsynced `disk` data, on the io thread (it
  // blocks for the sync: on a slow disk choose a longer interval; 0 =
  // never, page cache only).
  std::chrono::milliseconds sync_interval{100};
  // QoS 1 messages in flight. Under MQTT 5 the broker's Receive Maximum
  // less 4 caps it (mosquitto: 20 by default, so 16).
  std::size_t inflight_window = 256;
  bool accept_requests = true;
  // Topic filters a reply topic must match instead of the default rule
  // (mqtt.reply-topics); each MUST be valid (topic_filter_problem).
  std::vector<std::string> reply_topics;

  // server_uri, then the standbys.
  std::vector<std::string> uris() const {
    std::vector<std::string> all{server_uri};
    all.insert(all.end(), standby_uris.begin(), standby_uris.end());
    return all;
  }

  int qos_for(EventKind k) const { return qos[k]; }
  // The kind's storage; by default `disk` for QoS 1 kinds and `outage` for
  // QoS 0 ones (following qos_for(), so a kind raised to QoS 1 goes to disk).
  StorageMode storage_for(EventKind k) const {
    if (storage[k]) return *storage[k];
    return qos_for(k) == 0 ? StorageMode::Outage : StorageMode::Disk;
  }
};

}  // namespace gateway::mqtt
