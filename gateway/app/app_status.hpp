// The App as the front ends' read-only status view (status/view.hpp): each
// member forwards to the App's accessor of the same name.
//
// Thread safety: as the App (its io_context thread only).
#pragma once

#include "status/view.hpp"

namespace gateway {

class App;

class AppStatus final : public status::View {
 public:
  // `app` MUST outlive this view.
  explicit AppStatus(App& app) : app_(app) {}

  std::string_view version() const override;
  const std::string& gateway_id() const override;
  std::chrono::steady_clock::time_point started_at() const override;
  const std::vector<NetworkConfig>& networks() const override;
  const std::string& config_file() const override;
  std::size_t max_program_bytes() const override;
  const StateCache& cache() const override;
  const canopen::eds::DeviceDescription* description(std::uint32_t net, std::uint8_t node) const override;
  const canopen::od::ObjectDictionary* own_dictionary(std::uint32_t net) const override;
  std::optional<canopen::NmtState> own_state(std::uint32_t net) const override;
  std::optional<canopen::can::BusState> bus_state(std::uint32_t net) const override;
  std::vector<status::NodeOrigin> node_origins(std::uint32_t net) const override;
  std::vector<NodeConfig> configured_nodes(std::uint32_t net) const override;
  const canopen::pdo::RemotePdoTable* pdo_config(std::uint32_t net) const override;
  std::shared_ptr<trace::NetworkTrace> frame_tap(std::uint32_t net) const override;
  const history::ValueHistory* value_history() const override;
  const core::Counters& counters() const override;
  std::optional<status::MqttStatus> mqtt() const override;
  std::optional<status::SparkplugStatus> sparkplug() const override;
  std::string metrics_text() const override;

 private:
  App& app_;
};

}  // namespace gateway
