#include "metrics.hpp"

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

std::string render_metrics(const MetricsSnapshot& s) {
  constexpr auto C = MetricType::Counter;
  constexpr auto G = MetricType::Gauge;
  TextWriter w;

  if (!s.version.empty()) {
    w.family("canopen_gateway_build_info", "Gateway build; the value is always 1.", G);
    w.sample("canopen_gateway_build_info", {{"version", s.version}}, 1U);
  }

  // Per CAN network.
  const std::string frames = "canopen_gateway_can_frames_total";
  const std::string dropped = "canopen_gateway_can_frames_dropped_total";
  const std::string errors = "canopen_gateway_can_error_frames_total";
  const std::string reopens = "canopen_gateway_can_reopens_total";
  const std::string bus = "canopen_gateway_bus_state";
  const std::string net_events = "canopen_gateway_network_events_total";
  w.family(frames, "CAN frames received (rx) and sent (tx) per network.", C);
  w.family(dropped, "CAN frames lost per network: rx overflow in kernel or controller, tx queue full.", C);
  w.family(errors, "CAN error frames received per network.", C);
  w.family(reopens, "Times the CAN socket of a network was reopened after the link came back.", C);
  w.family(bus, "CAN controller state per network: 1 for the current state, 0 for the others.", G);
  w.family(net_events, "Events produced by each network.", C);
  for (const auto& n : s.networks) {
    const std::string id = integer_text(n.network);
    auto labels = [&](std::string_view k, std::string_view v) {
      Labels l{{"network", id}, {"interface", n.interface}};
      if (!k.empty()) l.emplace_back(std::string(k), std::string(v));
      return l;
    };
    w.sample(frames, labels("direction", "rx"), n.rx_frames);
    w.sample(frames, labels("direction", "tx"), n.tx_frames);
    w.sample(dropped, labels("direction", "rx"), n.rx_dropped);
    w.sample(dropped, labels("direction", "tx"), n.tx_dropped);
    w.sample(errors, labels({}, {}), n.error_frames);
    w.sample(reopens, labels({}, {}), n.reopens);
    for (std::string_view state : kBusStates) {
      w.sample(bus, labels("state", state), n.bus_state == state);
    }
    w.sample(net_events, labels({}, {}), n.events);
  }

  // CANopen services.
  w.single("canopen_gateway_sdo_requests_total", "SDO transfers started by the gateway.", C, s.sdo_requests);
  w.single("canopen_gateway_sdo_aborts_total", "SDO transfers that ended with an abort.", C, s.sdo_aborts);
  w.single("canopen_gateway_sdo_timeouts_total", "SDO transfers that timed out.", C, s.sdo_timeouts);
  w.single("canopen_gateway_nmt_commands_total", "NMT commands sent.", C, s.nmt_commands);
  if (!s.sdo_latency_bounds.empty())
    w.histogram("canopen_gateway_sdo_latency_seconds", "SDO transfers from submission to result, queueing included.",
                s.sdo_latency_bounds, s.sdo_latency_counts, s.sdo_latency_sum);
  if (s.request_auth_failures)
    w.single("canopen_gateway_request_auth_failures_total",
             "Requests refused with 401/403 by the request handler (MQTT requests, NMT resets).", C,
             *s.request_auth_failures);
  if (s.requests_over_sdo_share || s.mqtt_requests_rate_limited) {
    const std::string limited = "canopen_gateway_requests_limited_total";
    w.family(limited,
             "Requests answered 429 for their caller by the request handler: sdo-queue-share (the caller had its "
             "share of the node's SDO queue waiting), mqtt-rate-limit (an MQTT caller over http.rate-limit).",
             C);
    if (s.requests_over_sdo_share) w.sample(limited, {{"reason", "sdo-queue-share"}}, *s.requests_over_sdo_share);
    if (s.mqtt_requests_rate_limited)
      w.sample(limited, {{"reason", "mqtt-rate-limit"}}, *s.mqtt_requests_rate_limited);
  }

  const std::string events = "canopen_gateway_events_published_total";
  w.family(events, "Events published to clients, by kind.", C);
  for (const auto& [kind, n] : s.events_by_kind) w.sample(events, {{"kind", kind}}, n);

  // MQTT.
  w.single("canopen_gateway_mqtt_enabled", "1 when MQTT publishing is configured.", G, s.mqtt_enabled);
  if (s.mqtt_enabled) {
    w.single("canopen_gateway_mqtt_connected", "1 while connected to the MQTT broker.", G, s.mqtt_connected);
    const std::string msgs = "canopen_gateway_mqtt_messages_total";
    w.family(msgs, "MQTT messages by result: published (handed to the broker), acked, dropped.", C);
    w.sample(msgs, {{"result", "published"}}, s.mqtt_published);
    w.sample(msgs, {{"result", "acked"}}, s.mqtt_acked);
    w.sample(msgs, {{"result", "dropped"}}, s.mqtt_dropped);
    w.single("canopen_gateway_mqtt_queue_depth", "MQTT messages waiting to be sent.", G, s.mqtt_queue_depth);
    w.single("canopen_gateway_mqtt_queue_bytes", "Bytes of MQTT messages waiting to be sent.", G,
             s.mqtt_queue_bytes);
    w.single("canopen_gateway_mqtt_reconnects_total", "Reconnections to the MQTT broker.", C, s.mqtt_reconnects);
    w.single("canopen_gateway_mqtt_requests_refused_total",
             "MQTT requests dropped unanswered and not executed: reply topic not allowed (mqtt.reply-topics) or "
             "correlation data over 1 KiB.",
             C, s.mqtt_requests_refused);
    const std::string mqtt_dropped = "canopen_gateway_mqtt_dropped_total";
    w.family(mqtt_dropped,
             "MQTT messages dropped, by reason: queue_full (max-bytes/max-messages), too_big, storage_full (the "
             "state-dir file system is full or failing), memory_full (memory tier), rejected (by the broker).",
             C);
    for (const auto& [reason, n] : s.mqtt_dropped_by_reason) w.sample(mqtt_dropped, {{"reason", reason}}, n);
    w.single("canopen_gateway_mqtt_memory_queue_depth", "MQTT messages waiting in memory (outage and memory kinds).",
             G, s.mqtt_memory_depth);
    w.single("canopen_gateway_mqtt_spilled_total",
             "MQTT messages of outage kinds written to disk because the broker was away or memory full.", C,
             s.mqtt_spilled);
    w.single("canopen_gateway_mqtt_storage_written_bytes_total", "Bytes the MQTT queue wrote to its files.", C,
             s.mqtt_storage_bytes);
    w.single("canopen_gateway_mqtt_storage_syncs_total", "fdatasync calls of the MQTT queue.", C,
             s.mqtt_storage_syncs);
    w.single("canopen_gateway_mqtt_storage_errors_total", "Failed writes of the MQTT queue (disk full, I/O errors).",
             C, s.mqtt_storage_errors);
    w.single("canopen_gateway_mqtt_storage_failing", "1 while the MQTT queue cannot write to its files.", G,
             s.mqtt_storage_failing);
    w.single("canopen_gateway_mqtt_queue_corrupt_records_total",
             "MQTT queue records lost to corruption, found when the queue was opened.", C, s.mqtt_corrupt_records);
    w.single("canopen_gateway_mqtt_queue_corrupt_bytes_total",
             "Bytes of the MQTT queue's files skipped as corrupt or torn when it was opened.", C,
             s.mqtt_corrupt_bytes);
    w.single("canopen_gateway_mqtt_stalls_total",
             "Times MQTT delivery was restarted because it had stalled (no acknowledgement while messages were in "
             "flight).",
             C, s.mqtt_stalls);
  }

  // WebSocket and HTTP.
  w.single("canopen_gateway_websocket_clients", "Connected WebSocket clients.", G, s.ws_clients);
  const std::string ws = "canopen_gateway_websocket_messages_total";
  w.family(ws, "WebSocket messages by result: sent, or dropped for a slow client.", C);
  w.sample(ws, {{"result", "sent"}}, s.ws_messages_sent);
  w.sample(ws, {{"result", "dropped"}}, s.ws_messages_dropped);

  const std::string http = "canopen_gateway_http_responses_total";
  w.family(http, "HTTP responses by status code.", C);
  for (const auto& [code, n] : s.http_responses_by_status) w.sample(http, {{"code", integer_text(code)}}, n);
  if (const auto& hc = s.http_connections) {
    const std::string conns = "canopen_gateway_http_connections";
    w.family(conns, "Open HTTP and WebSocket connections; idle: HTTP ones waiting for a request.", G);
    w.sample(conns, {{"state", "open"}}, hc->open);
    w.sample(conns, {{"state", "idle"}}, hc->idle);
    const std::string refused = "canopen_gateway_http_connections_refused_total";
    w.family(refused,
             "New connections closed at once: their client address had http.max-connections-per-address open "
             "(per-address), or http.max-connections were open and none idle (full).",
             C);
    w.sample(refused, {{"reason", "per-address"}}, hc->refused_per_address);
    w.sample(refused, {{"reason", "full"}}, hc->refused_full);
    w.single("canopen_gateway_http_connections_evicted_total",
             "Idle connections closed to admit a new one at http.max-connections.", C, hc->evicted_idle);
    w.single("canopen_gateway_http_header_timeouts_total",
             "Connections closed because a request header did not arrive in time (slow clients).", C,
             hc->header_timeouts);
    const std::string req = "canopen_gateway_http_requests_refused_total";
    w.family(req,
             "Requests refused before their route ran: ambiguous framing (400), Host not the gateway's (421/400), "
             "Origin not the gateway's nor allowed (403), body neither JSON nor protobuf (415).",
             C);
    w.sample(req, {{"reason", "framing"}}, hc->refused_framing);
    w.sample(req, {{"reason", "host"}}, hc->refused_host);
    w.sample(req, {{"reason", "origin"}}, hc->refused_origin);
    w.sample(req, {{"reason", "media-type"}}, hc->refused_media_type);
  }

  w.single("canopen_gateway_uptime_seconds", "Seconds since the gateway started.", G, s.uptime_seconds);
  return w.str();
}

}  // namespace gateway::metrics
