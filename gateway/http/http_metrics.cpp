#include "http/http_metrics.hpp"

namespace gateway::http {

metrics::HttpServerMetrics to_metrics(const HttpStats& s) {
  metrics::HttpServerMetrics m;
  m.ws_clients = s.ws_clients;
  m.ws_messages_sent = s.ws_messages_sent;
  m.ws_messages_dropped = s.ws_messages_dropped;
  m.responses_by_status = s.responses_by_status;
  auto& hc = m.connections;
  hc.open = s.connections_active;
  hc.idle = s.connections_idle;
  hc.refused_per_address = s.connections_rejected_per_address;
  hc.refused_full = s.connections_rejected_full;
  hc.evicted_idle = s.connections_evicted_idle;
  hc.header_timeouts = s.header_timeouts;
  hc.refused_framing = s.refused_framing;
  hc.refused_host = s.refused_host;
  hc.refused_origin = s.refused_origin;
  hc.refused_media_type = s.refused_media_type;
  return m;
}

void register_metrics(metrics::Registry& r, const HttpServer& server) {
  metrics::register_http_server(r, [&server] { return to_metrics(server.stats()); });
}

}  // namespace gateway::http
