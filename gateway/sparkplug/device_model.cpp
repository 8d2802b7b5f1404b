#include "sparkplug/device_model.hpp"

#include <array>
#include <cmath>
#include <map>
#include <set>

#include "canopen/literal.hpp"
#include "core/format.hpp"
#include "log.hpp"

namespace gateway::sparkplug {

namespace {

using CoType = canopen::DataType;

constexpr std::int64_t kMsPerDay = 86'400'000;
constexpr std::int64_t kEpoch1984Ms = 441'763'200'000;  // 1984-01-01T00:00:00Z, TIME_OF_DAY's day 0

std::string fallback_id(std::uint32_t network, std::uint8_t node) {
  return "net" + std::to_string(network) + "-node" + std::to_string(node);
}

// Spec ch4: a topic level holds no '+', '/' or '#'; MQTT forbids NUL.
bool valid_level(std::string_view id) {
  return !id.empty() && id.find_first_of(std::string_view("+/#\0", 4)) == std::string_view::npos &&
         canopen::is_utf8(id);
}

std::string fold(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

// One level of a metric name from an EDS name: UTF-8, no control characters,
// '/' (a folder separator in Sparkplug names) as '-', trimmed.
std::string name_part(std::string_view raw, std::string fallback) {
  const std::string text = canopen::is_utf8(raw) ? std::string(raw) : canopen::latin1_to_utf8(raw);
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F) continue;
    out.push_back(c == '/' ? '-' : c);
  }
  const auto first = out.find_first_not_of(' ');
  if (first == std::string::npos) return fallback;
  out = out.substr(first, out.find_last_not_of(' ') - first + 1);
  return out;
}

bool is_variable(const canopen::od::Object* obj) {
  return obj == nullptr || obj->code == canopen::od::ObjectCode::Var || obj->code == canopen::od::ObjectCode::Domain;
}

// The name before de-duplication; `obj` nullptr: not in the EDS.
std::string base_name(const canopen::od::Object* obj, std::uint16_t index, std::uint8_t sub) {
  const std::string object = name_part(obj ? std::string_view(obj->name) : std::string_view(), core::index_text(index));
  // A variable has only sub 0; an unknown object at sub 0 is taken as one.
  if ((obj != nullptr && is_variable(obj)) || (obj == nullptr && sub == 0)) return object;
  const auto* e = obj ? [&]() -> const canopen::od::SubEntry* {
    auto it = obj->subs.find(sub);
    return it == obj->subs.end() ? nullptr : &it->second;
  }()
                      : nullptr;
  return object + "/" + name_part(e ? std::string_view(e->name) : std::string_view(), "sub " + std::to_string(sub));
}

std::string dedup_suffix(const canopen::od::Object* obj, std::uint16_t index, std::uint8_t sub) {
  if ((obj != nullptr && is_variable(obj)) || (obj == nullptr && sub == 0)) return " " + core::index_text(index);
  return " " + core::object_label(index, sub);
}

const std::array<std::string_view, 4> kFixedNames = {kNodeState, kEmcyErrorCode, kEmcyErrorRegister, kEmcyDescription};

std::uint64_t object_alias(std::uint32_t network, std::uint8_t node, std::uint16_t index, std::uint8_t sub) {
  return std::uint64_t{network} << 32 | std::uint64_t{node} << 24 | std::uint64_t{index} << 8 | sub;
}

std::string pdo_label(canopen::pdo::PdoKey key) {
  return (key.direction == canopen::pdo::Direction::Transmit ? "TPDO" : "RPDO") + std::to_string(key.number);
}

}  // namespace

DeviceIds device_ids(std::span<const NodeName> nodes) {
  DeviceIds out;
  std::map<std::string, int> uses;
  for (const auto& n : nodes)
    if (!n.name.empty()) ++uses[n.name];
  for (const auto& n : nodes) {
    const std::string fb = fallback_id(n.network, n.node);
    const std::string where = "network " + std::to_string(n.network) + " node " + std::to_string(n.node);
    if (n.name.empty()) {
      out.ids.push_back(fb);
    } else if (!valid_level(n.name)) {
      out.notes.push_back(where + ": name \"" + printable(n.name) +
                          "\" cannot be a Sparkplug device id (empty, '+', '/', '#' or not UTF-8): device id " + fb);
      out.ids.push_back(fb);
    } else if (uses[n.name] > 1) {
      out.notes.push_back(where + ": name \"" + n.name + "\" is shared by " + std::to_string(uses[n.name]) +
                          " nodes, and a device id must be unique: device id " + fb);
      out.ids.push_back(fb);
    } else {
      out.ids.push_back(n.name);
    }
  }
  // A name that equals another node's fallback id ("net1-node5") yields it.
  std::map<std::string, int> taken;
  for (const auto& id : out.ids) ++taken[id];
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const std::string fb = fallback_id(nodes[i].network, nodes[i].node);
    if (taken[out.ids[i]] > 1 && out.ids[i] != fb) {
      out.notes.push_back("network " + std::to_string(nodes[i].network) + " node " + std::to_string(nodes[i].node) +
                          ": name \"" + out.ids[i] + "\" is another node's device id: device id " + fb);
      --taken[out.ids[i]];
      out.ids[i] = fb;
    }
  }
  return out;
}

std::uint64_t bus_state_alias(std::uint32_t network) { return std::uint64_t{network} << 32; }
std::string bus_state_name(std::uint32_t network) { return "Network " + std::to_string(network) + "/Bus State"; }

Value to_sparkplug(const canopen::Value& v) {
  return std::visit(
      [&](const auto& x) -> Value {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, std::string>) {
          return canopen::is_utf8(x) ? x : canopen::latin1_to_utf8(x);
        } else if constexpr (std::is_same_v<T, std::u16string>) {
          return canopen::format_value(v);  // UNICODE_STRING as UTF-8
        } else if constexpr (std::is_same_v<T, canopen::TimeOfDay>) {
          if (v.type == CoType::TimeOfDay)
            return static_cast<std::uint64_t>(canopen::unix_ms_from_time_of_day(x));  // DateTime
          return std::int64_t{x.days} * kMsPerDay + x.ms;  // td: Int64 ms
        } else {
          return x;
        }
      },
      v.data);
}

std::variant<canopen::Value, std::string> typed_for(const Value& v, canopen::DataType type) {
  canopen::Literal j;
  if (std::holds_alternative<std::monostate>(v)) return std::string("a null value cannot be written");
  if (const auto* b = std::get_if<bool>(&v)) {
    j = *b;
  } else if (const auto* i = std::get_if<std::int64_t>(&v)) {
    j = *i;
  } else if (const auto* u = std::get_if<std::uint64_t>(&v)) {
    if (type == CoType::TimeOfDay) {
      // DateTime (UTC ms): TIME_OF_DAY holds 1984-01-01 .. day 65535; the
      // stack's converter clamps, so refuse here instead.
      if (*u < static_cast<std::uint64_t>(kEpoch1984Ms) ||
          (*u - static_cast<std::uint64_t>(kEpoch1984Ms)) / kMsPerDay > 0xFFFF)
        return std::string("DateTime " + std::to_string(*u) + " is outside what TIME_OF_DAY holds (1984-01-01 .. +65535 days)");
      const auto tod = canopen::time_of_day_from_unix_ms(static_cast<std::int64_t>(*u));
      j = canopen::format_value(canopen::Value{CoType::TimeOfDay, tod});  // RFC 3339, as the contract writes t
    } else {
      j = *u;
    }
  } else if (const auto* f = std::get_if<float>(&v)) {
    j = std::isfinite(*f) ? canopen::Literal(static_cast<double>(*f))
                          : canopen::Literal(std::isnan(*f) ? "nan" : (*f > 0 ? "inf" : "-inf"));
  } else if (const auto* d = std::get_if<double>(&v)) {
    j = std::isfinite(*d) ? canopen::Literal(*d)
                          : canopen::Literal(std::isnan(*d) ? "nan" : (*d > 0 ? "inf" : "-inf"));
  } else if (const auto* s = std::get_if<std::string>(&v)) {
    j = *s;
  } else if (const auto* bytes = std::get_if<canopen::Bytes>(&v)) {
    j = core::hex_bytes(*bytes);
  }
  // The contract's reader of values does the type and range checks once.
  auto typed = canopen::value_from_literal(type, j);
  if (!typed) return typed.error().detail;
  return std::move(*typed);
}

DeviceModel DeviceModel::build(const Input& in) {
  DeviceModel m;
  m.network_ = in.network;
  m.node_ = in.node;
  m.device_id_ = in.device_id;
  const canopen::od::ObjectDictionary* od = nullptr;
  if (in.description != nullptr)
    od = &in.description->od;
  else if (in.pdos != nullptr)
    od = in.pdos->description(in.node);

  // Names the EDS gives more than once (and the fixed ones) get a suffix.
  std::map<std::string, int> uses;
  if (od != nullptr)
    for (const auto& [index, obj] : od->objects()) {
      if (is_variable(&obj)) {
        ++uses[fold(base_name(&obj, index, 0))];
      } else {
        for (const auto& [sub, e] : obj.subs) ++uses[fold(base_name(&obj, index, sub))];
      }
    }
  for (auto f : kFixedNames) ++uses[fold(f)];

  const auto add_object = [&](std::uint16_t index, std::uint8_t sub, std::optional<canopen::pdo::PdoKey> pdo,
                              bool listed) {
    const ObjectRef ref{index, sub};
    if (auto at = m.find(ref)) {
      Source& s = m.sources_[*at];
      if (pdo && pdo->direction == canopen::pdo::Direction::Transmit && s.tpdo == 0) s.tpdo = pdo->number;
      if (pdo && pdo->direction == canopen::pdo::Direction::Receive && s.rpdo == 0) s.rpdo = pdo->number;
      s.listed = s.listed || listed;
      return;
    }
    const canopen::od::Object* obj = od ? od->find(index) : nullptr;
    const canopen::od::SubEntry* e = od ? od->find(index, sub) : nullptr;
    if (obj != nullptr && e == nullptr) obj = nullptr;  // the sub is missing: named as unknown
    Metric metric;
    metric.name = base_name(obj, index, sub);
    const auto n = uses.find(fold(metric.name));
    if ((n != uses.end() && n->second > (obj != nullptr ? 1 : 0))) {
      const std::string renamed = metric.name + dedup_suffix(obj, index, sub);
      m.notes_.push_back(core::object_label(index, sub) + ": name \"" + metric.name +
                         "\" is not unique in the EDS: metric \"" + renamed + "\"");
      metric.name = renamed;
    }
    Source s;
    s.type = e ? e->type : CoType::Domain;
    s.writable = e == nullptr || canopen::od::writable(e->access);
    s.readable = e != nullptr && canopen::od::readable(e->access);
    metric.datatype = datatype_of(s.type);
    metric.object = ref;
    if (in.aliases) metric.alias = object_alias(in.network, in.node, index, sub);
    if (pdo) (pdo->direction == canopen::pdo::Direction::Transmit ? s.tpdo : s.rpdo) = pdo->number;
    s.listed = listed;
    const std::size_t at = m.add(std::move(metric), s);
    if (e) {
      m.low_[at] = e->low;
      m.high_[at] = e->high;
    }
  };

  // 1. PDO-mapped objects, TPDOs first (the node's telemetry), then RPDOs.
  if (in.pdos != nullptr && in.pdos->has_node(in.node)) {
    for (const auto dir : {canopen::pdo::Direction::Transmit, canopen::pdo::Direction::Receive}) {
      for (const auto* p : in.pdos->pdos(in.node)) {
        if (p->key.direction != dir || !p->parameters.comm.cob_id.valid()) continue;  // not in use
        if (p->parameters.count == 0xFE || p->parameters.count == 0xFF) continue;     // MPDO: no fixed mapping
        const std::string label = pdo_label(p->key);
        auto cfg = in.pdos->resolve(in.node, p->key);
        if (cfg) {
          for (const auto& entry : cfg->entries)
            if (!entry.dummy) add_object(entry.index, entry.sub, p->key, false);
          continue;
        }
        // Not decoded or produced as it stands: its described objects are
        // still metrics, without the PDO (so writes go by SDO).
        m.notes_.push_back(label + " is not usable (" + cfg.error().detail +
                           "): its objects are metrics, written by SDO");
        for (unsigned k = 1; k <= p->parameters.count; ++k) {
          const auto raw = p->parameters.entries.find(static_cast<std::uint8_t>(k));
          if (raw == p->parameters.entries.end()) continue;
          const auto entry = canopen::pdo::MappingEntry::from_raw(raw->second);
          if (entry.index >= 0x0001 && entry.index <= 0x0007 && entry.sub == 0) continue;  // a dummy entry
          if (od == nullptr || od->find(entry.index, entry.sub) == nullptr) {
            m.notes_.push_back(label + " maps " + core::object_label(entry.index, entry.sub) +
                               ", which the EDS does not describe: left out");
            continue;
          }
          add_object(entry.index, entry.sub, std::nullopt, false);
        }
      }
    }
  }

  // 2. sparkplug-metrics.
  for (const auto& o : in.listed) {
    const canopen::od::Object* obj = od ? od->find(o.index) : nullptr;
    if (o.sub) {
      if (od == nullptr || od->find(o.index, *o.sub) == nullptr)
        m.notes_.push_back("sparkplug-metrics " + core::object_label(o.index, *o.sub) +
                           " is not in the EDS: read as bytes (DOMAIN)");
      add_object(o.index, *o.sub, std::nullopt, true);
    } else if (obj == nullptr) {
      m.notes_.push_back("sparkplug-metrics " + core::index_text(o.index) + " is not in the EDS: sub 0 read as bytes (DOMAIN)");
      add_object(o.index, 0, std::nullopt, true);
    } else if (is_variable(obj)) {
      add_object(o.index, 0, std::nullopt, true);
    } else {
      for (const auto& [sub, e] : obj->subs) add_object(o.index, sub, std::nullopt, true);
    }
  }

  // 3. The fixed metrics.
  const auto add_fixed = [&](std::string_view name, DataType t, Kind k, std::uint8_t alias_sub) {
    Metric metric;
    metric.name = std::string(name);
    metric.datatype = t;
    if (in.aliases) metric.alias = object_alias(in.network, in.node, 0, alias_sub);
    Source s;
    s.kind = k;
    m.add(std::move(metric), s);
  };
  add_fixed(kNodeState, DataType::String, Kind::NodeState, 1);
  add_fixed(kEmcyErrorCode, DataType::UInt16, Kind::EmcyErrorCode, 2);
  add_fixed(kEmcyErrorRegister, DataType::UInt8, Kind::EmcyErrorRegister, 3);
  add_fixed(kEmcyDescription, DataType::String, Kind::EmcyDescription, 4);

  // Last resort (an EDS name that equals another's suffixed name): " 2", " 3".
  std::set<std::string> seen;
  for (auto& metric : m.metrics_) {
    if (seen.insert(fold(metric.name)).second) continue;
    const std::string before = metric.name;
    for (int k = 2;; ++k) {
      const std::string candidate = before + " " + std::to_string(k);
      if (seen.insert(fold(candidate)).second) {
        metric.name = candidate;
        break;
      }
    }
    m.notes_.push_back("metric \"" + before + "\" exists twice: the second is \"" + metric.name + "\"");
  }
  return m;
}

std::size_t DeviceModel::add(Metric metric, Source s) {
  metrics_.push_back(std::move(metric));
  sources_.push_back(s);
  low_.emplace_back();
  high_.emplace_back();
  return metrics_.size() - 1;
}

std::optional<std::size_t> DeviceModel::find(ObjectRef object) const {
  for (std::size_t i = 0; i < metrics_.size(); ++i)
    if (metrics_[i].object == object) return i;
  return std::nullopt;
}

std::size_t DeviceModel::fixed(Kind kind) const {
  for (std::size_t i = 0; i < sources_.size(); ++i)
    if (sources_[i].kind == kind) return i;
  return metrics_.size();  // not reached: build() adds every fixed metric
}

void DeviceModel::carry_values(const DeviceModel& older) {
  for (std::size_t i = 0; i < metrics_.size(); ++i) {
    for (std::size_t k = 0; k < older.metrics_.size(); ++k) {
      const bool same = metrics_[i].object ? metrics_[i].object == older.metrics_[k].object
                                           : (!older.metrics_[k].object && older.metrics_[k].name == metrics_[i].name);
      if (!same) continue;
      // A value of another type (the EDS changed the object's type) is not carried.
      if (metrics_[i].datatype == older.metrics_[k].datatype) {
        metrics_[i].value = older.metrics_[k].value;
        metrics_[i].timestamp = older.metrics_[k].timestamp;
      }
      break;
    }
  }
}

std::vector<Update> DeviceModel::changed(std::size_t i, Value v, std::uint64_t timestamp) {
  if (i >= metrics_.size()) return {};
  if (metrics_[i].value == v) return {};
  metrics_[i].value = v;
  metrics_[i].timestamp = timestamp;
  return {Update{i, std::move(v), timestamp}};
}

std::vector<Update> DeviceModel::on_values(std::span<const canopen::MappedValue> values, std::uint64_t timestamp) {
  std::vector<Update> out;
  for (const auto& mv : values)
    if (auto at = find({mv.index, mv.sub}))
      for (auto& u : changed(*at, to_sparkplug(mv.value), timestamp)) out.push_back(std::move(u));
  return out;
}

std::vector<Update> DeviceModel::on_value(ObjectRef object, const canopen::Value& value, std::uint64_t timestamp) {
  const auto at = find(object);
  if (!at) return {};
  return changed(*at, to_sparkplug(value), timestamp);
}

std::vector<Update> DeviceModel::on_state(canopen::NmtState state, std::uint64_t timestamp) {
  return changed(fixed(Kind::NodeState), std::string(canopen::to_string(state)), timestamp);
}

std::vector<Update> DeviceModel::on_emcy(const canopen::EmcyEvent& emcy, std::uint64_t timestamp) {
  // An EMCY is an event: all three go out each time, even when repeated.
  std::vector<Update> out;
  const auto put = [&](Kind k, Value v) {
    const std::size_t i = fixed(k);
    metrics_[i].value = v;
    metrics_[i].timestamp = timestamp;
    out.push_back(Update{i, std::move(v), timestamp});
  };
  put(Kind::EmcyErrorCode, std::uint64_t{emcy.error_code});
  put(Kind::EmcyErrorRegister, std::uint64_t{emcy.error_register});
  put(Kind::EmcyDescription, canopen::is_utf8(emcy.description) ? emcy.description
                                                                : canopen::latin1_to_utf8(emcy.description));
  return out;
}

std::variant<core::Command, std::string> DeviceModel::command_for(const WriteCommand::Item& item) const {
  if (item.metric >= metrics_.size()) return std::string("no such metric");
  const Metric& metric = metrics_[item.metric];
  const Source& s = sources_[item.metric];
  if (s.kind != Kind::Object || !metric.object)
    return "\"" + metric.name + "\" is reported by the gateway and cannot be written";
  const ObjectRef ref = *metric.object;
  const std::string label = core::object_label(ref.index, ref.sub_index);
  auto t = typed_for(item.value, s.type);
  if (auto* err = std::get_if<std::string>(&t)) return "\"" + metric.name + "\" (" + label + "): " + *err;
  auto& typed = std::get<canopen::Value>(t);
  if (low_[item.metric] || high_[item.metric]) {
    std::string detail;
    if (canopen::check_limits(typed, low_[item.metric], high_[item.metric], &detail))
      return "\"" + metric.name + "\" (" + label + "): " + detail;
  }
  if (s.rpdo == 0 && !s.writable) return "\"" + metric.name + "\" (" + label + ") is read-only in the EDS";
  if (s.rpdo != 0) {
    core::RpdoWrite w{node_, s.rpdo, {}, {}, {}};
    w.values.push_back(core::RpdoItem{ref.index, ref.sub_index, std::move(typed), {}});
    return core::Command{std::move(w)};
  }
  return core::Command{core::SdoWrite{node_, ref.index, ref.sub_index, s.type, std::move(typed)}};
}

DeviceModel::Writes DeviceModel::writes_for(std::span<const WriteCommand::Item> items) const {
  Writes out;
  std::map<std::uint16_t, std::size_t> rpdos;  // number -> its write in out.writes
  for (const auto& item : items) {
    auto c = command_for(item);
    if (auto* reason = std::get_if<std::string>(&c)) {
      out.refused.push_back(std::move(*reason));
      continue;
    }
    const ObjectRef ref = *metrics_[item.metric].object;
    auto& command = std::get<core::Command>(c);
    auto* rpdo = std::get_if<core::RpdoWrite>(&command);
    if (rpdo == nullptr) {
      out.writes.push_back({std::move(command), {ref}});
      continue;
    }
    // Values for one RPDO go out as one frame; a repeated object: the last value.
    core::RpdoItem value = std::move(rpdo->values.at(0));
    auto [it, fresh] = rpdos.try_emplace(rpdo->number, out.writes.size());
    if (fresh) {
      rpdo->values.clear();
      out.writes.push_back({std::move(command), {}});
    }
    auto& write = out.writes[it->second];
    auto& values = std::get<core::RpdoWrite>(write.command).values;
    auto& objects = write.objects;
    bool replaced = false;
    for (std::size_t k = 0; k < objects.size(); ++k)
      if (objects[k] == ref) {
        values[k] = value;
        replaced = true;
      }
    if (!replaced) {
      values.push_back(std::move(value));
      objects.push_back(ref);
    }
  }
  return out;
}

}  // namespace gateway::sparkplug
