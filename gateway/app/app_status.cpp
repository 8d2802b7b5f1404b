#include "app/app_status.hpp"

#include "app/app.hpp"
#include "sparkplug/edge_client.hpp"

namespace gateway {

std::string_view AppStatus::version() const { return App::version(); }
const std::string& AppStatus::gateway_id() const { return app_.config().gateway_id; }
std::chrono::steady_clock::time_point AppStatus::started_at() const { return app_.started_at(); }
const std::vector<NetworkConfig>& AppStatus::networks() const { return app_.config().networks; }
std::size_t AppStatus::max_program_bytes() const { return app_.config().http.max_program_bytes; }
const StateCache& AppStatus::cache() const { return app_.cache(); }

const canopen::eds::DeviceDescription* AppStatus::description(std::uint32_t net, std::uint8_t node) const {
  return app_.description(net, node);
}
const canopen::od::ObjectDictionary* AppStatus::own_dictionary(std::uint32_t net) const {
  return app_.own_dictionary(net);
}
std::optional<canopen::NmtState> AppStatus::own_state(std::uint32_t net) const { return app_.own_state(net); }
std::optional<canopen::can::BusState> AppStatus::bus_state(std::uint32_t net) const { return app_.bus_state(net); }
std::vector<status::NodeOrigin> AppStatus::node_origins(std::uint32_t net) const { return app_.node_origins(net); }
const canopen::pdo::RemotePdoTable* AppStatus::pdo_config(std::uint32_t net) const { return app_.pdo_config(net); }
std::shared_ptr<trace::NetworkTrace> AppStatus::frame_tap(std::uint32_t net) const { return app_.frame_tap(net); }
const history::ValueHistory* AppStatus::value_history() const { return app_.value_history(); }
const core::Counters& AppStatus::counters() const { return app_.counters(); }

std::optional<status::SparkplugStatus> AppStatus::sparkplug() const {
  const auto* sp = app_.sparkplug();
  if (sp == nullptr) return std::nullopt;
  const auto& edge = sp->edge();
  const auto& cfg = sp->config();
  const auto counters = sp->counters();
  status::SparkplugStatus s;
  s.group_id = cfg.session.group_id;
  s.edge_node_id = cfg.session.edge_node_id;
  s.state = sparkplug::state_name(edge.state());
  s.connected = sp->connected();
  s.bd_seq = edge.bd_seq();
  s.last_rebirth_ms = edge.last_rebirth();
  s.primary_host_id = cfg.session.primary_host_id;
  s.primary_host_online = edge.host_online();
  s.messages_published = counters.published;
  s.commands_received = counters.commands;
  return s;
}

std::string AppStatus::metrics_text() const { return app_.metrics().render(); }

}  // namespace gateway
