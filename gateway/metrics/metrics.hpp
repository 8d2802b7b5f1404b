// Prometheus text exposition (format 0.0.4) for GET /metrics: a small,
// dependency-free writer and the gateway's metric families. Each family's
// name, help and labels are defined once, in the register_* function of the
// component that owns it (below), on a Registry (registry.hpp): the live
// components register once (pipeline_metrics.hpp, app/core_metrics.hpp,
// mqtt/mqtt_metrics.hpp, http_metrics.hpp; the App holds the process's
// registry) and /metrics serves Registry::render() with kContentType.
//
// TextWriter: no shared state (thread-safe per instance); the register_*
// functions: as the Registry.
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

// ---- Registration per component (registry.hpp) ----------------------------
// Each registers its families once, with the names, help and labels above;
// `read` runs at every render() and MUST stay valid as long as the registry
// renders. /metrics writes the families in the order registered, which the
// gateway keeps as it has always been: build info, network families,
// networks, services (request core), events, MQTT, HTTP, uptime.

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
// with_connections false: no connection families.
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
  std::string broker;  // the connected broker's URI; "" when not connected
};
// An empty read: MQTT is off, only canopen_gateway_mqtt_enabled 0 is written.
// brokers: every configured broker URI (normalized), one
// canopen_gateway_mqtt_broker_connected{uri} series each.
void register_mqtt(Registry& r, std::function<MqttMetrics()> read, const std::vector<std::string>& brokers = {});

}  // namespace gateway::metrics
