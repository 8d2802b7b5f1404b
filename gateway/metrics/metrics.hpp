// Prometheus text exposition (format 0.0.4) for GET /metrics: a small,
// dependency-free writer and the gateway's metric families. Each family's
// name, help and labels are defined once, in the register_* function of the
// component that owns it (below), on a Registry (registry.hpp). Two ways to
// serve /metrics with kContentType:
//   - register the live components once (http_metrics.hpp,
//     pipeline_metrics.hpp, mqtt/mqtt_metrics.hpp, register_requests() for
//     the request core) and serve Registry::render();
//   - fill a MetricsSnapshot from the live parts and serve render_metrics(),
//     which registers the same functions reading the snapshot.
//
// TextWriter and render_metrics(): pure functions, thread-safe (no shared
// state); the register_* functions: as the Registry.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace gateway::metrics {

inline constexpr std::string_view kContentType = "text/plain; version=0.0.4; charset=utf-8";

enum class MetricType : std::uint8_t { Counter, Gauge, Histogram };

// Label name/value pairs, written in the order given.
using Labels = std::vector<std::pair<std::string, std::string>>;

// A sample value: integers are printed exactly, doubles like %.17g
// (NaN, +Inf, -Inf spelled as Prometheus expects).
// Implicit from the integer and floating types so call sites pass counters as is.
class Value {
 public:
  Value(std::uint64_t v) : kind_(Kind::Unsigned), u_(v) {}
  Value(std::int64_t v) : kind_(Kind::Signed), i_(v) {}
  Value(double v) : kind_(Kind::Double), d_(v) {}
  Value(std::uint32_t v) : Value(std::uint64_t{v}) {}
  Value(int v) : Value(std::int64_t{v}) {}
  Value(bool v) : Value(std::uint64_t{v ? 1U : 0U}) {}
  std::string to_string() const;

 private:
  enum class Kind : std::uint8_t { Unsigned, Signed, Double };
  Kind kind_;
  std::uint64_t u_ = 0;
  std::int64_t i_ = 0;
  double d_ = 0.0;
};

// Collects metric families and writes them in the order first declared,
// each family once (HELP, TYPE, then all its samples) however its samples
// were interleaved with others'. Misuse is a programming error and throws
// std::invalid_argument: a bad metric or label name, a family declared
// again with another type or help, a sample of an undeclared family, or a
// series (family + labels) added twice.
class TextWriter {
 public:
  // Declares a family; declaring it again with the same type and help is a
  // no-op. A family with no samples is still written (HELP and TYPE only).
  void family(std::string_view name, std::string_view help, MetricType type);
  void sample(std::string_view name, const Labels& labels, Value value);
  // family() + sample() for a one-series family without labels.
  void single(std::string_view name, std::string_view help, MetricType type, Value value);
  // A histogram family without labels: `counts` per upper bound in `bounds`
  // (ascending), NOT cumulative, plus one last count for everything above;
  // written as cumulative name_bucket{le=...} series, le="+Inf", name_sum and
  // name_count. Throws std::invalid_argument when counts.size() != bounds.size() + 1.
  void histogram(std::string_view name, std::string_view help, const std::vector<double>& bounds,
                 const std::vector<std::uint64_t>& counts, double sum);

  std::string str() const;

 private:
  struct Family {
    std::string name, help;
    MetricType type;
    std::vector<std::string> label_sets;  // rendered "{...}" or "", for duplicate checks
    std::vector<std::string> lines;
  };
  Family& find(std::string_view name);
  std::vector<Family> families_;
};

bool valid_metric_name(std::string_view name);  // [a-zA-Z_:][a-zA-Z0-9_:]*
bool valid_label_name(std::string_view name);   // [a-zA-Z_][a-zA-Z0-9_]*, not "__..."
std::string escape_label_value(std::string_view v);  // \ -> \\, " -> \", newline -> \n
std::string escape_help(std::string_view v);         // \ -> \\, newline -> \n

// ---- The gateway's metrics -------------------------------------------------

// Bus state names as canopen::can::to_string(BusState) spells them; the
// bus_state family has one series per name.
inline constexpr std::string_view kBusStates[] = {"error-active", "error-warning", "error-passive",
                                                  "bus-off", "down"};

struct NetworkMetrics {
  std::uint32_t network = 0;   // label network="<id>"
  std::string interface;       // label interface="can0"
  std::string bus_state;       // one of kBusStates; anything else gives all-zero bus_state series
  std::uint64_t rx_frames = 0, tx_frames = 0;
  std::uint64_t rx_dropped = 0, tx_dropped = 0;
  std::uint64_t error_frames = 0;
  std::uint64_t reopens = 0;   // socket (re)opens after link loss
  std::uint64_t events = 0;    // events produced by this network
};

// The HTTP server's connection handling (HttpStats).
struct HttpConnectionMetrics {
  std::uint64_t open = 0, idle = 0;  // now; idle: waiting for a request
  std::uint64_t refused_per_address = 0, refused_full = 0;  // closed at accept
  std::uint64_t evicted_idle = 0;     // idle ones closed to admit a new one
  std::uint64_t header_timeouts = 0;  // request header sent too slowly
  // Requests refused before their route: ambiguous framing, foreign Host,
  // foreign Origin, body media type.
  std::uint64_t refused_framing = 0, refused_host = 0, refused_origin = 0, refused_media_type = 0;
};

struct MetricsSnapshot {
  std::string version;  // build_info version label; empty = no build_info family
  std::vector<NetworkMetrics> networks;
  std::uint64_t sdo_requests = 0, sdo_aborts = 0, sdo_timeouts = 0;
  std::uint64_t nmt_commands = 0;
  // SDO transfer latency (submit to result, seconds): counts per upper bound,
  // not cumulative, the last for slower ones (TextWriter::histogram). Empty
  // bounds = no histogram family.
  std::vector<double> sdo_latency_bounds;
  std::vector<std::uint64_t> sdo_latency_counts;
  double sdo_latency_sum = 0.0;
  // Requests refused with 401/403 by the request handler (MQTT requests,
  // NMT resets); the HTTP authorizer's refusals are in http_responses_by_status.
  // nullopt = no such family.
  std::optional<std::uint64_t> request_auth_failures;
  // Requests the request handler answered 429 for their caller: over its
  // share of a node's SDO queue, over the MQTT rate limit. nullopt = no such family.
  std::optional<std::uint64_t> requests_over_sdo_share, mqtt_requests_rate_limited;
  std::map<std::string, std::uint64_t> events_by_kind;  // "tpdo" -> n
  bool mqtt_enabled = false;  // false: only canopen_gateway_mqtt_enabled 0 is written
  bool mqtt_connected = false;
  std::uint64_t mqtt_published = 0, mqtt_acked = 0, mqtt_dropped = 0;
  std::uint64_t mqtt_queue_depth = 0, mqtt_queue_bytes = 0;
  std::uint64_t mqtt_reconnects = 0;
  std::uint64_t mqtt_requests_refused = 0;  // dropped unanswered for their reply address
  // The MQTT queue's storage (mqtt/outbound_queue.hpp, disk_queue.hpp).
  std::map<std::string, std::uint64_t> mqtt_dropped_by_reason;  // "storage_full" -> n
  std::uint64_t mqtt_memory_depth = 0;
  std::uint64_t mqtt_spilled = 0;
  std::uint64_t mqtt_storage_bytes = 0, mqtt_storage_syncs = 0, mqtt_storage_errors = 0;
  bool mqtt_storage_failing = false;
  std::uint64_t mqtt_corrupt_records = 0, mqtt_corrupt_bytes = 0;
  std::uint64_t mqtt_stalls = 0;
  std::uint64_t ws_clients = 0, ws_messages_sent = 0, ws_messages_dropped = 0;
  std::map<int, std::uint64_t> http_responses_by_status;  // 200 -> n
  std::optional<HttpConnectionMetrics> http_connections;   // nullopt = no such families
  double uptime_seconds = 0.0;
};

// The whole /metrics body. Family order is fixed; series within a family
// follow the snapshot's order (networks) or key order (maps). Built on the
// registry with the register_* functions below, reading the snapshot.
std::string render_metrics(const MetricsSnapshot& s);

// ---- Registration per component (registry.hpp) ----------------------------
// Each registers its families once, with the names, help and labels above;
// `read` runs at every render() and MUST stay valid as long as the registry
// renders. Today's /metrics order results from registering in the order
// render_metrics() does: build info, network families, networks, services
// (request core), events, MQTT, HTTP, uptime.

class Registry;
struct HistogramValues;

void register_build_info(Registry& r, const std::string& version);
// The per-network families (frames, drops, error frames, reopens, bus
// state, events), written even while no network is registered.
void register_network_families(Registry& r);
// One network: its channel's counters and bus state, the state cache's
// event count. Labels network/interface are taken from read() now.
void register_network(Registry& r, const std::function<NetworkMetrics()>& read);
// The event pipeline: events published, by kind ("tpdo" -> n).
void register_events_by_kind(Registry& r, std::function<std::map<std::string, std::uint64_t>()> read);

// The HTTP server (HttpStats, as http_metrics.hpp fills it).
struct HttpServerMetrics {
  std::uint64_t ws_clients = 0, ws_messages_sent = 0, ws_messages_dropped = 0;
  std::map<int, std::uint64_t> responses_by_status;  // 200 -> n
  HttpConnectionMetrics connections;
};
// with_connections false: no connection families (a snapshot without them).
void register_http_server(Registry& r, std::function<HttpServerMetrics()> read, bool with_connections = true);

void register_uptime(Registry& r, std::function<double()> seconds);

// The request core's counters (SDO, NMT, refusals). The optional families
// are registered when read() has them at registration time.
struct RequestMetrics {
  std::uint64_t sdo_requests = 0, sdo_aborts = 0, sdo_timeouts = 0, nmt_commands = 0;
  std::optional<std::uint64_t> auth_failures;  // 401/403 by the request handler
  std::optional<std::uint64_t> over_sdo_share, mqtt_rate_limited;  // 429s
};
// sdo_latency: the SDO latency histogram (e.g. an owned Histogram's
// values()); unset = no histogram family.
void register_requests(Registry& r, std::function<RequestMetrics()> read, const std::vector<double>& sdo_latency_bounds,
                       std::function<HistogramValues()> sdo_latency);

// The MQTT publisher and its queue (mqtt/mqtt_metrics.hpp fills it).
struct MqttMetrics {
  bool connected = false;
  std::uint64_t published = 0, acked = 0, dropped = 0;
  std::uint64_t queue_depth = 0, queue_bytes = 0;
  std::uint64_t reconnects = 0;
  std::uint64_t requests_refused = 0;
  std::map<std::string, std::uint64_t> dropped_by_reason;
  std::uint64_t memory_depth = 0, spilled = 0;
  std::uint64_t storage_bytes = 0, storage_syncs = 0, storage_errors = 0;
  bool storage_failing = false;
  std::uint64_t corrupt_records = 0, corrupt_bytes = 0;
  std::uint64_t stalls = 0;
};
// An empty read: MQTT is off, only canopen_gateway_mqtt_enabled 0 is written.
void register_mqtt(Registry& r, std::function<MqttMetrics()> read);

}  // namespace gateway::metrics
