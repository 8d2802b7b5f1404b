#include "sparkplug/edge_node.hpp"

#include <utility>
#include <vector>

namespace gateway::sparkplug {
namespace {
// SparkplugOutput reads a device's values again for a rebirth's DBIRTH.
EdgeClientConfig with_owner_rebirths(EdgeClientConfig c) {
  c.session.owner_reads_rebirths = true;
  return c;
}
}  // namespace

EdgeNode::EdgeNode(boost::asio::io_context& io, EdgeClientConfig client, SparkplugOutput::Options options,
                   core::RequestCore& core, const status::View& view, Logger& log)
    : client_(std::make_unique<EdgeClient>(io, with_owner_rebirths(std::move(client)), log)) {
  std::vector<SparkplugOutput::Network> networks;
  for (std::uint32_t net = 1; net <= view.networks().size(); ++net) networks.push_back({net, view.configured_nodes(net)});
  SparkplugOutput::Sources sources;
  sources.description = [&view](std::uint32_t net, std::uint8_t node) { return view.description(net, node); };
  sources.pdo_table = [&view](std::uint32_t net) { return view.pdo_config(net); };
  sources.bus_state = [&view](std::uint32_t net) { return view.bus_state(net); };
  sources.now_ms = [c = client_.get()] { return c->now_ms(); };
  output_ = std::make_unique<SparkplugOutput>(
      client_->edge(), [c = client_.get()](std::vector<Outgoing>& out) { c->send(out); },
      [&core](core::Request req, core::RequestCore::Done done) { core.execute(std::move(req), std::move(done)); },
      std::move(networks), std::move(sources), options, log);
  client_->on_command = [o = output_.get()](WriteCommand cmd) { o->on_command(cmd); };
}

EdgeNode::~EdgeNode() = default;

void EdgeNode::start() {
  output_->start();  // the node metrics, born with the first NBIRTH
  client_->start();
}

void EdgeNode::on_event(std::uint32_t network, const canopen::Event& ev) { output_->on_event(network, ev); }

void EdgeNode::node_changed(std::uint32_t network, const NodeConfig& node) {
  output_->node_changed(network, node.id, node.sparkplug_metrics);
}

void EdgeNode::stop() { client_->stop(); }

status::SparkplugStatus EdgeNode::status() const {
  const auto& edge = client_->edge();
  const auto& cfg = client_->config();
  const auto counters = client_->counters();
  status::SparkplugStatus s;
  s.group_id = cfg.session.group_id;
  s.edge_node_id = cfg.session.edge_node_id;
  s.state = state_name(edge.state());
  s.connected = client_->connected();
  s.broker = client_->broker();
  s.mqtt_version = client_->mqtt_version();
  s.bd_seq = edge.bd_seq();
  s.last_rebirth_ms = edge.last_rebirth();
  s.primary_host_id = cfg.session.primary_host_id;
  s.primary_host_online = edge.host_online();
  s.messages_published = counters.published;
  s.commands_received = counters.commands;
  return s;
}

}  // namespace gateway::sparkplug
