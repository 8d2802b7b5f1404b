#include "sparkplug/edge_session.hpp"

#include <boost/json/parse.hpp>
#include <boost/json/value.hpp>
#include <stdexcept>

namespace gateway::sparkplug {

namespace {

// Spec ch4: ids are UTF-8 without the MQTT wildcards and the level separator.
void check_id(std::string_view what, std::string_view id, bool optional) {
  if (id.empty() && optional) return;
  if (id.empty() || id.find_first_of("+/#") != std::string_view::npos)
    throw std::invalid_argument(std::string(what) + " \"" + std::string(id) +
                                "\" is empty or holds '+', '/' or '#' (Sparkplug B topic rules)");
}

Metric control_metric(std::string_view name, std::uint64_t now) {
  Metric m;
  m.name = std::string(name);
  m.datatype = DataType::Boolean;
  m.value = false;
  m.timestamp = now;
  return m;
}

// Births need every metric's timestamp (spec ch6 "Metric"); one that never
// had a value yet gets the time it became known.
void stamp(std::vector<Metric>& metrics, std::uint64_t now) {
  for (auto& m : metrics)
    if (m.timestamp == 0) m.timestamp = now;
}

bool is_true(const Value& v) {
  if (const auto* b = std::get_if<bool>(&v)) return *b;
  return false;
}

}  // namespace

EdgeSession::EdgeSession(Options opts, BdSeqStore& store) : opts_(std::move(opts)), store_(store) {
  check_id("sparkplug group id", opts_.group_id, false);
  check_id("sparkplug edge node id", opts_.edge_node_id, false);
  check_id("sparkplug primary host id", opts_.primary_host_id, true);
  prefix_ = std::string(kNamespace) + "/" + opts_.group_id + "/";
}

std::string EdgeSession::node_topic(std::string_view type) const {
  std::string t = prefix_;
  t.append(type).append("/").append(opts_.edge_node_id);
  return t;
}

std::string EdgeSession::device_topic(std::string_view type, std::string_view device) const {
  std::string t = node_topic(type);
  t.append("/").append(device);
  return t;
}

std::string EdgeSession::ndeath_payload(std::uint64_t now) const {
  // NDEATH: only the bdSeq metric (Int64), no seq (spec ch6 payloads-ndeath-*).
  // Stamped with `now` in the payload and the metric: hosts show a death
  // at 0 as 1970 (issue 27 item 7).
  std::string p;
  Metric m;
  m.name = std::string(kBdSeq);
  m.datatype = DataType::Int64;
  m.value = std::uint64_t{bd_seq_.value_or(0)};
  m.timestamp = now;
  append_header(p, now);
  append_metric(p, m, Form::Birth);
  return p;
}

EdgeSession::ConnectParams EdgeSession::connect_params(std::uint64_t now) {
  ConnectParams c;
  const auto next = store_.next();
  bd_seq_ = next.bd_seq;
  c.bd_seq = next.bd_seq;
  c.will_topic = node_topic("NDEATH");
  c.will_payload = ndeath_payload(now);  // the Will: the connect time
  c.store_note = next.note;
  if (next.error) {
    if (!c.store_note.empty()) c.store_note += "; ";
    c.store_note += "Sparkplug bdSeq not stored in " + store_.file().string() + ": " + next.error.message();
  }
  return c;
}

std::uint8_t EdgeSession::take_seq() { return seq_++; }  // uint8_t: 255 wraps to 0 (spec ch6 sequence-num)

void EdgeSession::publish(std::vector<Outgoing>& out, std::string topic, std::string payload, std::uint8_t qos) {
  out.push_back({Outgoing::Kind::Publish, std::move(topic), std::move(payload), qos, false});
}

void EdgeSession::connected(std::vector<Outgoing>& out, std::uint64_t now) {
  // A fresh session (clean start): nothing is born on it yet.
  for (auto& d : devices_) d.born = false;
  host_online_ = false;
  // Subscriptions first: the broker handles them before the births that
  // follow on the same connection (spec ch5: NCMD before NBIRTH, QoS 1).
  out.push_back({Outgoing::Kind::Subscribe, node_topic("NCMD"), {}, 1, false});
  out.push_back({Outgoing::Kind::Subscribe, node_topic("DCMD") + "/+", {}, 1, false});
  if (!opts_.primary_host_id.empty()) {
    out.push_back({Outgoing::Kind::Subscribe, std::string(kNamespace) + "/STATE/" + opts_.primary_host_id, {}, 1,
                   false});
    state_ = State::WaitingForHost;  // the retained STATE comes right after the SUBACK
    return;
  }
  births(out, now);
}

void EdgeSession::births(std::vector<Outgoing>& out, std::uint64_t now, bool with_devices) {
  state_ = State::Born;
  last_rebirth_ = now;
  seq_ = 0;  // NBIRTH seq is 0, on rebirths too (spec ch4 topics-nbirth-seq-num)
  std::string p;
  append_header(p, now);
  Metric bd;
  bd.name = std::string(kBdSeq);
  bd.datatype = DataType::Int64;
  bd.value = std::uint64_t{bd_seq_.value_or(0)};
  bd.timestamp = now;
  append_metric(p, bd, Form::Birth);
  // Never aliased (spec ch5 data-commands-rebirth-*).
  append_metric(p, control_metric(kNodeRebirth, now), Form::Birth);
  for (const auto& m : node_metrics_) append_metric(p, m, Form::Birth);
  append_seq(p, take_seq());
  publish(out, node_topic("NBIRTH"), std::move(p));
  for (auto& d : devices_) {
    d.born = false;  // a new birth sequence: no DDATA before this one's DBIRTH
    if (d.online && with_devices) dbirth(out, d, now);
  }
}

void EdgeSession::dbirth(std::vector<Outgoing>& out, Device& d, std::uint64_t now) {
  std::string p;
  append_header(p, now);
  for (const auto& m : d.metrics) append_metric(p, m, Form::Birth);
  append_metric(p, control_metric(kDeviceRebirth, now), Form::Birth);
  append_seq(p, take_seq());
  publish(out, device_topic("DBIRTH", d.id), std::move(p));
  d.born = true;
}

void EdgeSession::lost() {
  state_ = State::Offline;
  host_online_ = false;
  for (auto& d : devices_) d.born = false;
}

void EdgeSession::end_session(std::vector<Outgoing>& out, std::uint64_t now) {
  // NDEATH at QoS 1 like the Will; on 3.1.1 the DISCONNECT suppresses the
  // Will, so this is the only NDEATH hosts get (spec ch5 intentional-disconnect).
  publish(out, node_topic("NDEATH"), ndeath_payload(now), 1);  // the stop time
  out.push_back({Outgoing::Kind::Disconnect, {}, {}, 0, false});
  state_ = State::Stopping;
  for (auto& d : devices_) d.born = false;
}

void EdgeSession::rebirth(std::vector<Outgoing>& out, std::uint64_t now) {
  if (state_ == State::Born) births(out, now);
}

void EdgeSession::stop(std::vector<Outgoing>& out, std::uint64_t now) {
  if (state_ == State::Offline || state_ == State::Stopping) return;
  end_session(out, now);
}

EdgeSession::Device* EdgeSession::find(std::string_view id) {
  for (auto& d : devices_)
    if (d.id == id) return &d;
  return nullptr;
}

void EdgeSession::set_node_metrics(std::vector<Metric> metrics, std::vector<Outgoing>& out, std::uint64_t now) {
  stamp(metrics, now);
  node_metrics_ = std::move(metrics);
  if (state_ == State::Born) births(out, now);
}

bool EdgeSession::device_online(std::vector<Outgoing>& out, std::string device_id, std::vector<Metric> metrics,
                                std::uint64_t now) {
  if (device_id.empty() || device_id.find_first_of("+/#") != std::string::npos) return false;
  stamp(metrics, now);
  Device* d = find(device_id);
  if (!d) {
    devices_.push_back(Device{std::move(device_id), {}, false, false});
    d = &devices_.back();
  }
  d->metrics = std::move(metrics);
  d->online = true;
  if (state_ == State::Born) dbirth(out, *d, now);
  return true;
}

void EdgeSession::device_lost(std::vector<Outgoing>& out, std::string_view device_id, std::uint64_t now) {
  Device* d = find(device_id);
  if (!d || !d->online) return;
  d->online = false;
  if (state_ != State::Born || !d->born) return;
  d->born = false;
  // DDEATH: timestamp (when the device went offline, for hosts) and seq.
  std::string p;
  append_header(p, now);
  append_seq(p, take_seq());
  publish(out, device_topic("DDEATH", d->id), std::move(p));
}

namespace {
// Keeps each update's value; returns whether any was for a known metric.
bool apply(std::vector<Metric>& metrics, std::span<const Update> updates) {
  bool any = false;
  for (const auto& u : updates) {
    if (u.metric >= metrics.size()) continue;
    metrics[u.metric].value = u.value;
    metrics[u.metric].timestamp = u.timestamp;
    any = true;
  }
  return any;
}
void append_updates(std::string& p, const std::vector<Metric>& metrics, std::span<const Update> updates) {
  for (const auto& u : updates)
    if (u.metric < metrics.size()) append_metric(p, metrics[u.metric], Form::Data);
}
}  // namespace

void EdgeSession::node_data(std::vector<Outgoing>& out, std::span<const Update> updates, std::uint64_t now) {
  if (!apply(node_metrics_, updates) || state_ != State::Born) return;
  std::string p;
  append_header(p, now);
  append_updates(p, node_metrics_, updates);
  append_seq(p, take_seq());
  publish(out, node_topic("NDATA"), std::move(p));
}

void EdgeSession::device_data(std::vector<Outgoing>& out, std::string_view device_id, std::span<const Update> updates,
                              std::uint64_t now) {
  Device* d = find(device_id);
  if (!d || !apply(d->metrics, updates) || state_ != State::Born || !d->born) return;
  std::string p;
  append_header(p, now);
  append_updates(p, d->metrics, updates);
  append_seq(p, take_seq());
  publish(out, device_topic("DDATA", d->id), std::move(p));
}

std::optional<WriteCommand> EdgeSession::received(std::vector<Outgoing>& out, std::string_view topic,
                                                  std::string_view payload, std::uint64_t now) {
  if (!opts_.primary_host_id.empty() &&
      topic == std::string(kNamespace) + "/STATE/" + opts_.primary_host_id) {
    handle_state(out, payload, now);
    return std::nullopt;
  }
  if (topic == node_topic("NCMD")) {
    const auto cmd = decode_command(payload);
    if (!cmd) return std::nullopt;
    return handle_command(out, *cmd, nullptr, now);
  }
  const std::string dcmd = node_topic("DCMD") + "/";
  if (topic.starts_with(dcmd)) {
    Device* d = find(topic.substr(dcmd.size()));
    const auto cmd = decode_command(payload);
    if (!d || !cmd) return std::nullopt;
    return handle_command(out, *cmd, d, now);
  }
  return std::nullopt;
}

std::optional<WriteCommand> EdgeSession::handle_command(std::vector<Outgoing>& out, const Command& cmd, Device* device,
                                                        std::uint64_t now) {
  const std::vector<Metric>& metrics = device ? device->metrics : node_metrics_;
  const std::string_view rebirth = device ? kDeviceRebirth : kNodeRebirth;
  WriteCommand w;
  if (device) w.device = device->id;
  bool rebirth_asked = false;
  for (const auto& c : cmd.metrics) {
    if (c.name == rebirth && !c.alias) {
      rebirth_asked = rebirth_asked || is_true(c.value);
      continue;
    }
    std::optional<std::size_t> at;
    for (std::size_t i = 0; i < metrics.size() && !at; ++i)
      if (c.alias ? metrics[i].alias == c.alias : (!c.name.empty() && metrics[i].name == c.name)) at = i;
    std::optional<Value> v = at ? typed_value(c.value, metrics[*at].datatype) : std::nullopt;
    if (!v) {
      w.refused.push_back(c.alias ? "alias " + std::to_string(*c.alias) : c.name);
      continue;
    }
    w.items.push_back({*at, std::move(*v)});
  }
  // Rebirth: stop DATA, the whole birth sequence (node) or that DBIRTH
  // (device), same bdSeq (spec ch5 rebirth-action-1..3). Before the births
  // (waiting for the Primary Host) they come anyway.
  if (rebirth_asked && state_ == State::Born) {
    const bool owner = opts_.owner_reads_rebirths;
    if (!device)
      births(out, now, !owner);
    else if (device->online && !owner)
      dbirth(out, *device, now);
    else if (owner)
      device->born = false;  // no DDATA until the owner's DBIRTH
    w.rebirth = owner;
  }
  if (w.items.empty() && w.refused.empty() && !w.rebirth) return std::nullopt;
  return w;
}

void EdgeSession::handle_state(std::vector<Outgoing>& out, std::string_view payload, std::uint64_t now) {
  // {"online": <bool>, "timestamp": <UTC ms>} (spec ch6 "STATE").
  boost::system::error_code ec;
  const boost::json::value v = boost::json::parse(payload, ec);
  const auto* obj = ec ? nullptr : v.if_object();
  if (!obj) return;
  const auto* online = obj->if_contains("online");
  const auto* ts = obj->if_contains("timestamp");
  if (!online || !online->is_bool() || !ts) return;
  std::uint64_t stamp_ms = 0;
  if (ts->is_uint64())
    stamp_ms = ts->get_uint64();
  else if (ts->is_int64() && ts->get_int64() >= 0)
    stamp_ms = static_cast<std::uint64_t>(ts->get_int64());
  else
    return;
  // Older than the latest accepted STATE: stale, ignored (spec ch5).
  if (host_timestamp_ && stamp_ms < *host_timestamp_) return;
  host_timestamp_ = stamp_ms;
  host_online_ = online->get_bool();
  if (host_online_) {
    if (state_ == State::WaitingForHost) births(out, now);
    return;
  }
  // Offline: NDEATH and disconnect; the owner connects again (to the next
  // server, if several) and waits for online there.
  if (state_ == State::Born) end_session(out, now);
}

}  // namespace gateway::sparkplug
