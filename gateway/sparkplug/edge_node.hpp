// The Sparkplug B front end (contract "Sparkplug B") as one unit: the
// EdgeClient (its own MQTT session, edge_client.hpp) and the CANopen side
// (SparkplugOutput, sparkplug_output.hpp) that turns the stack's events into
// births, deaths and data and NCMD/DCMD writes into request-core commands.
// It sees only the request core and the read-only status view (device
// models from the EDS/DCF and PDO configuration in use, bus states, the
// configured nodes); the composition root makes it (app/front_ends.hpp:
// add_sparkplug) and the App feeds it as a StackOutput
// (pipeline/stack_output.hpp).
//
// Thread safety: io thread only. The io_context, the request core, the view
// and the logger MUST outlive it.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include <boost/asio/io_context.hpp>

#include "core/request_core.hpp"
#include "log.hpp"
#include "pipeline/stack_output.hpp"
#include "sparkplug/edge_client.hpp"
#include "sparkplug/sparkplug_output.hpp"
#include "status/view.hpp"

namespace gateway::sparkplug {

class EdgeNode final : public StackOutput {
 public:
  // Checks the ids and the URI as EdgeClient does (std::invalid_argument).
  // The networks and their nodes as `view` has them now. Connects at start().
  EdgeNode(boost::asio::io_context& io, EdgeClientConfig client, SparkplugOutput::Options options,
           core::RequestCore& core, const status::View& view, Logger& log);
  ~EdgeNode() override;
  EdgeNode(const EdgeNode&) = delete;
  EdgeNode& operator=(const EdgeNode&) = delete;

  // StackOutput: the node metrics, then connecting; every stack event; a
  // node's new settings (its `sparkplug-metrics`, a new DBIRTH when online);
  // NDEATH and DISCONNECT (blocks up to 2 s).
  void start() override;
  void on_event(std::uint32_t network, const canopen::Event& ev) override;
  void node_changed(std::uint32_t network, const NodeConfig& node) override;
  void stop() override;

  // The session as GET /api/v1/gateway shows it.
  status::SparkplugStatus status() const;
  const EdgeClient& client() const { return *client_; }
  // The slot register_metrics() (edge_client.hpp) reads.
  const std::unique_ptr<EdgeClient>& client_slot() const { return client_; }

 private:
  std::unique_ptr<EdgeClient> client_;
  std::unique_ptr<SparkplugOutput> output_;  // after client_: it holds the client's EdgeSession
};

}  // namespace gateway::sparkplug
