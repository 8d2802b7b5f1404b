#include "metrics/metrics.hpp"

#include "metrics/registry.hpp"

#include <array>
#include <charconv>
#include <cstdio>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace gateway::metrics {

namespace {

bool name_start(char c, bool colon) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || (colon && c == ':');
}
bool name_char(char c, bool colon) { return name_start(c, colon) || (c >= '0' && c <= '9'); }

bool valid_name(std::string_view name, bool colon) {
  if (name.empty() || !name_start(name.front(), colon)) return false;
  for (char c : name) {
    if (!name_char(c, colon)) return false;
  }
  return true;
}

template <typename T>
std::string integer_text(T v) {
  std::array<char, 24> buf{};
  auto [end, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  (void)ec;  // 24 chars hold any 64-bit integer
  return std::string(buf.data(), end);
}

std::string render_labels(const Labels& labels) {
  if (labels.empty()) return {};
  std::string out = "{";
  bool first = true;
  for (const auto& [k, v] : labels) {
    if (!valid_label_name(k)) throw std::invalid_argument("metrics: bad label name '" + k + "'");
    if (!first) out += ',';
    first = false;
    out += k;
    out += "=\"";
    out += escape_label_value(v);
    out += '"';
  }
  out += '}';
  return out;
}

}  // namespace

std::string Value::to_string() const {
  switch (kind_) {
    case Kind::Unsigned: return integer_text(u_);
    case Kind::Signed: return integer_text(i_);
    case Kind::Double: break;
  }
  if (std::isnan(d_)) return "NaN";
  if (std::isinf(d_)) return d_ > 0 ? "+Inf" : "-Inf";
  // %.17g, but locale-independent.
  std::array<char, 40> buf{};
  auto [end, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), d_, std::chars_format::general, 17);
  (void)ec;  // 40 chars hold any %.17g
  return std::string(buf.data(), end);
}

bool valid_metric_name(std::string_view name) { return valid_name(name, true); }

bool valid_label_name(std::string_view name) {
  return valid_name(name, false) && name.substr(0, 2) != "__";
}

std::string escape_label_value(std::string_view v) {
  std::string out;
  out.reserve(v.size());
  for (char c : v) {
    switch (c) {
      case '\\': out += "\\\\"; break;
      case '"': out += "\\\""; break;
      case '\n': out += "\\n"; break;
      default: out += c;
    }
  }
  return out;
}

std::string escape_help(std::string_view v) {
  std::string out;
  out.reserve(v.size());
  for (char c : v) {
    switch (c) {
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      default: out += c;
    }
  }
  return out;
}

void TextWriter::family(std::string_view name, std::string_view help, MetricType type) {
  if (!valid_metric_name(name)) throw std::invalid_argument("metrics: bad metric name '" + std::string(name) + "'");
  for (const auto& f : families_) {
    if (f.name != name) continue;
    if (f.type != type || f.help != help) {
      throw std::invalid_argument("metrics: family '" + std::string(name) + "' declared twice differently");
    }
    return;
  }
  families_.push_back(Family{std::string(name), std::string(help), type, {}, {}});
}

TextWriter::Family& TextWriter::find(std::string_view name) {
  for (auto& f : families_) {
    if (f.name == name) return f;
  }
  throw std::invalid_argument("metrics: sample of undeclared family '" + std::string(name) + "'");
}

void TextWriter::sample(std::string_view name, const Labels& labels, Value value) {
  Family& f = find(name);
  std::string rendered = render_labels(labels);
  for (const auto& existing : f.label_sets) {
    if (existing == rendered) {
      throw std::invalid_argument("metrics: duplicate series " + f.name + rendered);
    }
  }
  std::string line = f.name;
  line += rendered;
  line += ' ';
  line += value.to_string();
  line += '\n';
  f.lines.push_back(std::move(line));
  f.label_sets.push_back(std::move(rendered));
}

void TextWriter::single(std::string_view name, std::string_view help, MetricType type, Value value) {
  family(name, help, type);
  sample(name, {}, value);
}

void TextWriter::histogram(std::string_view name, std::string_view help, const std::vector<double>& bounds,
                           const std::vector<std::uint64_t>& counts, double sum) {
  if (counts.size() != bounds.size() + 1)
    throw std::invalid_argument("metrics: histogram '" + std::string(name) + "' needs one count per bound plus one");
  family(name, help, MetricType::Histogram);
  Family& f = find(name);
  if (!f.lines.empty()) throw std::invalid_argument("metrics: histogram '" + f.name + "' written twice");
  std::uint64_t cumulative = 0;
  auto bucket = [&](const std::string& le, std::uint64_t n) {
    f.lines.push_back(f.name + "_bucket{le=\"" + le + "\"} " + Value(n).to_string() + "\n");
  };
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    cumulative += counts[i];
    char le[32];
    std::snprintf(le, sizeof le, "%g", bounds[i]);  // "0.0005", "1", "2.5": short, as exposition usually has
    bucket(le, cumulative);
  }
  cumulative += counts.back();
  bucket("+Inf", cumulative);
  f.lines.push_back(f.name + "_sum " + Value(sum).to_string() + "\n");
  f.lines.push_back(f.name + "_count " + Value(cumulative).to_string() + "\n");
}

std::string TextWriter::str() const {
  std::string out;
  for (const auto& f : families_) {
    out += "# HELP ";
    out += f.name;
    out += ' ';
    out += escape_help(f.help);
    out += "\n# TYPE ";
    out += f.name;
    out += f.type == MetricType::Counter ? " counter\n" : f.type == MetricType::Gauge ? " gauge\n" : " histogram\n";
    for (const auto& line : f.lines) out += line;
  }
  return out;
}

namespace {
constexpr std::string_view kFrames = "canopen_gateway_can_frames_total";
constexpr std::string_view kDropped = "canopen_gateway_can_frames_dropped_total";
constexpr std::string_view kErrors = "canopen_gateway_can_error_frames_total";
constexpr std::string_view kReopens = "canopen_gateway_can_reopens_total";
constexpr std::string_view kBus = "canopen_gateway_bus_state";
constexpr std::string_view kNetEvents = "canopen_gateway_network_events_total";
constexpr std::string_view kFramesHelp = "CAN frames received (rx) and sent (tx) per network.";
constexpr std::string_view kDroppedHelp =
    "CAN frames lost per network: rx overflow in kernel or controller, tx queue full.";
constexpr std::string_view kErrorsHelp = "CAN error frames received per network.";
constexpr std::string_view kReopensHelp = "Times the CAN socket of a network was reopened after the link came back.";
constexpr std::string_view kBusHelp = "CAN controller state per network: 1 for the current state, 0 for the others.";
constexpr std::string_view kNetEventsHelp = "Events produced by each network.";
}  // namespace

void register_build_info(Registry& r, const std::string& version) {
  r.gauge_fn("canopen_gateway_build_info", "Gateway build; the value is always 1.", {{"version", version}},
             [] { return Value(1U); });
}

void register_network_families(Registry& r) {
  r.family(kFrames, kFramesHelp, MetricType::Counter);
  r.family(kDropped, kDroppedHelp, MetricType::Counter);
  r.family(kErrors, kErrorsHelp, MetricType::Counter);
  r.family(kReopens, kReopensHelp, MetricType::Counter);
  r.family(kBus, kBusHelp, MetricType::Gauge);
  r.family(kNetEvents, kNetEventsHelp, MetricType::Counter);
}

void register_network(Registry& r, const std::function<NetworkMetrics()>& read) {
  const NetworkMetrics now = read();
  const std::string id = integer_text(now.network);
  auto labels = [&](std::string_view k, std::string_view v) {
    Labels l{{"network", id}, {"interface", now.interface}};
    if (!k.empty()) l.emplace_back(std::string(k), std::string(v));
    return l;
  };
  auto field = [&read](std::uint64_t NetworkMetrics::*f) { return [read, f] { return Value(read().*f); }; };
  r.counter_fn(kFrames, kFramesHelp, labels("direction", "rx"), field(&NetworkMetrics::rx_frames));
  r.counter_fn(kFrames, kFramesHelp, labels("direction", "tx"), field(&NetworkMetrics::tx_frames));
  r.counter_fn(kDropped, kDroppedHelp, labels("direction", "rx"), field(&NetworkMetrics::rx_dropped));
  r.counter_fn(kDropped, kDroppedHelp, labels("direction", "tx"), field(&NetworkMetrics::tx_dropped));
  r.counter_fn(kErrors, kErrorsHelp, labels({}, {}), field(&NetworkMetrics::error_frames));
  r.counter_fn(kReopens, kReopensHelp, labels({}, {}), field(&NetworkMetrics::reopens));
  for (std::string_view state : kBusStates) {
    r.gauge_fn(kBus, kBusHelp, labels("state", state), [read, state] { return Value(read().bus_state == state); });
  }
  r.counter_fn(kNetEvents, kNetEventsHelp, labels({}, {}), field(&NetworkMetrics::events));
}

void register_events_by_kind(Registry& r, std::function<std::map<std::string, std::uint64_t>()> read) {
  r.collect("canopen_gateway_events_published_total", "Events published to clients, by kind.", MetricType::Counter,
            [read = std::move(read)](const Registry::Emit& emit) {
              for (const auto& [kind, n] : read()) emit({{"kind", kind}}, n);
            });
}

void register_uptime(Registry& r, std::function<double()> seconds) {
  r.gauge_fn("canopen_gateway_uptime_seconds", "Seconds since the gateway started.", {},
             [seconds = std::move(seconds)] { return Value(seconds()); });
}

// The HTTP server: WebSocket hub, responses, connection handling.
void register_http_server(Registry& r, std::function<HttpServerMetrics()> read, bool with_connections) {
  auto field = [&read](auto HttpServerMetrics::*f) { return [read, f] { return Value(read().*f); }; };
  auto conn = [&read](std::uint64_t HttpConnectionMetrics::*f) {
    return [read, f] { return Value(read().connections.*f); };
  };
  r.gauge_fn("canopen_gateway_websocket_clients", "Connected WebSocket clients.", {},
             field(&HttpServerMetrics::ws_clients));
  static constexpr std::string_view ws = "canopen_gateway_websocket_messages_total";
  static constexpr std::string_view ws_help = "WebSocket messages by result: sent, or dropped for a slow client.";
  r.counter_fn(ws, ws_help, {{"result", "sent"}}, field(&HttpServerMetrics::ws_messages_sent));
  r.counter_fn(ws, ws_help, {{"result", "dropped"}}, field(&HttpServerMetrics::ws_messages_dropped));
  r.collect("canopen_gateway_http_responses_total", "HTTP responses by status code.", MetricType::Counter,
            [read](const Registry::Emit& emit) {
              for (const auto& [code, n] : read().responses_by_status) emit({{"code", integer_text(code)}}, n);
            });
  if (!with_connections) return;
  static constexpr std::string_view conns = "canopen_gateway_http_connections";
  static constexpr std::string_view conns_help =
      "Open HTTP and WebSocket connections; idle: HTTP ones waiting for a request.";
  r.gauge_fn(conns, conns_help, {{"state", "open"}}, conn(&HttpConnectionMetrics::open));
  r.gauge_fn(conns, conns_help, {{"state", "idle"}}, conn(&HttpConnectionMetrics::idle));
  static constexpr std::string_view refused = "canopen_gateway_http_connections_refused_total";
  static constexpr std::string_view refused_help =
      "New connections closed at once: their client address had http.max-connections-per-address open, "
      "none idle (per-address), or http.max-connections were open and none idle (full).";
  r.counter_fn(refused, refused_help, {{"reason", "per-address"}}, conn(&HttpConnectionMetrics::refused_per_address));
  r.counter_fn(refused, refused_help, {{"reason", "full"}}, conn(&HttpConnectionMetrics::refused_full));
  r.counter_fn("canopen_gateway_http_connections_evicted_total",
               "Idle connections closed to admit a new one at http.max-connections or at its address's "
               "http.max-connections-per-address.", {},
               conn(&HttpConnectionMetrics::evicted_idle));
  r.counter_fn("canopen_gateway_http_header_timeouts_total",
               "Connections closed because a request header did not arrive in time (slow clients).", {},
               conn(&HttpConnectionMetrics::header_timeouts));
  static constexpr std::string_view req = "canopen_gateway_http_requests_refused_total";
  static constexpr std::string_view req_help =
      "Requests refused before their route ran: ambiguous framing (400), Host not the gateway's (421/400), "
      "Origin not the gateway's nor allowed (403), body neither JSON nor protobuf (415).";
  r.counter_fn(req, req_help, {{"reason", "framing"}}, conn(&HttpConnectionMetrics::refused_framing));
  r.counter_fn(req, req_help, {{"reason", "host"}}, conn(&HttpConnectionMetrics::refused_host));
  r.counter_fn(req, req_help, {{"reason", "origin"}}, conn(&HttpConnectionMetrics::refused_origin));
  r.counter_fn(req, req_help, {{"reason", "media-type"}}, conn(&HttpConnectionMetrics::refused_media_type));
}

// The request handler's CANopen services (SDO, NMT, refusals).
void register_requests(Registry& r, std::function<RequestMetrics()> read, const std::vector<double>& sdo_latency_bounds,
                       std::function<HistogramValues()> sdo_latency) {
  const RequestMetrics now = read();
  auto field = [&read](std::uint64_t RequestMetrics::*f) { return [read, f] { return Value(read().*f); }; };
  auto optional = [&read](std::optional<std::uint64_t> RequestMetrics::*f) {
    return [read, f] { return Value((read().*f).value_or(0)); };
  };
  r.counter_fn("canopen_gateway_sdo_requests_total", "SDO transfers started by the gateway.", {},
               field(&RequestMetrics::sdo_requests));
  r.counter_fn("canopen_gateway_sdo_aborts_total", "SDO transfers that ended with an abort.", {},
               field(&RequestMetrics::sdo_aborts));
  r.counter_fn("canopen_gateway_sdo_timeouts_total", "SDO transfers that timed out.", {},
               field(&RequestMetrics::sdo_timeouts));
  r.counter_fn("canopen_gateway_nmt_commands_total", "NMT commands sent.", {}, field(&RequestMetrics::nmt_commands));
  if (sdo_latency)
    r.histogram_fn("canopen_gateway_sdo_latency_seconds", "SDO transfers from submission to result, queueing included.",
                   sdo_latency_bounds, std::move(sdo_latency));
  if (now.auth_failures)
    r.counter_fn("canopen_gateway_request_auth_failures_total",
                 "Requests refused with 401/403 by the request handler (MQTT requests, NMT resets).", {},
                 optional(&RequestMetrics::auth_failures));
  if (now.over_sdo_share || now.mqtt_rate_limited) {
    static constexpr std::string_view limited = "canopen_gateway_requests_limited_total";
    static constexpr std::string_view help =
        "Requests answered 429 for their caller by the request handler: sdo-queue-share (the caller had its "
        "share of the node's SDO queue waiting), mqtt-rate-limit (an MQTT caller over http.rate-limit).";
    r.family(limited, help, MetricType::Counter);
    if (now.over_sdo_share)
      r.counter_fn(limited, help, {{"reason", "sdo-queue-share"}}, optional(&RequestMetrics::over_sdo_share));
    if (now.mqtt_rate_limited)
      r.counter_fn(limited, help, {{"reason", "mqtt-rate-limit"}},
                   optional(&RequestMetrics::mqtt_rate_limited));
  }
}

// The MQTT publisher and its queue.
void register_mqtt(Registry& r, std::function<MqttMetrics()> read, const std::vector<std::string>& brokers) {
  auto field = [&read](auto MqttMetrics::*f) { return [read, f] { return Value(read().*f); }; };
  const bool enabled = static_cast<bool>(read);
  r.gauge_fn("canopen_gateway_mqtt_enabled", "1 when MQTT publishing is configured.", {},
             [enabled] { return Value(enabled); });
  if (!enabled) return;
  r.gauge_fn("canopen_gateway_mqtt_connected", "1 while connected to the MQTT broker.", {},
             field(&MqttMetrics::connected));
  for (const auto& uri : brokers)
    r.gauge_fn("canopen_gateway_mqtt_broker_connected",
               "1 for the broker of mqtt.uri's list the gateway is connected to, 0 for the others.", {{"uri", uri}},
               [read, uri] { return Value(read().broker == uri); });
  static constexpr std::string_view msgs = "canopen_gateway_mqtt_messages_total";
  static constexpr std::string_view msgs_help =
      "MQTT messages by result: published (handed to the broker), acked, dropped.";
  r.counter_fn(msgs, msgs_help, {{"result", "published"}}, field(&MqttMetrics::published));
  r.counter_fn(msgs, msgs_help, {{"result", "acked"}}, field(&MqttMetrics::acked));
  r.counter_fn(msgs, msgs_help, {{"result", "dropped"}}, field(&MqttMetrics::dropped));
  r.gauge_fn("canopen_gateway_mqtt_queue_depth", "MQTT messages waiting to be sent.", {},
             field(&MqttMetrics::queue_depth));
  r.gauge_fn("canopen_gateway_mqtt_queue_bytes", "Bytes of MQTT messages waiting to be sent.", {},
             field(&MqttMetrics::queue_bytes));
  r.counter_fn("canopen_gateway_mqtt_reconnects_total", "Reconnections to the MQTT broker.", {},
               field(&MqttMetrics::reconnects));
  r.counter_fn("canopen_gateway_mqtt_requests_refused_total",
               "MQTT requests dropped unanswered and not executed: reply topic not allowed (mqtt.reply-topics) or "
               "correlation data over 1 KiB.",
               {}, field(&MqttMetrics::requests_refused));
  r.collect("canopen_gateway_mqtt_dropped_total",
            "MQTT messages dropped, by reason: queue_full (max-bytes/max-messages), too_big, storage_full (the "
            "state-dir file system is full or failing), memory_full (memory tier), backpressure (QoS 0 outage "
            "messages, the oldest first, while a connected broker was slower than the buses: never stored), "
            "rejected (by the broker).",
            MetricType::Counter, [read](const Registry::Emit& emit) {
              for (const auto& [reason, n] : read().dropped_by_reason) emit({{"reason", reason}}, n);
            });
  r.gauge_fn("canopen_gateway_mqtt_memory_queue_depth", "MQTT messages waiting in memory (outage and memory kinds).",
             {}, field(&MqttMetrics::memory_depth));
  r.counter_fn("canopen_gateway_mqtt_spilled_total",
               "MQTT messages of outage kinds written to disk because the broker was away or memory full.", {},
               field(&MqttMetrics::spilled));
  r.counter_fn("canopen_gateway_mqtt_storage_written_bytes_total", "Bytes the MQTT queue wrote to its files.", {},
               field(&MqttMetrics::storage_bytes));
  r.counter_fn("canopen_gateway_mqtt_storage_syncs_total", "fdatasync calls of the MQTT queue.", {},
               field(&MqttMetrics::storage_syncs));
  r.counter_fn("canopen_gateway_mqtt_storage_errors_total", "Failed writes of the MQTT queue (disk full, I/O errors).",
               {}, field(&MqttMetrics::storage_errors));
  r.gauge_fn("canopen_gateway_mqtt_storage_failing", "1 while the MQTT queue cannot write to its files.", {},
             field(&MqttMetrics::storage_failing));
  r.counter_fn("canopen_gateway_mqtt_queue_corrupt_records_total",
               "MQTT queue records lost to corruption, found when the queue was opened.", {},
               field(&MqttMetrics::corrupt_records));
  r.counter_fn("canopen_gateway_mqtt_queue_corrupt_bytes_total",
               "Bytes of the MQTT queue's files skipped as corrupt or torn when it was opened.", {},
               field(&MqttMetrics::corrupt_bytes));
  r.counter_fn("canopen_gateway_mqtt_stalls_total",
               "Times MQTT delivery was restarted because it had stalled (no acknowledgement while messages were in "
               "flight).",
               {}, field(&MqttMetrics::stalls));
}

}  // namespace gateway::metrics
