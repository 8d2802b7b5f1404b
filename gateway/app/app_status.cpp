#include "app/app_status.hpp"

#include "app/app.hpp"

namespace gateway {

std::string_view AppStatus::version() const { return App::version(); }
const std::string& AppStatus::gateway_id() const { return app_.config().gateway_id; }
std::chrono::steady_clock::time_point AppStatus::started_at() const { return app_.started_at(); }
const std::vector<NetworkConfig>& AppStatus::networks() const { return app_.config().networks; }
const std::string& AppStatus::config_file() const { return app_.config().source; }
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
std::vector<NodeConfig> AppStatus::configured_nodes(std::uint32_t net) const { return app_.configured_nodes(net); }
const canopen::pdo::RemotePdoTable* AppStatus::pdo_config(std::uint32_t net) const { return app_.pdo_config(net); }
std::shared_ptr<trace::NetworkTrace> AppStatus::frame_tap(std::uint32_t net) const { return app_.frame_tap(net); }
const history::ValueHistory* AppStatus::value_history() const { return app_.value_history(); }
const core::Counters& AppStatus::counters() const { return app_.counters(); }

std::optional<status::MqttStatus> AppStatus::mqtt() const { return app_.mqtt_status(); }
std::optional<status::SparkplugStatus> AppStatus::sparkplug() const { return app_.sparkplug_status(); }

std::string AppStatus::metrics_text() const { return app_.metrics().render(); }

}  // namespace gateway
