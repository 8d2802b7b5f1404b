#include "sparkplug/sparkplug_output.hpp"

#include <chrono>

#include "canopen/pdo/mapping.hpp"
#include "core/format.hpp"

namespace gateway {

namespace {

using sparkplug::Update;

core::Caller sparkplug_caller(std::string who, Role role) {
  core::Caller c;
  c.transport = core::Transport::sparkplug;
  c.who = std::move(who);
  c.authenticated = true;
  c.role = role;
  c.key = "sparkplug";
  return c;
}

std::string where(std::uint32_t network, std::uint8_t node) {
  return "sparkplug: network " + std::to_string(network) + " node " + std::to_string(node);
}

}  // namespace

SparkplugOutput::SparkplugOutput(sparkplug::EdgeSession& edge, Send send, Execute execute,
                                 std::vector<Network> networks, Sources sources, Options options, Logger& log)
    : edge_(edge),
      send_(std::move(send)),
      execute_(std::move(execute)),
      networks_(std::move(networks)),
      sources_(std::move(sources)),
      options_(options),
      log_(log) {
  std::vector<sparkplug::NodeName> names;
  for (const auto& n : networks_)
    for (const auto& node : n.nodes) names.push_back({n.number, node.id, node.name});
  auto ids = sparkplug::device_ids(names);
  for (const auto& note : ids.notes) log_.warn("sparkplug: " + note);
  std::size_t k = 0;
  for (const auto& n : networks_)
    for (const auto& node : n.nodes) {
      Device& d = devices_.emplace_back();
      d.network = n.number;
      d.node = node.id;
      d.id = ids.ids[k++];
      d.listed = node.sparkplug_metrics;
      by_node_[{d.network, d.node}] = &d;
    }
  bus_state_.resize(networks_.size());
}

SparkplugOutput::~SparkplugOutput() { *alive_ = false; }

std::string SparkplugOutput::device_id(std::uint32_t network, std::uint8_t node) const {
  auto it = by_node_.find({network, node});
  return it == by_node_.end() ? std::string() : it->second->id;
}

SparkplugOutput::Device* SparkplugOutput::find(std::uint32_t network, std::uint8_t node) {
  auto it = by_node_.find({network, node});
  return it == by_node_.end() ? nullptr : it->second;
}

SparkplugOutput::Device* SparkplugOutput::find(std::string_view id) {
  for (auto& d : devices_)
    if (d.id == id) return &d;
  return nullptr;
}

SparkplugOutput::Device& SparkplugOutput::device(std::uint32_t network, std::uint8_t node) {
  if (Device* d = find(network, node)) return *d;
  // Heard but not configured: no EDS, no sparkplug-metrics, the fallback id
  // (a configured node may have taken it as its name: then a suffix).
  Device& d = devices_.emplace_back();
  d.network = network;
  d.node = node;
  d.id = "net" + std::to_string(network) + "-node" + std::to_string(node);
  if (find(d.id) != &d) d.id += "-unconfigured";
  by_node_[{network, node}] = &d;
  return d;
}

std::uint64_t SparkplugOutput::stamp(const canopen::Event& ev) const {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(ev.timestamp.time_since_epoch()).count();
  if (ms > 0) return static_cast<std::uint64_t>(ms);
  return sources_.now_ms();
}

void SparkplugOutput::start() {
  std::vector<sparkplug::Metric> metrics;
  for (std::size_t i = 0; i < networks_.size(); ++i) {
    const std::uint32_t net = networks_[i].number;
    sparkplug::Metric m;
    m.name = sparkplug::bus_state_name(net);
    m.datatype = sparkplug::DataType::String;
    if (options_.aliases) m.alias = sparkplug::bus_state_alias(net);
    if (sources_.bus_state)
      if (auto s = sources_.bus_state(net)) {
        bus_state_[i] = std::string(canopen::can::to_string(*s));
        m.value = bus_state_[i];
      }
    metrics.push_back(std::move(m));
  }
  std::vector<sparkplug::Outgoing> out;
  edge_.set_node_metrics(std::move(metrics), out, sources_.now_ms());
  send_(out);
}

sparkplug::DeviceModel SparkplugOutput::build(Device& d) {
  sparkplug::DeviceModel::Input in;
  in.network = d.network;
  in.node = d.node;
  in.device_id = d.id;
  in.description = sources_.description ? sources_.description(d.network, d.node) : nullptr;
  in.pdos = sources_.pdo_table ? sources_.pdo_table(d.network) : nullptr;
  in.listed = d.listed;
  in.aliases = options_.aliases;
  auto model = sparkplug::DeviceModel::build(in);
  if (d.model) model.carry_values(*d.model);
  if (model.notes() != d.last_notes) {
    for (const auto& note : model.notes()) log_.info(where(d.network, d.node) + ": " + note);
    d.last_notes = model.notes();
  }
  return model;
}

void SparkplugOutput::begin_birth(Device& d) {
  ++d.generation;
  d.model = build(d);
  if (d.state) (void)d.model->on_state(*d.state, sources_.now_ms());
  d.phase = Device::Phase::Reading;
  d.unheard_reads = 0;
  read_next(d, d.generation, 0);
}

// What the DBIRTH declares, read one after the other (one place of the
// node's SDO queue at a time, whatever the list's length): first every
// sparkplug-metrics object, again for every birth (contract: rebirths
// too), then the other objects that have no value yet (a TPDO not heard
// since, an RPDO output never written: issue 27 item 8), at most
// kMaxUnheardReads of those per birth so a large mapping cannot hold the
// birth for long. An object the EDS marks wo, or one without an EDS
// entry, is not read; a value heard meanwhile is not read again.
// `from` counts over both passes: n + k is the second pass's k.
void SparkplugOutput::read_next(Device& d, std::uint64_t generation, std::size_t from) {
  const auto& sources = d.model->sources();
  const auto& metrics = d.model->metrics();
  const std::size_t n = sources.size();
  const auto wanted = [&](std::size_t at) {
    if (at < n) return sources[at].listed;
    const std::size_t k = at - n;
    return !sources[k].listed && sources[k].kind == sparkplug::DeviceModel::Kind::Object && sources[k].readable &&
           std::holds_alternative<std::monostate>(metrics[k].value) && d.unheard_reads < kMaxUnheardReads;
  };
  std::size_t at = from;
  while (at < 2 * n && !wanted(at)) ++at;
  if (at == 2 * n) return finish_birth(d);
  const std::size_t i = at < n ? at : at - n;
  const bool listed = at < n;
  if (!listed) ++d.unheard_reads;
  const sparkplug::ObjectRef ref = *d.model->metrics()[i].object;
  core::Request r;
  r.caller = sparkplug_caller("sparkplug:birth", Role::Viewer);
  r.network = d.network;
  r.command = core::SdoRead{d.node, ref.index, ref.sub_index, std::nullopt};
  std::weak_ptr<bool> alive = alive_;
  Device* dp = &d;
  execute_(std::move(r), [this, alive, dp, generation, ref, at, listed](core::Result res) {
    if (alive.expired() || dp->generation != generation) return;  // gone, lost or born anew meanwhile
    if (const auto* v = std::get_if<core::SdoValue>(&res)) {
      (void)dp->model->on_value(ref, v->value, sources_.now_ms());
    } else if (const auto* p = std::get_if<core::Problem>(&res)) {
      const std::string what = where(dp->network, dp->node) + ": reading " +
                               core::object_label(ref.index, ref.sub_index) + " for the DBIRTH failed (" +
                               std::to_string(p->status) + " " + p->detail + "): it is null";
      if (listed) {
        log_.warn(what);
      } else {
        log_.debug(what);
        // No answer, or no bus: the other unheard objects would wait as
        // long each; they stay null until their PDO is heard.
        if (p->status == 504 || p->status == 503) dp->unheard_reads = kMaxUnheardReads;
      }
    }
    read_next(*dp, generation, at + 1);
  });
}

void SparkplugOutput::finish_birth(Device& d) {
  d.phase = Device::Phase::Online;
  std::vector<sparkplug::Outgoing> out;
  if (!edge_.device_online(out, d.id, d.model->metrics(), sources_.now_ms()))
    log_.warn(where(d.network, d.node) + ": device id \"" + d.id + "\" is not a valid topic level: no DBIRTH");
  send_(out);
}

void SparkplugOutput::data(Device& d, const std::vector<Update>& updates, std::uint64_t now) {
  // While a birth is being prepared the model keeps the values; the
  // DBIRTH carries them (the session's metric positions are the old ones).
  if (updates.empty() || d.phase != Device::Phase::Online) return;
  std::vector<sparkplug::Outgoing> out;
  edge_.device_data(out, d.id, updates, now);
  send_(out);
}

void SparkplugOutput::on_state(Device& d, const canopen::NodeStateEvent& s, std::uint64_t ts) {
  using Cause = canopen::NodeStateEvent::Cause;
  if (s.cause == Cause::Lost) {
    ++d.generation;
    d.state.reset();
    const bool was = d.phase != Device::Phase::Offline;
    d.phase = Device::Phase::Offline;
    if (!was) return;
    std::vector<sparkplug::Outgoing> out;
    edge_.device_lost(out, d.id, ts);
    send_(out);
    return;
  }
  if (s.state) d.state = s.state;
  // A boot-up is a new life (its PDOs and listed values may differ); a
  // node first heard, or back, is born.
  if (s.cause == Cause::BootUp || s.cause == Cause::Recovered || d.phase == Device::Phase::Offline) {
    begin_birth(d);
    return;
  }
  if (s.state) data(d, d.model->on_state(*s.state, ts), ts);
}

void SparkplugOutput::on_event(std::uint32_t network, const canopen::Event& ev) {
  const std::uint64_t ts = stamp(ev);
  if (const auto* s = std::get_if<canopen::NodeStateEvent>(&ev.body)) {
    if (s->node < 1 || s->node > 127) return;
    on_state(device(network, s->node), *s, ts);
  } else if (const auto* p = std::get_if<canopen::PdoEvent>(&ev.body)) {
    Device* d = p->node != 0 && p->number != 0 && !p->error && !p->mpdo ? find(network, p->node) : nullptr;
    if (d != nullptr && d->model) data(*d, d->model->on_values(p->values, ts), ts);
  } else if (const auto* e = std::get_if<canopen::EmcyEvent>(&ev.body)) {
    Device* d = find(network, e->node);
    if (d != nullptr && d->model) data(*d, d->model->on_emcy(*e, ts), ts);
  } else if (const auto* b = std::get_if<canopen::can::BusEvent>(&ev.body)) {
    for (std::size_t i = 0; i < networks_.size(); ++i) {
      if (networks_[i].number != network) continue;
      std::string state(canopen::can::to_string(b->state));
      if (state == bus_state_[i]) return;
      bus_state_[i] = state;
      const Update u{i, std::move(state), ts};
      std::vector<sparkplug::Outgoing> out;
      edge_.node_data(out, std::span<const Update>(&u, 1), ts);
      send_(out);
    }
  } else if (const auto* c = std::get_if<canopen::BootConfigEvent>(&ev.body)) {
    // The configuration may have read the PDOs from the device: a new
    // metric set is a new birth.
    Device* d = c->step == canopen::BootConfigEvent::Step::Done ? find(network, c->node) : nullptr;
    if (d == nullptr || d->phase == Device::Phase::Offline || !d->model) return;
    const auto fresh = build(*d);
    bool same = fresh.metrics().size() == d->model->metrics().size();
    for (std::size_t i = 0; same && i < fresh.metrics().size(); ++i)
      same = fresh.metrics()[i].name == d->model->metrics()[i].name &&
             fresh.metrics()[i].datatype == d->model->metrics()[i].datatype &&
             fresh.metrics()[i].object == d->model->metrics()[i].object;
    if (!same) begin_birth(*d);
  }
}

void SparkplugOutput::node_changed(std::uint32_t network, std::uint8_t node,
                                   const std::vector<SparkplugObject>& listed) {
  Device& d = device(network, node);
  d.listed = listed;
  if (d.phase == Device::Phase::Offline) return;  // born with its next boot-up or heartbeat
  begin_birth(d);  // a new generation: answers of a birth under way are dropped
}

void SparkplugOutput::on_command(const sparkplug::WriteCommand& cmd) {
  const std::string what = cmd.device.empty() ? std::string("NCMD") : "DCMD " + cmd.device;
  for (const auto& r : cmd.refused)
    log_.warn("sparkplug: " + what + ": metric \"" + printable(r) +
              "\" refused (unknown, or the value does not fit its type)");
  if (cmd.rebirth) {
    // Every DBIRTH of a rebirth reads its values again (contract "Sparkplug
    // B"; issue 27 item 9): the session sent the NBIRTH, the DBIRTHs follow
    // each device's reads.
    for (auto& d : devices_)
      if (d.phase != Device::Phase::Offline && (cmd.device.empty() || d.id == cmd.device)) begin_birth(d);
  }
  if (cmd.items.empty()) return;
  if (options_.commands_role == Role::None) {
    log_.info("sparkplug: " + what + ": ignored (sparkplug.commands-role is none)");
    return;
  }
  if (cmd.device.empty()) {
    log_.warn("sparkplug: NCMD: the edge node's metrics cannot be written (only Node Control/Rebirth)");
    return;
  }
  Device* d = find(cmd.device);
  if (d == nullptr || !d->model) {
    log_.warn("sparkplug: " + what + ": no such device");
    return;
  }
  auto plan = d->model->writes_for(cmd.items);
  for (const auto& reason : plan.refused) log_.warn("sparkplug: " + what + ": write refused: " + reason);
  for (auto& w : plan.writes) {
    std::string objects;
    for (const auto& o : w.objects)
      objects += (objects.empty() ? "\"" : ", \"") + d->model->metrics()[*d->model->find(o)].name + "\" (" +
                 core::object_label(o.index, o.sub_index) + ")";
    core::Request r;
    r.caller = sparkplug_caller("sparkplug:dcmd", options_.commands_role);
    r.network = d->network;
    r.command = std::move(w.command);
    std::weak_ptr<bool> alive = alive_;
    Device* dp = d;
    const sparkplug::ObjectRef ref = w.objects.front();
    execute_(std::move(r), [this, alive, dp, what, objects, ref](core::Result res) {
      if (alive.expired()) return;
      if (const auto* p = std::get_if<core::Problem>(&res)) {
        log_.warn("sparkplug: " + what + ": write of " + objects + " refused (" + std::to_string(p->status) + " " +
                  p->detail + ")");
        return;
      }
      on_written(*dp, ref, res);
    });
  }
}

void SparkplugOutput::on_written(Device& d, sparkplug::ObjectRef ref, const core::Result& result) {
  if (!d.model) return;
  const std::uint64_t now = sources_.now_ms();
  if (const auto* rpdo = std::get_if<core::RpdoSent>(&result)) {
    // Every value of the RPDO as sent: the written one and the others as last sent.
    const auto* table = sources_.pdo_table ? sources_.pdo_table(d.network) : nullptr;
    if (table == nullptr) return;
    auto cfg = table->resolve(d.node, {canopen::pdo::Direction::Receive, rpdo->number});
    if (!cfg || rpdo->raw.size() < cfg->byte_length()) return;
    auto values = canopen::pdo::unpack(*cfg, rpdo->raw);
    if (values) data(d, d.model->on_values(*values, now), now);
  } else if (const auto* sdo = std::get_if<core::SdoValue>(&result)) {
    data(d, d.model->on_value(ref, sdo->value, now), now);
  }
}

}  // namespace gateway
