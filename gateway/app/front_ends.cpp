#include "app/front_ends.hpp"

#include <chrono>

#include "ascii/ascii_lss.hpp"
#include "http/http_metrics.hpp"
#include "metrics/metrics.hpp"
#include "mqtt/client.hpp"
#include "mqtt_requests/mqtt_requests.hpp"
#include "sparkplug/edge_node.hpp"
#include "rest/rest_api.hpp"

namespace gateway {

void install_http_api(http::HttpServer& server, App& app) {
  server.set_authorizer(app.http_authorizer());
  // The server's families and the uptime come last, as /metrics has always
  // had them (after the App's own, app.hpp).
  http::register_metrics(app.metrics(), server);
  metrics::register_uptime(app.metrics(), [started = app.started_at()] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  });
  register_api_routes(server, app.requests(), app.status(), app.io());
}

void connect_event_stream(http::HttpServer& server, App& app) {
  app.add_consumer([srv = &server](const EncodedEventPtr& ev) { srv->publish(ev); });
  app.set_protobuf_demand([srv = &server] { return srv->binary_clients() > 0; });
}

void serve_mqtt_requests(App& app, Logger& log) {
  const auto& config = app.config();
  if (!config.mqtt.enabled) return;
  app.serve_mqtt_requests(std::make_unique<mqtt::MqttRequests>(
      config.gateway_id, config.mqtt.reply_topics, log,
      [&core = app.requests()](core::Request req, core::RequestCore::Done done) {
        core.execute(std::move(req), std::move(done));
      }));
}

sparkplug::EdgeNode* add_sparkplug(boost::asio::io_context& io, App& app, Logger& log) {
  const auto& config = app.config();
  if (!config.sparkplug.enabled) return nullptr;
  sparkplug::EdgeClientConfig client;
  client.session = {config.sparkplug.group_id, config.sparkplug.edge_node_id, config.sparkplug.primary_host_id};
  client.mqtt = config.sparkplug.mqtt;
  client.state_dir = config.state_dir;
  auto node = std::make_unique<sparkplug::EdgeNode>(
      io, std::move(client), SparkplugOutput::Options{config.sparkplug.aliases, config.sparkplug.commands_role},
      app.requests(), app.status(), log);
  auto* edge = node.get();
  std::vector<std::string> brokers;
  for (const auto& u : config.sparkplug.mqtt.uris()) brokers.push_back(mqtt::normalize_server_uri(u));
  sparkplug::register_metrics(app.metrics(), edge->client_slot(), brokers);
  app.set_sparkplug_status([edge] { return std::optional<status::SparkplugStatus>(edge->status()); });
  app.add_output(std::move(node));
  return edge;
}

std::unique_ptr<ascii::Server> make_ascii_server(boost::asio::io_context& io, App& app, Logger& log) {
  const auto& config = app.config();
  ascii::ServerConfig a;
  a.listen = config.ascii.listen;
  a.role = config.ascii.role.value_or(Role::Operator);  // merge() sets it
  a.idle_timeout = config.ascii.idle_timeout;
  a.max_clients = config.ascii.max_clients;
  a.networks = static_cast<std::uint32_t>(config.networks.size());
  auto server = std::make_unique<ascii::Server>(io, std::move(a), app.requests(), &log);
  server->set_lss_handler(ascii::make_lss_handler(app.requests()));
  return server;
}

}  // namespace gateway
