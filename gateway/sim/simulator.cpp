#include "sim/simulator.hpp"

#include <boost/asio/post.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "canopen/pdo/mapping.hpp"
#include "canopen/sdo/abort.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "sim/device_objects.hpp"

namespace canopen::sim {

namespace {

constexpr std::uint16_t kProfileIo = 401;     // CiA 401 generic I/O module
constexpr std::uint16_t kProfileDrive = 402;  // CiA 402 drive

struct EmcyPlan {
  std::uint16_t code;
  std::uint8_t bits;
};
// What the periodic EMCY cycles through: plausible device errors.
constexpr std::array<EmcyPlan, 3> kPeriodicEmcy{{{0x3210, emcy::error_register::kVoltage},      // DC link over-voltage
                                                 {0x4210, emcy::error_register::kTemperature},  // excess temperature device
                                                 {0x2310, emcy::error_register::kCurrent}}};    // continuous over current

std::uint8_t register_bits_for(std::uint16_t code) {
  switch (code >> 12) {
    case 0x2: return emcy::error_register::kCurrent;
    case 0x3: return emcy::error_register::kVoltage;
    case 0x4: return emcy::error_register::kTemperature;
    case 0x8: return emcy::error_register::kCommunication;
    case 0xF: return emcy::error_register::kDeviceProfile;
    default: return 0;
  }
}

std::string hex4(std::uint16_t v) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  std::string s(4, '0');
  for (int i = 3; i >= 0; --i, v = static_cast<std::uint16_t>(v >> 4)) s[static_cast<std::size_t>(i)] = kDigits[v & 0xF];
  return s;
}

std::optional<double> as_double(const std::optional<Value>& v) {
  if (!v) return std::nullopt;
  if (const auto* u = std::get_if<std::uint64_t>(&v->data)) return static_cast<double>(*u);
  if (const auto* s = std::get_if<std::int64_t>(&v->data)) return static_cast<double>(*s);
  if (const auto* f = std::get_if<float>(&v->data)) return static_cast<double>(*f);
  if (const auto* d = std::get_if<double>(&v->data)) return *d;
  return std::nullopt;
}

// x as a value of the entry's numeric type, inside its limits and its type's range.
std::optional<Value> numeric(const od::SubEntry& e, double x) {
  if (auto lo = as_double(e.low)) x = std::max(x, *lo);
  if (auto hi = as_double(e.high)) x = std::min(x, *hi);
  const DataType t = e.type;
  if (is_unsigned_integer(t)) {
    x = std::clamp(std::round(x), 0.0, static_cast<double>(unsigned_max(t)));
    return Value::of_unsigned(t, static_cast<std::uint64_t>(x));
  }
  if (is_signed_integer(t)) {
    x = std::clamp(std::round(x), static_cast<double>(signed_min(t)), static_cast<double>(signed_max(t)));
    return Value::of_signed(t, static_cast<std::int64_t>(x));
  }
  if (t == DataType::Real32) return Value::of_real32(static_cast<float>(x));
  if (t == DataType::Real64) return Value::of_real64(x);
  if (t == DataType::Boolean) return Value::of_bool(x >= 0.5);
  return std::nullopt;
}

// The next plausible value of a TPDO-mapped object at `t` seconds after
// power-on; nullopt leaves the object alone.
std::optional<Value> generate(const od::ObjectDictionary& od, std::uint16_t profile, std::uint16_t index,
                              std::uint8_t sub, double t, std::uint64_t tick) {
  const od::SubEntry* e = od.find(index, sub);
  if (e == nullptr) return std::nullopt;
  const double w = 2.0 * std::numbers::pi;
  if (profile == kProfileDrive) {
    switch (index) {
      case 0x6041:  // Statusword: operation enabled, "target reached" toggling
        return numeric(*e, (tick / 20) % 2 == 0 ? 0x0637 : 0x0237);
      case 0x6064:  // Position actual value: integral of the velocity below
        return numeric(*e, 2000.0 * 10.0 / w * (1.0 - std::cos(w * t / 10.0)));
      case 0x606C:  // Velocity actual value: a 10 s speed cycle
        return numeric(*e, 2000.0 * std::sin(w * t / 10.0));
      case 0x6077:  // Torque actual value
        return numeric(*e, 300.0 * std::sin(w * t / 3.0));
      case 0x6061:  // Modes of operation display mirrors 6060h
        if (auto m = od.get(0x6060, 0); m && m->type == e->type) return *m;
        return std::nullopt;
      default: break;
    }
  }
  if (profile == kProfileIo) {
    if (index >= 0x6000 && index <= 0x6003)  // digital inputs: a walking bit per group
      return numeric(*e, static_cast<double>(1U << ((tick / 5 + sub) % 8)));
    if (index == 0x6401 || index == 0x6402)  // analog inputs: slow sine per channel
      return numeric(*e, 10000.0 * std::sin(w * t / 20.0 + sub));
  }
  if (e->type == DataType::Boolean) return Value::of_bool((tick / 10) % 2 == 1);
  if (is_unsigned_integer(e->type)) {
    const double lo = as_double(e->low).value_or(0.0);
    const double hi = std::min(as_double(e->high).value_or(65535.0), static_cast<double>(unsigned_max(e->type)));
    const double span = std::max(hi - lo + 1.0, 1.0);
    return numeric(*e, lo + std::fmod(static_cast<double>(tick), span));
  }
  if (is_signed_integer(e->type) || is_real(e->type)) return numeric(*e, 1000.0 * std::sin(w * t / 5.0 + sub));
  return std::nullopt;
}

// The index range of a 1010h/1011h sub-index (CiA 301 7.5.2.13).
std::optional<std::pair<std::uint16_t, std::uint16_t>> parameter_group(std::uint8_t group) {
  switch (group) {
    case 1: return std::pair<std::uint16_t, std::uint16_t>{0x1000, 0x9FFF};
    case 2: return std::pair<std::uint16_t, std::uint16_t>{0x1000, 0x1FFF};
    case 3: return std::pair<std::uint16_t, std::uint16_t>{0x2000, 0x9FFF};
    case 4: return std::pair<std::uint16_t, std::uint16_t>{0x2000, 0x5FFF};  // as canopen::Device
    default: return std::nullopt;
  }
}

// Program download objects (CiA 302-3) hold the program, not settings: resets keep them.
bool is_program_object(std::uint16_t index) { return index >= 0x1F50 && index <= 0x1F5F; }

// Copies the writable entries of `from` in the group's range into `to`
// (the values a reset brings back).
void copy_parameters(const od::ObjectDictionary& from, od::ObjectDictionary& to, std::uint8_t group) {
  const auto range = parameter_group(group);
  if (!range) return;
  for (const auto& [index, obj] : from.objects()) {
    if (index < range->first || index > range->second || is_program_object(index) || index == 0x1003 ||
        index == 0x1010 || index == 0x1011)
      continue;
    for (const auto& [sub, entry] : obj.subs)
      if (od::writable(entry.access))
        if (od::SubEntry* e = to.find(index, sub)) e->value = entry.value;
  }
}

void ensure_u32(od::ObjectDictionary& od, std::uint16_t index, const char* name, std::uint32_t value) {
  if (od.find(index, 0) == nullptr)
    od.insert(od::make_var(index, name, DataType::Unsigned32, od::Access::ReadWrite,
                           Value::of_unsigned(DataType::Unsigned32, value)));
}

}  // namespace

struct Simulator::Node {
  std::uint8_t id = lss::kUnconfiguredNodeId;  // the active node-ID; FFh while unconfigured
  std::uint16_t profile = 0;     // 1000h bits 0-15
  od::ObjectDictionary initial;  // the EDS values, restored by resets
  od::ObjectDictionary factory;  // the EDS values, which 1011h "load" brings back
  od::ObjectDictionary od;
  std::unique_ptr<Device> device;  // none while unconfigured
  bool sync_producer = false;
  std::uint16_t emcy_active = 0;
  std::size_t emcy_next = 0;
  Describe describe;              // reloads the description for a new node-ID; may be empty
  lss::Identity identity;         // the LSS address (1018h, serial made unique)
  std::unique_ptr<lss::LssSlave> lss;
  bool silenced = false;          // the device is being replaced: what it still sends is dropped
};

namespace {

// The LSS address of a description: 1018h sub 1..4.
lss::Identity identity_of(const od::ObjectDictionary& od) {
  auto part = [&](std::uint8_t sub) { return static_cast<std::uint32_t>(od.get_unsigned(0x1018, sub).value_or(0)); };
  return {part(1), part(2), part(3), part(4)};
}

}  // namespace

Simulator::Simulator(boost::asio::io_context& io, can::Channel& channel, SimulatorOptions options,
                     LineHandler on_line)
    : io_(io),
      channel_(channel),
      opt_(options),
      on_line_(std::move(on_line)),
      driver_(io, channel),
      value_timer_(io),
      emcy_timer_(io) {}

Simulator::~Simulator() { stop(); }

void Simulator::say(const std::string& line) {
  if (on_line_) on_line_(line);
}

void Simulator::add_node(std::uint8_t node, const std::filesystem::path& eds) {
  if (node < 1 || node > 127) throw std::invalid_argument("node-ID must be 1..127");
  add_node(node, Describe([eds](std::uint8_t id) { return eds::load_device_description(eds, id); }));
}

void Simulator::add_node(std::uint8_t node, eds::DeviceDescription description) {
  if (node < 1 || node > 127) throw std::invalid_argument("node-ID must be 1..127");
  if (nodes_.contains(node)) throw std::invalid_argument("node " + std::to_string(node) + " given twice");
  auto n = make_node(node, std::move(description), nullptr);
  nodes_.emplace(node, std::move(n));
}

void Simulator::add_node(std::uint8_t node, Describe describe) {
  if (node < 1 || node > 127) throw std::invalid_argument("node-ID must be 1..127");
  if (nodes_.contains(node)) throw std::invalid_argument("node " + std::to_string(node) + " given twice");
  auto n = make_node(node, describe(node), describe);
  nodes_.emplace(node, std::move(n));
}

void Simulator::add_unconfigured_node(const std::filesystem::path& eds) {
  add_unconfigured_node(Describe([eds](std::uint8_t id) { return eds::load_device_description(eds, id); }));
}

void Simulator::add_unconfigured_node(Describe describe) {
  // Any node-ID resolves the description: only its identity is needed now.
  const eds::DeviceDescription probe = describe(1);
  auto n = std::make_unique<Node>();
  n->describe = std::move(describe);
  n->identity = identity_of(probe.od);
  if (n->identity.serial == 0) n->identity.serial = 0x55000000U + ++unconfigured_added_;
  make_lss(*n, lss::kUnconfiguredNodeId);
  waiting_.push_back(std::move(n));
}

std::unique_ptr<Simulator::Node> Simulator::make_node(std::uint8_t node, eds::DeviceDescription description,
                                                      Describe describe) {
  auto n = std::make_unique<Node>();
  n->describe = std::move(describe);
  n->identity = identity_of(description.od);
  if (n->identity.serial == 0) n->identity.serial = 0x53000000U + node;
  n->sync_producer = opt_.sync_period.count() > 0 && nodes_.empty();
  build_device(*n, node, std::move(description));
  make_lss(*n, node);
  return n;
}

void Simulator::build_device(Node& n, std::uint8_t node, eds::DeviceDescription description) {
  Node* np = &n;
  n.device.reset();  // before its dictionary is replaced
  n.id = node;
  n.silenced = false;
  n.emcy_active = 0;
  n.od = std::move(description.od);
  // The LSS address is the device's: 1018h sub 4 says the same.
  if (n.od.find(0x1018, 4) != nullptr)
    (void)n.od.set(0x1018, 4, Value::of_unsigned(DataType::Unsigned32, n.identity.serial));
  n.profile = static_cast<std::uint16_t>(n.od.get_unsigned(0x1000, 0).value_or(0) & 0xFFFF);
  // Objects the simulation writes must exist before the Device observes the dictionary.
  if (n.od.find(0x1017, 0) == nullptr)
    n.od.insert(od::make_var(0x1017, "Producer heartbeat time", DataType::Unsigned16, od::Access::ReadWrite,
                             Value::of_unsigned(DataType::Unsigned16, 0)));
  if (n.sync_producer) {
    ensure_u32(n.od, 0x1005, "COB-ID SYNC message", 0x80);
    ensure_u32(n.od, 0x1006, "Communication cycle period", 0);
  }
  n.initial = n.od;
  n.factory = n.od;
  // 1010h "save" / 1011h "load": the device's power-on values and what the
  // simulation's resets restore change together.
  od::install_store_restore(
      n.od,
      [np](std::uint8_t group) -> std::error_code {
        if (!np->device) return make_error_code(SdoAbort::CannotStoreDeviceState);
        if (auto ec = np->device->store_parameters(group)) return ec;
        copy_parameters(np->od, np->initial, group);
        return {};
      },
      [np](std::uint8_t group) -> std::error_code {
        if (!np->device) return make_error_code(SdoAbort::CannotStoreDeviceState);
        if (auto ec = np->device->restore_default_parameters(group)) return ec;
        copy_parameters(np->factory, np->initial, group);
        return {};
      });
  (void)install_program_objects(n.od);

  DeviceConfig cfg;
  cfg.node_id = node;
  DeviceCallbacks cb;
  cb.on_state_change = [this, np](NmtState now, NmtState before) {
    if (before == NmtState::Initialising) {
      say("node " + std::to_string(np->id) + " boot-up");
      if (opt_.auto_start) {
        // Not from inside the Device's callback: after it returns.
        boost::asio::post(io_, [this, np, alive = std::weak_ptr<bool>(alive_)] {
          if (alive.expired() || !running_ || !np->device) return;
          np->device->command(NmtCommand::Start, SteadyClock::now());
        });
      }
    }
    say("node " + std::to_string(np->id) + " state " + std::string(to_string(now)));
  };
  cb.on_reset_application = [this, np] { restore(*np, 0x2000, 0xFFFF); };
  cb.on_reset_communication = [this, np] {
    restore(*np, 0x1000, 0x1FFF);
    (void)np->od.set(0x1017, 0,
                     Value::of_unsigned(DataType::Unsigned16,
                                        static_cast<std::uint64_t>(std::min<std::int64_t>(opt_.heartbeat.count(), 65535))));
    if (np->sync_producer) {
      const auto us = static_cast<std::uint64_t>(
          std::chrono::duration_cast<std::chrono::microseconds>(opt_.sync_period).count());
      (void)np->od.set(0x1006, 0, Value::of_unsigned(DataType::Unsigned32, us));
      const auto cob = np->od.get_unsigned(0x1005, 0).value_or(0x80);
      (void)np->od.set(0x1005, 0, Value::of_unsigned(DataType::Unsigned32, cob | kCobIdBit30));
    }
    np->emcy_active = 0;
    // CiA 305: a node-ID configured by LSS becomes active now. The device
    // boots again at it (or goes silent for FFh); this one says no more.
    if (np->lss) {
      const std::uint8_t active = np->lss->reset_communication();
      if (active != np->id) {
        np->silenced = true;
        boost::asio::post(io_, [this, np, active, alive = std::weak_ptr<bool>(alive_)] {
          if (!alive.expired()) rehome(np, active);
        });
      }
    }
  };
  cb.on_rpdo = [this, np](std::uint16_t number, std::span<const MappedValue> values) {
    std::string line = "node " + std::to_string(np->id) + " rpdo " + std::to_string(number);
    for (const auto& v : values) line += " " + v.name + "=" + format_value(v.value);
    say(line);
  };
  n.device = std::make_unique<Device>(n.od, cfg,
                                      [this, np](const can::Frame& f) {
                                        if (np->silenced) return;
                                        channel_.send(f);
                                        loopback(np, f);
                                      },
                                      std::move(cb));
}

void Simulator::make_lss(Node& n, std::uint8_t node_id) {
  Node* np = &n;
  lss::SlaveCallbacks cb;
  // The simulation keeps nothing across runs: storing always succeeds.
  cb.store = [](std::uint8_t, std::optional<std::uint8_t>) { return std::uint8_t{0}; };
  cb.activate_bit_timing = [this, np](std::uint16_t delay) {
    say("lss " + lss::to_string(np->identity) + " activate bit timing (delay " + std::to_string(delay) +
        " ms): ignored, the simulated bus has no bit rate");
  };
  cb.on_activate = [this, np](std::uint8_t id) {
    boost::asio::post(io_, [this, np, id, alive = std::weak_ptr<bool>(alive_)] {
      if (!alive.expired()) rehome(np, id);
    });
  };
  n.lss = std::make_unique<lss::LssSlave>(n.identity, node_id, [this](const can::Frame& f) { channel_.send(f); },
                                          std::move(cb));
}

void Simulator::rehome(Node* n, std::uint8_t new_id) {
  if (!running_) return;
  // Take the node out of where it is now.
  std::unique_ptr<Node> owned;
  if (n->id == lss::kUnconfiguredNodeId) {
    auto it = std::find_if(waiting_.begin(), waiting_.end(), [n](const auto& w) { return w.get() == n; });
    if (it == waiting_.end()) return;
    owned = std::move(*it);
    waiting_.erase(it);
  } else {
    auto it = nodes_.find(n->id);
    if (it == nodes_.end() || it->second.get() != n) return;
    owned = std::move(it->second);
    nodes_.erase(it);
    driver_.remove(n->device.get());
    std::erase_if(local_, [n](const auto& e) { return e.first == n; });
    n->device.reset();
  }
  const std::string who = "lss " + lss::to_string(n->identity);
  auto park = [&](const std::string& why) {
    say(who + ": " + why);
    n->id = lss::kUnconfiguredNodeId;
    make_lss(*n, lss::kUnconfiguredNodeId);  // a fresh slave: unconfigured, waiting
    waiting_.push_back(std::move(owned));
  };
  if (new_id == lss::kUnconfiguredNodeId) return park("unconfigured, silent until LSS gives a node-ID");
  if (nodes_.contains(new_id)) return park("node-ID " + std::to_string(new_id) + " is used by another simulated device");
  try {
    eds::DeviceDescription d;
    if (n->describe) {
      d = n->describe(new_id);
    } else {
      d.od = n->initial;  // no file to reload: the dictionary as it was
    }
    build_device(*n, new_id, std::move(d));
  } catch (const std::exception& e) {
    return park(std::string("cannot load its description for node-ID ") + std::to_string(new_id) + ": " + e.what());
  }
  say(who + ": node-ID " + std::to_string(new_id));
  Node& placed = *owned;
  nodes_.emplace(new_id, std::move(owned));
  driver_.add(*placed.device);
  placed.device->start(SteadyClock::now());
}

void Simulator::LssPort::on_frame(const can::Frame& f, TimePoint) {
  if (!lss::is_master_frame(f)) return;
  for (auto& [id, n] : sim->nodes_) n->lss->on_frame(f);
  for (auto& n : sim->waiting_) n->lss->on_frame(f);
}

lss::LssSlave* Simulator::lss(std::uint8_t node) {
  auto it = nodes_.find(node);
  return it == nodes_.end() ? nullptr : it->second->lss.get();
}

void Simulator::restore(Node& n, std::uint16_t first, std::uint16_t last) {
  for (const auto& [index, obj] : n.initial.objects()) {
    if (index < first || index > last || is_program_object(index)) continue;
    for (const auto& [sub, entry] : obj.subs) (void)n.od.set(index, sub, entry.value);
  }
}

void Simulator::start() {
  if (running_) return;
  running_ = true;
  started_ = SteadyClock::now();
  driver_.add(lss_port_);
  for (auto& [id, n] : nodes_) driver_.add(*n->device);
  for (auto& [id, n] : nodes_) n->device->start(SteadyClock::now());
  arm_values();
  arm_emcy();
}

void Simulator::stop() {
  if (!running_) return;
  running_ = false;
  value_timer_.cancel();
  emcy_timer_.cancel();
  driver_.remove(&lss_port_);
  for (auto& [id, n] : nodes_) driver_.remove(n->device.get());
  local_.clear();
}

Device* Simulator::device(std::uint8_t node) {
  auto it = nodes_.find(node);
  return it == nodes_.end() ? nullptr : it->second->device.get();
}

bool Simulator::store(std::uint8_t node) {
  auto it = nodes_.find(node);
  if (it == nodes_.end()) return false;
  Node& n = *it->second;
  // Values only: `initial` keeps no hooks or observers of the live dictionary.
  for (const auto& [index, obj] : n.od.objects())
    for (const auto& [sub, entry] : obj.subs)
      if (od::SubEntry* e = n.initial.find(index, sub)) e->value = entry.value;
  // The device's own power-on values too (before its first start() there
  // are none yet: it takes the current values then).
  (void)n.device->store_parameters(1);
  return true;
}

bool Simulator::raise_emcy(std::uint8_t node, std::uint16_t code) {
  Device* d = device(node);
  if (d == nullptr || !d->raise_emcy(code, register_bits_for(code), SteadyClock::now())) return false;
  say("node " + std::to_string(node) + " emcy " + hex4(code));
  return true;
}

void Simulator::arm_values() {
  if (opt_.tpdo_period.count() <= 0) return;
  // Drift-free: the next tick is one period after the previous one's due
  // time, so a busy loop catches up and the rate holds on average.
  const auto now = std::chrono::steady_clock::now();
  if (value_due_ == std::chrono::steady_clock::time_point{} || value_due_ + opt_.tpdo_period * 50 < now)
    value_due_ = now;  // first tick, or hopelessly behind (suspended): restart from now
  value_due_ += opt_.tpdo_period;
  value_timer_.expires_at(value_due_);
  value_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || !running_) return;
    tick_values();
    arm_values();
  });
}

void Simulator::arm_emcy() {
  if (opt_.emcy_period.count() <= 0) return;
  emcy_timer_.expires_after(opt_.emcy_period);
  emcy_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || !running_) return;
    tick_emcy();
    arm_emcy();
  });
}

void Simulator::tick_values() {
  ++ticks_;
  const TimePoint now = SteadyClock::now();
  const double t = std::chrono::duration<double>(now - started_).count();
  for (auto& [id, n] : nodes_) {
    if (n->device->state() != NmtState::Operational) continue;
    for (const auto number : n->device->tpdo_numbers()) {
      auto cfg = pdo::read_pdo(n->od, pdo::Direction::Transmit, number);
      if (!cfg) continue;
      for (const auto& e : cfg->entries) {
        if (e.dummy) continue;
        auto v = generate(n->od, n->profile, e.index, e.sub, t, ticks_);
        if (!v) continue;
        if (auto cur = n->od.get(e.index, e.sub); cur && *cur == *v) continue;
        (void)n->device->set(e.index, e.sub, std::move(*v), now);
      }
    }
  }
}

void Simulator::tick_emcy() {
  const TimePoint now = SteadyClock::now();
  for (auto& [id, n] : nodes_) {
    const NmtState s = n->device->state();
    if (s != NmtState::Operational && s != NmtState::PreOperational) continue;
    if (n->emcy_active != 0) {
      if (n->device->clear_emcy(n->emcy_active, now)) say("node " + std::to_string(id) + " emcy 0000");
      n->emcy_active = 0;
      continue;
    }
    const EmcyPlan& p = kPeriodicEmcy[n->emcy_next++ % kPeriodicEmcy.size()];
    if (n->device->raise_emcy(p.code, p.bits, now)) {
      n->emcy_active = p.code;
      say("node " + std::to_string(id) + " emcy " + hex4(p.code));
    }
  }
}

void Simulator::loopback(const Node* from, const can::Frame& f) {
  if (nodes_.size() < 2) return;
  local_.emplace_back(from, f);
  if (draining_posted_) return;
  draining_posted_ = true;
  boost::asio::post(io_, [this, alive = std::weak_ptr<bool>(alive_)] {
    if (alive.expired()) return;
    draining_posted_ = false;
    // Frames sent while draining are appended and handled in this loop.
    while (running_ && !local_.empty()) {
      auto [sender, frame] = local_.front();
      local_.pop_front();
      const TimePoint now = SteadyClock::now();
      for (auto& [id, n] : nodes_)
        if (n.get() != sender) n->device->on_frame(frame, now);
    }
  });
}

}  // namespace canopen::sim
