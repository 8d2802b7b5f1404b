#include "app.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>

#include "canopen/eds/eds.hpp"
#include "canopen/network.hpp"
#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/link_monitor.hpp"
#include "composition.hpp"
#include "event_encoder.hpp"
#include "json_text.hpp"
#include "mqtt/publisher.hpp"
#include "request_codec.hpp"
#include "seq_store.hpp"
#include "sim/asio_memory_bus.hpp"
#include "sim/simulator.hpp"

#ifndef CANOPEN_GATEWAY_VERSION
#define CANOPEN_GATEWAY_VERSION "0.0.0"
#endif

namespace gateway {

namespace {

// Who asked, for the audit log.
std::string requester(std::string_view who) { return who.empty() ? std::string("anonymous") : std::string(who); }

// Requests that may wait per node behind the running one: the networks are
// built with the SDO client's default configuration.
constexpr std::size_t kSdoQueueLimit = canopen::sdo::ClientConfig{}.queue_limit;

// The queue key of QueueShares for a node's SDO queue.
std::uint64_t sdo_queue_key(std::uint32_t network, std::uint8_t node) {
  return std::uint64_t{network} << 8 | node;
}

std::string hex4(unsigned v) {
  char b[8];
  std::snprintf(b, sizeof b, "%04Xh", v);
  return b;
}

std::string pdo_text(const canopen::PdoEvent& ev) {
  char buf[48];
  std::string s;
  if (ev.node == 0) {
    std::snprintf(buf, sizeof buf, "unclaimed PDO %03Xh", static_cast<unsigned>(ev.cob_id));
    s = buf;
  } else {
    s = "node " + std::to_string(ev.node) + " TPDO" + std::to_string(ev.number);
  }
  for (const auto& v : ev.values) {
    std::snprintf(buf, sizeof buf, " %04Xh/%02X ", static_cast<unsigned>(v.index), static_cast<unsigned>(v.sub));
    s += buf + v.name + "=" + canopen::format_value(v.value);
  }
  if (ev.values.empty() || ev.error) {
    s += " raw ";
    for (auto b : ev.raw) {
      std::snprintf(buf, sizeof buf, "%02X", static_cast<unsigned>(b));
      s += buf;
    }
  }
  if (ev.error) s += " (" + *ev.error + ")";
  return s;
}

}  // namespace


struct App::Mqtt {
  std::unique_ptr<mqtt::MqttPublisher> publisher;
  // Retained node state topics to delete at a clean stop: every configured
  // node's and every one published.
  std::set<std::string> state_topics;
};

App::App(boost::asio::io_context& io, Config config, Logger& log, Composition networks)
    : io_(io),
      config_(std::move(config)),
      log_(log),
      tokens_([this] {
        std::vector<auth::TokenEntry> t;
        for (const auto& c : config_.http.tokens) t.push_back({c.name, c.role, c.sha256});
        return auth::TokenStore(std::move(t));
      }()),
      request_limiter_(config_.http.rate_limit, config_.http.rate_burst),
      sdo_shares_(auth::caller_share(kSdoQueueLimit)),
      encode_ctx_{config_.gateway_id},
      pipeline_(
          [this, mqtt_protobuf = config_.mqtt.enabled && config_.mqtt.format == PayloadFormat::Protobuf](
              std::uint32_t network, const canopen::Event& ev) {
            encode_ctx_.protobuf = mqtt_protobuf || (protobuf_demand_ && protobuf_demand_());
            return encode_event(ev, network, encode_ctx_);
          },
          cache_),
      monitor_(std::move(networks.monitor)),
      nets_(std::move(networks.units)) {
  for (auto& n : nets_) attach(*n);
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

std::error_code App::write_rpdo(std::uint32_t net_number, std::uint8_t node, std::uint16_t number,
                                std::span<const canopen::MappedValue> values, const canopen::Bytes* raw,
                                canopen::Bytes* sent, std::string_view who) {
  const std::string line = "RPDO write by " + requester(who) +
                           ": net " + std::to_string(net_number) + " node " + std::to_string(node) + " RPDO" +
                           std::to_string(number);
  Net* n = net(net_number);
  if (n == nullptr) {
    const auto ec = make_error_code(canopen::SdoAbort::NoSuchObject);
    audit(line + ": " + ec.message());
    return ec;
  }
  auto& tx = n->network->rpdo();
  const auto now = canopen::SteadyClock::now();
  const auto ec = raw != nullptr ? tx.set_raw(node, number, *raw, now) : tx.set_values(node, number, values, now);
  if (ec) {
    audit(line + ": " + ec.message());
    return ec;
  }
  const auto* p = tx.payload(node, number);
  if (sent != nullptr && p != nullptr) *sent = *p;
  audit(line + " = " + (p != nullptr ? detail::to_hex(*p) : std::string()) + ": sent");
  return {};
}

bool App::send_sync(std::uint32_t net_number, std::optional<std::uint8_t> counter, std::string_view who) {
  Net* n = net(net_number);
  if (n == nullptr) return false;
  n->local->send_sync(counter);  // 1005h's COB-ID, to the bus and the master side
  audit("SYNC by " + requester(who) + ": net " +
        std::to_string(net_number) + (counter ? " counter " + std::to_string(*counter) : std::string()) + ": sent");
  return true;
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

std::error_code App::read_pdo_config(std::uint32_t net_number, std::uint8_t node,
                                     std::function<void(const canopen::pdo::PdoReadReport&)> done,
                                     std::string_view who) {
  const std::string line = "PDO configuration read by " + requester(who) + ": net " + std::to_string(net_number) +
                           " node " + std::to_string(node);
  Net* n = net(net_number);
  if (n == nullptr) {
    const auto ec = make_error_code(canopen::SdoAbort::NoSuchObject);
    audit(line + ": " + ec.message());
    return ec;
  }
  auto ec = n->network->read_pdo_config(
      node,
      [this, line, done = std::move(done)](const canopen::pdo::PdoReadReport& r) {
        audit(line + ": " + r.summary());
        if (done) done(r);
      },
      canopen::SteadyClock::now());
  if (ec) {
    audit(line + ": " + ec.message());
    return ec;
  }
  return {};
}

canopen::sim::Simulator* App::simulator(std::uint32_t net_number) {
  Net* n = net(net_number);
  return n == nullptr ? nullptr : n->link.simulator.get();
}

bool App::set_simulated_link(std::uint32_t net_number, bool up) {
  Net* n = net(net_number);
  if (n == nullptr || !n->link.memory_gateway) return false;
  n->link.memory_gateway->set_link_up(up);
  return true;
}

canopen::can::MemoryBus* App::simulated_bus(std::uint32_t net_number) {
  Net* n = net(net_number);
  return n == nullptr || !n->link.memory_bus ? nullptr : &n->link.memory_bus->bus();
}

std::optional<canopen::can::ChannelStats> App::channel_stats(std::uint32_t net_number) const {
  if (net_number == 0 || net_number > nets_.size()) return std::nullopt;
  return nets_[net_number - 1]->channel->stats();
}

std::optional<App::MqttCounters> App::mqtt_counters() const {
  if (!mqtt_ || !mqtt_->publisher) return std::nullopt;
  const auto c = mqtt_->publisher->counters();
  MqttCounters out;
  out.connected = c.connected;
  out.published = c.published;
  out.acked = c.acked;
  out.dropped = c.dropped;
  out.queue_depth = c.queue_depth;
  out.queue_bytes = c.queue_bytes;
  out.reconnects = c.reconnects;
  out.requests_refused = c.replies_refused;
  out.stalls = c.stalls;
  out.storage_failing = c.storage_failing;
  const auto& q = mqtt_->publisher->queue_counters();
  const auto& t = mqtt_->publisher->tier_counters();
  out.memory_depth = t.memory_depth;
  out.spilled = t.spilled + t.to_disk;
  out.storage_bytes = q.storage_bytes;
  out.storage_syncs = q.syncs;
  out.storage_errors = q.write_errors;
  out.corrupt_records = q.corrupt_records;
  out.corrupt_bytes = q.corrupt_bytes + q.truncated_bytes;
  out.dropped_by_reason = {{"queue_full", q.dropped_qos0 + q.dropped_qos1 + q.dropped_span},
                           {"too_big", q.dropped_too_big},
                           {"storage_full", q.dropped_full + t.dropped_spill},
                           {"memory_full", t.dropped_memory},
                           {"rejected", c.rejected}};
  return out;
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
  if (config_.mqtt.enabled) start_mqtt();
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
    if (n->link.simulator) n->link.simulator->start();
  }
  std::string nets;
  for (const auto& n : nets_) nets += (nets.empty() ? "" : ", ") + n->label;
  log_.info("canopen-gateway started: " + nets + "; version " CANOPEN_GATEWAY_VERSION ", gateway id " +
            config_.gateway_id);
  log_.flush();
}

void App::start_mqtt() {
  mqtt_ = std::make_unique<Mqtt>();
  mqtt::MqttConfig mc;
  mc.server_uri = config_.mqtt.uri;
  mc.client_id = config_.mqtt.client_id;
  mc.username = config_.mqtt.username;
  mc.password = config_.mqtt.password;
  mc.ca_file = config_.mqtt.ca_file;
  mc.cert_file = config_.mqtt.cert_file;
  mc.key_file = config_.mqtt.key_file;
  mc.gateway_id = config_.gateway_id;
  mc.format = config_.mqtt.format == PayloadFormat::Protobuf ? mqtt::PayloadFormat::Protobuf : mqtt::PayloadFormat::Json;
  for (std::size_t k = 0; k < mc.qos.size(); ++k) {
    mc.qos[k] = static_cast<std::uint8_t>(config_.mqtt.qos_for(static_cast<EventKind>(k)));
    const auto mode = config_.mqtt.storage_for(static_cast<EventKind>(k));
    mc.storage[k] = mode == StorageMode::Disk     ? mqtt::StorageMode::Disk
                    : mode == StorageMode::Outage ? mqtt::StorageMode::Outage
                                                  : mqtt::StorageMode::Memory;
  }
  mc.queue.dir = config_.mqtt.queue_dir;
  mc.queue.max_bytes = config_.mqtt.queue_max_bytes;
  mc.queue.max_messages = config_.mqtt.queue_max_messages;
  mc.reply_topics = config_.mqtt.reply_topics;
  mc.memory_max_bytes = config_.mqtt.memory_max_bytes;
  mc.memory_max_messages = config_.mqtt.memory_max_messages;
  // The Will is fixed at start: it carries the start time and uptime 0
  // (the broker publishes it when it notices the loss; only a clean stop
  // knows when it went offline).
  mc.online_payload = status_payload(true);
  mc.offline_payload = status_payload(false);
  mqtt_->publisher = std::make_unique<mqtt::MqttPublisher>(
      io_, mc, log_, [this](const ApiRequest& req, ReplyFn reply) { handle_request(req, std::move(reply)); });
  auto* pub = mqtt_->publisher.get();
  for (const auto& n : nets_) {
    for (const auto& node : n->cfg.nodes) mqtt_->state_topics.insert(node_topic(encode_ctx_, n->number, node.id, "state"));
  }
  const bool heartbeats = config_.mqtt.heartbeat;
  const auto min_interval = config_.mqtt.heartbeat_min_interval;
  pipeline_.add_consumer([this, pub, heartbeats, min_interval](const EncodedEventPtr& ev) {
    if (ev->kind == EventKind::State) mqtt_->state_topics.insert(ev->topic);
    if (ev->kind == EventKind::Heartbeat) {
      if (!heartbeats) return;
      if (min_interval.count() > 0) {
        auto* n = net(ev->network);
        if (n != nullptr) {
          const auto now = std::chrono::steady_clock::now();
          auto [it, fresh] = n->last_heartbeat_published.try_emplace(ev->node, now);
          if (!fresh) {
            if (now - it->second < min_interval) return;
            it->second = now;
          }
        }
      }
    }
    pub->publish(ev);
  });
  pub->start();
  // Where to look, for a person: the broker and the topics to subscribe to.
  log_.info("MQTT: broker " + config_.mqtt.uri + ", topic prefix canopen/" + config_.gateway_id + "/ (subscribe to canopen/" +
            config_.gateway_id + "/#)");
}

std::string App::status_payload(bool online) const {
  GatewayStatusInfo status;
  status.online = online;
  status.version = CANOPEN_GATEWAY_VERSION;
  status.node_id = nets_.empty() ? 127 : nets_.front()->cfg.node_id;
  for (const auto& n : nets_) status.networks.push_back(n->number);
  status.timestamp = std::chrono::system_clock::now();
  status.uptime_ms = static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - started_at_).count());
  auto e = encode_status(status, EncodeContext{config_.gateway_id});
  return config_.mqtt.format == PayloadFormat::Protobuf ? e->binary : e->json;
}

void App::stop() {
  if (stopped_) return;
  stopped_ = true;
  for (auto& n : nets_) {
    if (n->link.simulator) n->link.simulator->stop();
  }
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
  if (mqtt_ && mqtt_->publisher) {
    // No retained message may claim a node runs once the gateway is gone:
    // its state topics are deleted (an empty retained message; not a state
    // of the contract's list, which would be a claim about the node), and
    // the offline status says when and after how long.
    mqtt::MqttPublisher::Farewell last;
    const auto qos = static_cast<std::uint8_t>(config_.mqtt.qos_for(EventKind::State));
    for (const auto& topic : mqtt_->state_topics) last.messages.push_back({topic, std::string(), qos, true});
    last.offline_payload = status_payload(false);
    mqtt_->publisher->stop(std::chrono::seconds(2), last);
  }
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
  // Durably reserved before the event leaves the process (one write per block).
  if (auto ec = n.seq ? n.seq->use(ev.seq) : std::error_code())
    log_.warn(n.label + ": cannot store the event sequence in " + n.seq->file().string() + ": " + ec.message() +
              " (numbers may repeat after a crash)");
  pipeline_.on_event(n.number, ev);
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
    char code[48];
    std::snprintf(code, sizeof code, "%04Xh, error register %02Xh", e->error_code, e->error_register);
    log_.warn(prefix + " node " + std::to_string(e->node) + " EMCY " + code + ": " + e->description);
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

void App::handle_request(const ApiRequest& request, ReplyFn reply) {
  ReplyOptions opts;
  opts.protobuf = request.protobuf;
  ApiRequest identified;
  if (!request.authenticated) {
    identified = request;
    const auto denial = auth::identify(identified, tokens_, config_.mqtt.requests_role.value_or(Role::None));
    // Per caller, as the HTTP authorizer does per address, and before
    // anything is logged or done: a flood with bad tokens is limited too.
    if (!request_limiter_.allow(identified.caller, auth::RateLimiter::Clock::now())) {
      ++counters_.requests_rate_limited;
      auto r = problem(429, "too many requests from " + identified.caller + "; slow down (http.rate-limit)", opts);
      r.retry_after = 1;
      reply(std::move(r));
      return;
    }
    if (const auto& d = denial) {
      ++counters_.auth_failures;
      audit("auth failure: " + requester(identified.who) + ": request to net " + std::to_string(request.network) +
            " node " + std::to_string(request.node) + ": " + std::to_string(d->status) + " " + d->detail);
      reply(problem(d->status, d->detail, opts));
      return;
    }
  }
  const ApiRequest& req = request.authenticated ? request : identified;
  Net* n = net(req.network);
  if (n == nullptr) {
    reply(problem(404, "network " + std::to_string(req.network) + " is not configured (networks are 1.." +
                           std::to_string(nets_.size()) + ")",
                  opts));
    return;
  }
  if (req.node > 127 || (req.node == 0 && req.kind != RequestKind::Nmt)) {
    reply(problem(400, "node-ID " + std::to_string(req.node) + " is out of range 1..127", opts));
    return;
  }
  if (req.kind != RequestKind::Nmt) {  // NMT: once its command is known
    if (auto r = refused(*n, req, auth::required_role(req.kind, 0),
                         req.kind == RequestKind::SdoRead ? "SDO read" : "SDO write", opts)) {
      reply(std::move(*r));
      return;
    }
  }
  switch (req.kind) {
    case RequestKind::SdoRead:
      sdo_read(*n, req, std::move(reply));
      break;
    case RequestKind::SdoWrite:
      sdo_write(*n, req, std::move(reply));
      break;
    case RequestKind::Nmt:
      nmt(*n, req, std::move(reply));
      break;
  }
}

namespace {


// The type of index/sub: the request's, else the node's EDS/DCF entry's.
// DOMAIN (raw hex) when neither knows. Error reply when the EDS lacks it.
std::optional<ApiReply> resolve_type(const canopen::eds::DeviceDescription* desc, std::uint16_t index,
                                     std::uint8_t sub, std::optional<canopen::DataType> requested,
                                     const ReplyOptions& opts, canopen::DataType& out,
                                     const canopen::od::SubEntry** entry) {
  *entry = desc != nullptr ? desc->od.find(index, sub) : nullptr;
  if (requested) {
    out = *requested;
    return std::nullopt;
  }
  if (desc == nullptr) {
    out = canopen::DataType::Domain;  // no EDS: raw bytes as hex
    return std::nullopt;
  }
  if (*entry == nullptr) {
    return problem(404, "the node's EDS/DCF has no object " + canopen::od::object_label(index, sub) +
                            " (give ?type= to ask anyway)",
                   opts);
  }
  out = (*entry)->type;
  return std::nullopt;
}

// The same for the gateway's own dictionary.
std::optional<ApiReply> resolve_own_type(const canopen::od::ObjectDictionary& od, std::uint16_t index, std::uint8_t sub,
                                         std::optional<canopen::DataType> requested, const ReplyOptions& opts,
                                         canopen::DataType& out, const canopen::od::SubEntry** entry) {
  *entry = od.find(index, sub);
  if (*entry == nullptr) {
    // As the device would answer (7.2.4.3.17): the object does not exist.
    const auto code = od.find(index) == nullptr ? canopen::SdoAbort::NoSuchObject : canopen::SdoAbort::NoSuchSubIndex;
    return sdo_error_reply(make_error_code(code), true, {}, opts);
  }
  out = requested.value_or((*entry)->type);
  return std::nullopt;
}

}  // namespace

void App::sdo_read(Net& n, const ApiRequest& req, ReplyFn reply) {
  auto params = parse_sdo_read(req.body, req.protobuf);
  ReplyOptions opts;
  opts.protobuf = req.protobuf;
  if (!params) {
    reply(bad_request(params.error(), opts));
    return;
  }
  opts.correlation_id = params->correlation_id;
  const auto index = *params->index;
  const auto sub = *params->sub;
  canopen::DataType type{};
  const canopen::od::SubEntry* entry = nullptr;
  if (req.node == n.cfg.node_id) {
    // The gateway's own node: its socket does not hear its own SDO request,
    // so the dictionary answers directly, with the same access rules.
    if (auto err = resolve_own_type(*n.own_od, index, sub, params->type, opts, type, &entry)) {
      reply(std::move(*err));
      return;
    }
    ++counters_.sdo_requests;
    auto bytes = n.own_od->read(index, sub);
    if (!bytes) {
      reply(sdo_error_reply(bytes.error().code, true, bytes.error().detail, opts));
      return;
    }
    auto v = canopen::decode(type, *bytes);
    if (!v) {
      reply(problem(400, canopen::od::object_label(index, sub) + ": the value read is not a " +
                             std::string(canopen::cia309_name(type)) + ": " + v.error().detail,
                    opts));
      return;
    }
    reply(sdo_response(*v, opts));
    return;
  }
  if (auto err = resolve_type(description(n.number, req.node), index, sub, params->type, opts, type, &entry)) {
    reply(std::move(*err));
    return;
  }
  canopen::sdo::Request r;
  r.node = req.node;
  r.index = index;
  r.sub = sub;
  // The reply must decode as `type`, so a fixed-size type is the size to
  // expect: small objects then skip the block initiate (7.2.4.3.13), which
  // costs devices without block transfer a refusal. Strings and domains
  // stay unknown.
  r.expected_size = canopen::fixed_size(type);
  if (auto full = take_sdo_place(n, req, opts)) {
    reply(std::move(*full));
    return;
  }
  ++counters_.sdo_requests;
  r.on_done = [this, type, opts, reply, net = n.number, node = req.node, caller = req.caller,
               t0 = std::chrono::steady_clock::now()](canopen::sdo::TransferResult&& res) {
    sdo_place_freed(net, node, caller);
    sdo_finished(t0);
    if (!res.ok()) {
      reply(transfer_failed(res, opts));
      return;
    }
    auto v = canopen::decode(type, res.data);
    if (!v) {
      reply(problem(502, "the device answered " + std::to_string(res.data.size()) + " bytes, which is not a " +
                             std::string(canopen::cia309_name(type)) + ": " + v.error().detail,
                    opts));
      return;
    }
    reply(sdo_response(*v, opts));
  };
  submitted(n, n.network->sdo().upload(std::move(r), canopen::SteadyClock::now()), req.node, req.caller, opts, reply);
}

void App::sdo_write(Net& n, const ApiRequest& req, ReplyFn reply) {
  auto params = parse_sdo_write(req.body, req.protobuf);
  ReplyOptions opts;
  opts.protobuf = req.protobuf;
  if (!params) {
    reply(bad_request(params.error(), opts));
    return;
  }
  opts.correlation_id = params->correlation_id;
  const auto index = *params->index;
  const auto sub = *params->sub;
  canopen::DataType type{};
  const canopen::od::SubEntry* entry = nullptr;
  const bool own = req.node == n.cfg.node_id;
  if (auto err = own ? resolve_own_type(*n.own_od, index, sub, params->type, opts, type, &entry)
                     : resolve_type(description(n.number, req.node), index, sub, params->type, opts, type, &entry)) {
    reply(std::move(*err));
    return;
  }
  // The value is checked against type and EDS limits before anything goes
  // on the bus; the errors name the object and the type.
  auto value = params->value_as(type);
  if (!value) {
    reply(bad_request(value.error(), opts));
    return;
  }
  if (entry != nullptr) {
    std::string detail;
    if (auto ec = canopen::check_limits(*value, entry->low, entry->high, &detail)) {
      reply(problem(400, canopen::od::object_label(index, sub) + ": " + detail, opts));
      return;
    }
  }
  ++counters_.sdo_requests;
  const canopen::Value written = *value;
  const std::string line = "SDO write by " + requester(req.who) + ": net " + std::to_string(n.number) + " node " +
                           std::to_string(req.node) + " " + hex4(index) + " sub " + std::to_string(sub) + " = " +
                           canopen::format_value(written);
  if (own) {
    // As an SDO download would: access, length and limit checks, hooks and
    // observers (a write to 1016h reconfigures the heartbeat consumers).
    if (auto ec = n.own_od->write(index, sub, canopen::encode(written))) {
      audit(line + ": " + ec.message());
      reply(sdo_error_reply(ec, true, {}, opts));
      return;
    }
    audit(line + ": ok");
    reply(sdo_response(written, opts));
    return;
  }
  if (auto full = take_sdo_place(n, req, opts)) {
    audit(line + ": " + std::to_string(full->status) + " (" + req.caller + " has its share of the node's SDO queue)");
    reply(std::move(*full));
    return;
  }
  canopen::sdo::Request r;
  r.node = req.node;
  r.index = index;
  r.sub = sub;
  r.on_done = [this, opts, reply, written, line, net = n.number, node = req.node, caller = req.caller,
               t0 = std::chrono::steady_clock::now()](canopen::sdo::TransferResult&& res) {
    sdo_place_freed(net, node, caller);
    sdo_finished(t0);
    if (!res.ok()) {
      audit(line + ": " + res.error.message());
      reply(transfer_failed(res, opts));
      return;
    }
    audit(line + ": ok");
    reply(sdo_response(written, opts));
  };
  submitted(n, n.network->sdo().download(std::move(r), canopen::encode(written), canopen::SteadyClock::now()), req.node,
            req.caller, opts, reply);
}

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

void App::sdo_finished(std::chrono::steady_clock::time_point submitted_at) {
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - submitted_at).count();
  const auto& bounds = Counters::kSdoLatencyBounds;
  const auto slot = static_cast<std::size_t>(std::lower_bound(bounds.begin(), bounds.end(), s) - bounds.begin());
  ++counters_.sdo_latency_counts[slot];
  counters_.sdo_latency_sum += s;
  ++counters_.sdo_latency_count;
}

ApiReply App::transfer_failed(const canopen::sdo::TransferResult& res, const ReplyOptions& opts) {
  const bool remote = res.origin == canopen::sdo::Origin::Remote;
  if (remote) ++counters_.sdo_aborts;
  if (res.error == make_error_code(canopen::SdoAbort::Timeout)) ++counters_.sdo_timeouts;
  return sdo_error_reply(res.error, remote, res.detail, opts);
}

void App::submitted(Net& n, const canopen::Result<canopen::sdo::RequestId>& id, std::uint8_t node,
                    const std::string& caller, const ReplyOptions& opts, const ReplyFn& reply) {
  // Queue full for the node (060A0023h): the client should come back later.
  if (!id) {
    sdo_place_freed(n.number, node, caller);  // the handler that would give it back never runs
    auto r = problem(429, "too many SDO requests queued for node " + std::to_string(node), opts);
    r.retry_after = 1;
    reply(std::move(r));
    return;
  }
}

std::optional<ApiReply> App::take_sdo_place(const Net& n, const ApiRequest& req, const ReplyOptions& opts) {
  if (sdo_shares_.take(sdo_queue_key(n.number, req.node), req.caller)) return std::nullopt;
  ++counters_.sdo_share_refused;
  const std::string who = req.caller.empty() ? std::string("this caller") : req.caller;
  auto r = problem(429,
                   who + " has " + std::to_string(sdo_shares_.share()) + " SDO requests waiting for node " +
                       std::to_string(req.node) + " already, its share of the node's queue of " +
                       std::to_string(kSdoQueueLimit) + "; send more once one is answered (other callers still get in)",
                   opts);
  r.retry_after = 1;
  return r;
}

void App::sdo_place_freed(std::uint32_t net, std::uint8_t node, const std::string& caller) {
  sdo_shares_.give_back(sdo_queue_key(net, node), caller);
}

void App::nmt(Net& n, const ApiRequest& req, ReplyFn reply) {
  auto params = parse_nmt(req.body, req.protobuf);
  ReplyOptions opts;
  opts.protobuf = req.protobuf;
  if (!params) {
    reply(bad_request(params.error(), opts));
    return;
  }
  opts.correlation_id = params->correlation_id;
  if (auto r = refused(n, req, auth::required_role(RequestKind::Nmt, static_cast<std::uint8_t>(params->command)),
                       "NMT " + std::string(nmt_command_name(params->command)), opts)) {
    reply(std::move(*r));
    return;
  }
  ++counters_.nmt_commands;
  n.network->send_nmt(params->command, req.node);
  audit("NMT " + std::string(nmt_command_name(params->command)) + " by " + requester(req.who) + ": net " +
        std::to_string(n.number) + " node " + std::to_string(req.node) + ": sent");
  reply(nmt_response(n.number, req.node, params->command, opts));
}

std::optional<ApiReply> App::refused(const Net& n, const ApiRequest& req, Role need, std::string_view what,
                                     const ReplyOptions& opts) {
  auto d = auth::check_role(req, need);
  if (!d) return std::nullopt;
  ++counters_.auth_failures;
  audit("auth failure: " + requester(req.who) + ": " + std::string(what) + " net " + std::to_string(n.number) +
        " node " + std::to_string(req.node) + ": " + std::to_string(d->status) + " " + d->detail);
  return problem(d->status, d->detail, opts);
}

}  // namespace gateway
