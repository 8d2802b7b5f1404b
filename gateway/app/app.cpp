#include "app/app.hpp"

#include <algorithm>
#include <filesystem>

#include "canopen/eds/eds.hpp"
#include "canopen/sdo/abort.hpp"
#include "canopen/network.hpp"
#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/link_monitor.hpp"
#include "canopen/socketcan/service_driver.hpp"
#include "app/app_status.hpp"
#include "app/composition.hpp"
#include "app/core_metrics.hpp"
#include "history/history_metrics.hpp"
#include "core/format.hpp"
#include "messages/event_encoder.hpp"
#include "app/mqtt_output.hpp"
#include "mqtt/client.hpp"
#include "app/node_configs.hpp"
#include "pipeline/stack_output.hpp"
#include "pipeline/pipeline_metrics.hpp"
#include "app/seq_store.hpp"

#ifndef CANOPEN_GATEWAY_VERSION
#define CANOPEN_GATEWAY_VERSION "0.0.0"
#endif

namespace gateway {

namespace {


std::string pdo_text(const canopen::PdoEvent& ev) {
  std::string s = ev.node == 0 ? "unclaimed PDO " + core::hex_number(ev.cob_id, 3) + "h"
                               : "node " + std::to_string(ev.node) + " TPDO" + std::to_string(ev.number);
  for (const auto& v : ev.values)
    s += " " + core::index_text(v.index) + "/" + core::hex_number(v.sub, 2) + " " + v.name + "=" +
         canopen::format_value(v.value);
  if (ev.values.empty() || ev.error) {
    s += " raw ";
    core::append_hex(s, ev.raw, core::HexCase::upper);
  }
  if (ev.error) s += " (" + *ev.error + ")";
  return s;
}

// lss.assign of one network (contract "LSS master", config): entry `i`, then
// the next once it is answered, each through the request core (so it is
// audited and holds the network's LSS master like any LSS request). A
// device that does not answer is logged, never fatal.
void assign_from_config(core::RequestCore& core, Logger& log, std::string label, std::uint32_t net,
                        std::vector<LssAssignConfig> list, std::size_t i) {
  if (i >= list.size()) return;
  const LssAssignConfig e = list[i];
  core::Request r;
  r.caller.authenticated = true;
  r.caller.role = Role::Admin;
  r.caller.who = "lss.assign (configuration)";
  r.caller.key = "configuration";
  r.network = net;
  r.command = core::LssConfigure{e.identity, e.node_id,
                                 std::nullopt, e.store};
  core.execute(std::move(r), [&core, &log, label, net, list = std::move(list), i, e](core::Result result) mutable {
    const std::string what = label + ": lss.assign " +
                             canopen::lss::to_string(e.identity) +
                             " -> node-ID " + std::to_string(e.node_id);
    if (const auto* p = std::get_if<core::Problem>(&result)) {
      log.warn(what + ": not assigned: " + p->detail);
    } else {
      log.info(what + ": assigned" + (e.store ? " and stored" : ""));
    }
    log.flush();
    assign_from_config(core, log, label, net, std::move(list), i + 1);
  });
}

constexpr std::string_view kBusLoadHelp =
    "CAN bus load per network in percent of the configured bit rate over the window (worst-case bit stuffing).";

}  // namespace

App::App(boost::asio::io_context& io, Config config, Logger& log, Composition networks)
    : io_(io),
      config_(std::move(config)),
      log_(log),
      tokens_([this] {
        std::vector<auth::TokenEntry> t;
        for (const auto& c : config_.http.tokens) t.push_back({c.name, c.role, c.sha256});
        return auth::TokenStore(std::move(t));
      }()),
      core_networks_(make_core_networks(*this)),
      node_configs_(std::make_unique<NodeConfigs>(*this)),
      core_(*core_networks_, tokens_,
            core::RequestCore::Settings{config_.mqtt.requests_role.value_or(Role::None), config_.http.rate_limit,
                                        config_.http.rate_burst, canopen::sdo::ClientConfig{}.queue_limit},
            [this](const std::string& line) { audit(line); }),
      encode_ctx_{config_.gateway_id},
      pipeline_(
          [this, mqtt_protobuf = config_.mqtt.enabled && config_.mqtt.format == PayloadFormat::Protobuf](
              std::uint32_t network, const canopen::Event& ev) {
            encode_ctx_.protobuf = mqtt_protobuf || (protobuf_demand_ && protobuf_demand_());
            return encode_event(ev, network, encode_ctx_);
          },
          cache_),
      history_(config_.history.max_bytes),
      monitor_(std::move(networks.monitor)),
      nets_(std::move(networks.units)) {
  core_.set_node_settings(node_configs_.get());
  status_ = std::make_unique<AppStatus>(*this);
  for (auto& n : nets_) attach(*n);
  // Each component's families, once, in the order /metrics has always
  // written them (the HTTP server and the uptime follow, front_ends.cpp).
  metrics::register_build_info(metrics_, std::string(version()));
  metrics::register_network_families(metrics_);
  for (const auto& n : nets_)
    register_network_metrics(metrics_, cache_, n->number, [c = n->channel] { return c; });
  // Bus load per network (issue 18): a series only where the bit rate is
  // configured; without one there is no honest number.
  metrics_.family("canopen_gateway_bus_load_percent", kBusLoadHelp, metrics::MetricType::Gauge);
  for (const auto& n : nets_) {
    if (n->cfg.bitrate == 0) continue;
    for (const int seconds : {1, 10}) {
      metrics_.gauge_fn("canopen_gateway_bus_load_percent", kBusLoadHelp,
                        {{"network", std::to_string(n->number)},
                         {"interface", n->cfg.simulated ? std::string("demo") : n->cfg.interface},
                         {"window", std::to_string(seconds) + "s"}},
                        [t = n->tap.get(), seconds] {
                          return metrics::Value(
                              t->load().percent(std::chrono::seconds(seconds), std::chrono::steady_clock::now()).value_or(0.0));
                        });
    }
  }
  register_core_metrics(metrics_, core_.counters());
  register_metrics(metrics_, pipeline_);
  if (config_.mqtt.enabled) {
    MqttOutput::Status status{std::string(version()), nets_.empty() ? std::uint8_t{127} : nets_.front()->cfg.node_id,
                              {}, started_at_};
    std::vector<MqttOutput::Node> nodes;
    for (const auto& n : nets_) {
      status.networks.push_back(n->number);
      for (const auto& node : n->cfg.nodes) nodes.push_back({n->number, node.id});
    }
    mqtt_ = std::make_unique<MqttOutput>(io_, config_.mqtt, config_.gateway_id, log_, std::move(status), nodes);
    mqtt_->register_metrics(metrics_);
  } else {
    metrics::register_mqtt(metrics_, {});
  }
  history::register_metrics(metrics_, history_);  // issue 18: the PDO value history's bytes and objects
}

App::App(boost::asio::io_context& io, Config config, Logger& log)
    : App(io, config, log, compose_networks(io, config, log)) {}

App::~App() { stop(); }

void App::attach(Net& n) {
  Net* np = &n;
  n.on_event = [this, np](const canopen::Event& ev) { on_stack_event(*np, ev); };
  n.on_bus_event = [this, np](const canopen::can::BusEvent& ev) { log_bus_event(*np, ev); };
  cache_.add_network(n.number, n.cfg.simulated ? "demo" : n.cfg.interface, n.cfg.simulated);
  for (const auto& node : n.cfg.nodes) cache_.add_configured_node(n.number, node.id, node.name);
}

void App::log_bus_event(const Net& n, const canopen::can::BusEvent& ev) {
  std::string msg = n.label + " bus " + std::string(canopen::can::to_string(ev.previous)) + " -> " +
                    std::string(canopen::can::to_string(ev.state)) + " (" +
                    std::string(canopen::can::to_string(ev.cause));
  if (ev.cause == canopen::can::BusEventCause::RxOverflow) msg += ", " + std::to_string(ev.dropped) + " lost";
  msg += ", tec " + std::to_string(ev.tx_error_counter) + ", rec " + std::to_string(ev.rx_error_counter) + ")";
  const bool bad =
      ev.state != canopen::can::BusState::ErrorActive || ev.cause == canopen::can::BusEventCause::RxOverflow;
  log_.log(bad ? LogLevel::Warn : LogLevel::Info, msg);
  log_.flush();
}

App::Net* App::net(std::uint32_t number) {
  if (number == 0 || number > nets_.size()) return nullptr;
  return nets_[number - 1].get();
}

const canopen::eds::DeviceDescription* App::description(std::uint32_t net_number, std::uint8_t node) const {
  if (net_number == 0 || net_number > nets_.size()) return nullptr;
  const auto& d = nets_[net_number - 1]->descriptions;
  auto it = d.find(node);
  return it == d.end() ? nullptr : &it->second;
}

std::string_view App::version() { return CANOPEN_GATEWAY_VERSION; }

std::vector<App::NodeOrigin> App::node_origins(std::uint32_t net_number) const {
  std::vector<NodeOrigin> out;
  if (net_number == 0 || net_number > nets_.size()) return out;
  const Net& n = *nets_[net_number - 1];
  for (const auto& node : n.cfg.nodes) {
    auto it = n.overlay_files.find(node.id);
    if (it != n.overlay_files.end()) out.push_back({node.id, "state-dir", it->second});
    else out.push_back({node.id, "config", {}});
  }
  std::sort(out.begin(), out.end(), [](const NodeOrigin& a, const NodeOrigin& b) { return a.node < b.node; });
  return out;
}

const canopen::od::ObjectDictionary* App::own_dictionary(std::uint32_t net_number) const {
  if (net_number == 0 || net_number > nets_.size()) return nullptr;
  const auto& od = nets_[net_number - 1]->own_od;
  return od ? &*od : nullptr;
}

std::optional<canopen::NmtState> App::own_state(std::uint32_t net_number) const {
  if (net_number == 0 || net_number > nets_.size()) return std::nullopt;
  const auto& own = nets_[net_number - 1]->local;
  if (!own) return std::nullopt;
  return own->state();
}

std::optional<canopen::can::BusState> App::bus_state(std::uint32_t net_number) const {
  if (net_number == 0 || net_number > nets_.size()) return std::nullopt;
  return nets_[net_number - 1]->channel->state();
}

const canopen::pdo::RemotePdoTable* App::pdo_config(std::uint32_t net_number) const {
  if (net_number == 0 || net_number > nets_.size()) return nullptr;
  return &nets_[net_number - 1]->network->pdo_config();
}

const canopen::pdo::PdoConfig* App::rpdo_config(std::uint32_t net_number, std::uint8_t node,
                                                std::uint16_t number) const {
  if (net_number == 0 || net_number > nets_.size()) return nullptr;
  return nets_[net_number - 1]->network->rpdo().config(node, number);
}

canopen::sim::Simulator* App::simulator(std::uint32_t net_number) {
  Net* n = net(net_number);
  return n == nullptr ? nullptr : n->link.simulator.get();
}

bool App::set_simulated_link(std::uint32_t net_number, bool up) {
  Net* n = net(net_number);
  return n != nullptr && n->link.set_simulated_link(up);
}

canopen::can::MemoryBus* App::simulated_bus(std::uint32_t net_number) {
  Net* n = net(net_number);
  return n == nullptr ? nullptr : n->link.simulated_bus();
}

std::shared_ptr<trace::NetworkTrace> App::frame_tap(std::uint32_t net_number) {
  Net* n = net(net_number);
  return n ? n->tap : nullptr;
}

std::optional<canopen::can::ChannelStats> App::channel_stats(std::uint32_t net_number) const {
  if (net_number == 0 || net_number > nets_.size()) return std::nullopt;
  return nets_[net_number - 1]->channel->stats();
}

const status::View& App::status() const { return *status_; }

const mqtt::MqttPublisher* App::mqtt_publisher() const { return mqtt_ ? mqtt_->publisher() : nullptr; }

void App::add_output(std::unique_ptr<StackOutput> output) {
  if (!started_ && output) outputs_.push_back(std::move(output));
}

std::optional<status::SparkplugStatus> App::sparkplug_status() const {
  return sparkplug_status_ ? sparkplug_status_() : std::nullopt;
}

std::optional<status::MqttStatus> App::mqtt_status() const {
  if (!mqtt_) return std::nullopt;
  status::MqttStatus s;
  for (const auto& u : config_.mqtt.uris()) s.brokers.push_back(mqtt::normalize_server_uri(u));
  if (const auto* p = mqtt_->publisher()) {
    const auto c = p->counters();
    s.connected = c.connected;
    s.broker = c.broker;
    s.mqtt_version = c.mqtt_version;
    s.reconnects = c.reconnects;
  }
  return s;
}

std::vector<NodeConfig> App::configured_nodes(std::uint32_t net_number) const {
  if (net_number == 0 || net_number > nets_.size()) return {};
  return nets_[net_number - 1]->cfg.nodes;
}

void App::serve_mqtt_requests(std::unique_ptr<mqtt::MqttRequests> requests) {
  if (mqtt_ && !started_) mqtt_->set_requests(std::move(requests));
}

void App::start() {
  if (started_ || stopped_) return;
  started_ = true;
  for (auto& n : nets_) {
    // The sequence goes on where the last run left it (seq_store.hpp); read
    // here, not in the constructor, so a start-up that fails there leaves
    // it as it was.
    n->seq.emplace(config_.state_dir, n->number);
    const auto opened = n->seq->open();
    if (!opened.note.empty())
      log_.log(opened.corrupt ? LogLevel::Warn : LogLevel::Info, n->label + ": " + opened.note);
    if (opened.error)
      log_.warn(n->label + ": cannot store the event sequence in " + n->seq->file().string() + ": " +
                opened.error.message() + " (numbers may repeat after a crash)");
    n->network->continue_sequence(opened.first);
  }
  if (mqtt_) {
    mqtt_->start();
    pipeline_.add_consumer([out = mqtt_.get()](const EncodedEventPtr& ev) { out->on_event(ev); });
  }
  for (auto& o : outputs_) o->start();  // Sparkplug: the node metrics, then connecting
  for (auto& n : nets_) {
    // The state the channel was opened in: the channel reported it before
    // anyone listened, and the retained bus topic and the state cache (REST,
    // the dashboard's first paint) need it without waiting for a change.
    canopen::can::BusEvent opened;
    opened.state = n->channel->state();
    opened.previous = canopen::can::BusState::Down;
    opened.cause = opened.state == canopen::can::BusState::Down ? canopen::can::BusEventCause::LinkDown
                                                                 : canopen::can::BusEventCause::LinkUp;
    n->network->report(opened);
    n->local->start(n->now());  // boot-up (7.2.8.3.3), then heartbeats
    n->boot_at_start();         // CiA 302-2: the manager's own start boots its nodes
    n->link.start_simulation();
  }
  for (auto& n : nets_) assign_from_config(core_, log_, n->label, n->number, n->cfg.lss_assign, 0);
  std::string nets;
  for (const auto& n : nets_) nets += (nets.empty() ? "" : ", ") + n->label;
  log_.info("canopen-gateway started: " + nets + "; version " CANOPEN_GATEWAY_VERSION ", gateway id " +
            config_.gateway_id);
  log_.flush();
}

void App::stop() {
  if (stopped_) return;
  stopped_ = true;
  for (auto& n : nets_) n->link.stop_simulation();
  // The CAN side closes: each network's last event says so (the retained
  // bus topic becomes `down`, cause link-down), in order behind the events
  // before it.
  for (auto& n : nets_) {
    const auto state = n->channel->state();
    if (!started_ || state == canopen::can::BusState::Down) continue;
    canopen::can::BusEvent down;
    down.state = canopen::can::BusState::Down;
    down.previous = state;
    down.cause = canopen::can::BusEventCause::LinkDown;
    n->network->report(down);
  }
  // Sparkplug: NDEATH, then DISCONNECT, while the networks still run.
  for (auto& o : outputs_) o->stop();
  // No retained state may claim a node runs once the gateway is gone; the
  // offline status says when and after how long (mqtt_output.hpp).
  if (mqtt_) mqtt_->stop();
  for (auto& n : nets_) {
    n->driver.reset();
    if (n->link.socket) {
      log_.info(n->label + ": " + [&] {
        const auto s = n->link.socket->stats();
        return "rx " + std::to_string(s.rx_frames) + " frames, tx " + std::to_string(s.tx_frames) + ", rx dropped " +
               std::to_string(s.rx_dropped) + ", tx dropped " + std::to_string(s.tx_dropped) + ", error frames " +
               std::to_string(s.error_frames) + ", reopens " + std::to_string(s.reopens);
      }());
      n->link.socket->close();
    }
  }
  if (monitor_) monitor_->stop();
  // Exactly where the sequence stands: the next run goes on from there.
  for (auto& n : nets_) {
    if (auto ec = n->seq ? n->seq->close(n->network->last_seq() + 1) : std::error_code())
      log_.warn(n->label + ": cannot store the event sequence in " + n->seq->file().string() + ": " + ec.message() +
                " (the next run goes on after the reserved numbers)");
  }
  log_.flush();
}

// The own node's EMCYs for lost nodes were raised before (LocalNode, in the unit).
void App::on_stack_event(Net& n, const canopen::Event& ev) {
  log_event(n, ev);
  for (auto& o : outputs_) o->on_event(n.number, ev);  // typed values, not the encoded event
  // Durably reserved before the event leaves the process (one write per block).
  if (auto ec = n.seq ? n.seq->use(ev.seq) : std::error_code())
    log_.warn(n.label + ": cannot store the event sequence in " + n.seq->file().string() + ": " + ec.message() +
              " (numbers may repeat after a crash)");
  pipeline_.on_event(n.number, ev);
  history_.on_event(n.number, ev);  // TPDO values and node breaks for the charts
}

void App::log_event(const Net& n, const canopen::Event& ev) {
  const std::string& prefix = n.label;
  if (const auto* s = std::get_if<canopen::NodeStateEvent>(&ev.body)) {
    static constexpr const char* kCause[] = {"boot-up", "heartbeat", "node guarding", "lost", "recovered"};
    std::string msg = prefix + " node " + std::to_string(s->node) + " " +
                      (s->state ? std::string(canopen::to_string(*s->state)) : std::string("lost")) + " (" +
                      kCause[static_cast<int>(s->cause)] + ")";
    log_.log(s->cause == canopen::NodeStateEvent::Cause::Lost ? LogLevel::Warn : LogLevel::Info, msg);
    log_.flush();  // may come from a timer (lost), not only from a frame batch
  } else if (const auto* h = std::get_if<canopen::HeartbeatEvent>(&ev.body)) {
    if (log_.enabled(LogLevel::Trace))
      log_.trace(prefix + " node " + std::to_string(h->node) + " heartbeat " + std::string(canopen::to_string(h->state)));
  } else if (const auto* e = std::get_if<canopen::EmcyEvent>(&ev.body)) {
    log_.warn(prefix + " node " + std::to_string(e->node) + " EMCY " + core::hex_number(e->error_code, 4) +
              "h, error register " + core::hex_number(e->error_register, 2) + "h: " + e->description);
  } else if (const auto* p = std::get_if<canopen::PdoEvent>(&ev.body)) {
    const auto level = p->node == 0 ? LogLevel::Debug : p->error ? LogLevel::Warn : LogLevel::Debug;
    if (log_.enabled(level)) log_.log(level, prefix + " " + pdo_text(*p));
  } else if (const auto* b = std::get_if<canopen::BootConfigEvent>(&ev.body)) {
    static constexpr const char* kStep[] = {"identify", "identity checked", "configure", "start", "done", "FAILED"};
    std::string msg = prefix + " node " + std::to_string(b->node) + " boot-up configuration: " +
                      kStep[static_cast<int>(b->step)];
    if (!b->detail.empty()) msg += " (" + b->detail + ")";
    if (b->error) msg += ": " + b->error.message();
    log_.log(b->step == canopen::BootConfigEvent::Step::Failed ? LogLevel::Warn : LogLevel::Info, msg);
    log_.flush();
  }
}

// ---- requests ----------------------------------------------------------------

http::Authorizer App::http_authorizer() {
  auth::HttpAuthSettings s;
  s.enabled = config_.http.auth;
  s.anonymous = config_.http.anonymous_role();
  s.rate_limit = config_.http.rate_limit;
  s.rate_burst = config_.http.rate_burst;
  return auth::make_http_authorizer(s, tokens_, log_);
}

void App::audit(const std::string& line) {
  log_.info("audit: " + line);
  log_.flush();
}

}  // namespace gateway
