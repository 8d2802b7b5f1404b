// Everything the HTTP server answers besides its own WebSocket path and the
// dashboard files: the REST routes, /metrics and the OpenAPI document.
#include <chrono>
#include <string>

#include "metrics.hpp"
#include "rest_api.hpp"

namespace gateway {

namespace {

// GET /metrics: a snapshot of the counters in Prometheus text format.
http::Response metrics_response(const App& app, const http::HttpServer& server) {
  namespace m = metrics;
  m::MetricsSnapshot s;
  s.version = std::string(App::version());
  for (const auto& [number, info] : app.cache().networks()) {
    m::NetworkMetrics n;
    n.network = number;
    n.interface = info.simulated ? std::string("demo") : info.interface;
    if (auto st = app.bus_state(number)) n.bus_state = std::string(canopen::can::to_string(*st));
    if (auto c = app.channel_stats(number)) {
      n.rx_frames = c->rx_frames;
      n.tx_frames = c->tx_frames;
      n.rx_dropped = c->rx_dropped;
      n.tx_dropped = c->tx_dropped;
      n.error_frames = c->error_frames;
      n.reopens = c->reopens;
    }
    n.events = info.events;
    s.networks.push_back(std::move(n));
  }
  const auto& counters = app.counters();
  s.sdo_requests = counters.sdo_requests;
  s.sdo_aborts = counters.sdo_aborts;
  s.sdo_timeouts = counters.sdo_timeouts;
  s.nmt_commands = counters.nmt_commands;
  s.sdo_latency_bounds.assign(counters.kSdoLatencyBounds.begin(), counters.kSdoLatencyBounds.end());
  s.sdo_latency_counts.assign(counters.sdo_latency_counts.begin(), counters.sdo_latency_counts.end());
  s.sdo_latency_sum = counters.sdo_latency_sum;
  s.request_auth_failures = counters.auth_failures;
  s.requests_over_sdo_share = counters.sdo_share_refused;
  s.mqtt_requests_rate_limited = counters.requests_rate_limited;
  for (int k = 0; k <= static_cast<int>(EventKind::BootConfig); ++k) {
    const auto kind = static_cast<EventKind>(k);
    s.events_by_kind[std::string(to_string(kind))] = app.pipeline().published(kind);
  }
  if (auto mq = app.mqtt_counters()) {
    s.mqtt_enabled = true;
    s.mqtt_connected = mq->connected;
    s.mqtt_published = mq->published;
    s.mqtt_acked = mq->acked;
    s.mqtt_dropped = mq->dropped;
    s.mqtt_queue_depth = mq->queue_depth;
    s.mqtt_queue_bytes = mq->queue_bytes;
    s.mqtt_reconnects = mq->reconnects;
    s.mqtt_requests_refused = mq->requests_refused;
    s.mqtt_dropped_by_reason = mq->dropped_by_reason;
    s.mqtt_memory_depth = mq->memory_depth;
    s.mqtt_spilled = mq->spilled;
    s.mqtt_storage_bytes = mq->storage_bytes;
    s.mqtt_storage_syncs = mq->storage_syncs;
    s.mqtt_storage_errors = mq->storage_errors;
    s.mqtt_storage_failing = mq->storage_failing;
    s.mqtt_corrupt_records = mq->corrupt_records;
    s.mqtt_corrupt_bytes = mq->corrupt_bytes;
    s.mqtt_stalls = mq->stalls;
  }
  const auto hs = server.stats();
  s.ws_clients = hs.ws_clients;
  s.ws_messages_sent = hs.ws_messages_sent;
  s.ws_messages_dropped = hs.ws_messages_dropped;
  s.http_responses_by_status = hs.responses_by_status;
  auto& hc = s.http_connections.emplace();
  hc.open = hs.connections_active;
  hc.idle = hs.connections_idle;
  hc.refused_per_address = hs.connections_rejected_per_address;
  hc.refused_full = hs.connections_rejected_full;
  hc.evicted_idle = hs.connections_evicted_idle;
  hc.header_timeouts = hs.header_timeouts;
  hc.refused_framing = hs.refused_framing;
  hc.refused_host = hs.refused_host;
  hc.refused_origin = hs.refused_origin;
  hc.refused_media_type = hs.refused_media_type;
  s.uptime_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - app.started_at()).count();
  http::Response r;
  r.status = 200;
  r.content_type = std::string(m::kContentType);
  r.body = m::render_metrics(s);
  return r;
}

}  // namespace

void register_metrics_route(http::HttpServer& server, App& app) {
  server.add_route("GET", "/metrics", [a = &app, srv = &server](const http::Request&, http::Responder respond) {
    respond(metrics_response(*a, *srv));
  });
}

void register_openapi_route(http::HttpServer& server) {
  server.add_route("GET", "/api/v1/openapi.json", [](const http::Request&, http::Responder respond) {
    respond(http::Response::json(std::string(openapi_document())));
  });
}

void register_api_routes(http::HttpServer& server, App& app) {
  register_rest_routes(server, app);
  register_metrics_route(server, app);
  register_openapi_route(server);
}

}  // namespace gateway
