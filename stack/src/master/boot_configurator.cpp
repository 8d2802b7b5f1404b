#include "canopen/master/boot_configurator.hpp"

#include <string>
#include <utility>

#include "canopen/master/dcf_transfer.hpp"
#include "canopen/sdo/abort.hpp"
#include "runs.hpp"

namespace canopen::master {

namespace {

constexpr std::uint32_t kCobIdInvalid = 0x80000000U;

class BootErrorCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "canopen.boot"; }
  std::string message(int v) const override {
    switch (static_cast<BootError>(v)) {
      case BootError::DeviceTypeMismatch: return "device type (1000h) does not match";
      case BootError::VendorIdMismatch: return "vendor-ID (1018h sub 1) does not match";
      case BootError::ProductCodeMismatch: return "product code (1018h sub 2) does not match";
      case BootError::RevisionMismatch: return "revision number (1018h sub 3) does not match";
      case BootError::SerialNumberMismatch: return "serial number (1018h sub 4) does not match";
    }
    return "unknown boot-up error";
  }
};

using detail::hex32h;
using od::object_label;

std::uint32_t key(std::uint16_t index, std::uint8_t sub) { return static_cast<std::uint32_t>(index) << 8 | sub; }

Bytes u32_bytes(std::uint32_t v) {
  return encode(Value::of_unsigned(DataType::Unsigned32, v));
}

bool is_pdo_area(std::uint16_t index) { return index >= 0x1400 && index <= 0x1BFF; }
bool is_pdo_comm(std::uint16_t index) {
  return (index >= 0x1400 && index <= 0x15FF) || (index >= 0x1800 && index <= 0x19FF);
}

std::optional<std::uint32_t> dcf_u32(const eds::DeviceDescription& dcf, std::uint16_t index, std::uint8_t sub) {
  const auto v = dcf.od.get_unsigned(index, sub);
  if (!v || *v > 0xFFFFFFFFU) return std::nullopt;
  return static_cast<std::uint32_t>(*v);
}

// The PDO's writes in the remapping order of CiA 301 7.5.2.35 / 7.5.2.36.
void plan_pdo(const eds::DeviceDescription& dcf, const od::Object& comm, std::vector<ConfigWrite>& out) {
  const od::Object* map = dcf.od.find(static_cast<std::uint16_t>(comm.index + 0x200));
  const od::SubEntry* cob = nullptr;
  if (auto it = comm.subs.find(1); it != comm.subs.end() && od::writable(it->second.access)) cob = &it->second;
  if (cob != nullptr) out.push_back({comm.index, 1, {}, true});
  for (const auto& [sub, e] : comm.subs) {
    if (sub <= 1 || !od::writable(e.access)) continue;
    out.push_back({comm.index, sub, encode(e.value), false});
  }
  if (map != nullptr) {
    const auto count_it = map->subs.find(0);
    if (count_it != map->subs.end() && od::writable(count_it->second.access)) {
      const od::SubEntry& count = count_it->second;
      out.push_back({map->index, 0, encode(Value::of_unsigned(count.type, 0)), false});
      const auto n = dcf.od.get_unsigned(map->index, 0).value_or(0);
      for (const auto& [sub, e] : map->subs) {
        if (sub == 0 || sub > n || !od::writable(e.access)) continue;
        out.push_back({map->index, sub, encode(e.value), false});
      }
      out.push_back({map->index, 0, encode(count.value), false});
    }
  }
  if (cob != nullptr) out.push_back({comm.index, 1, encode(cob->value), false});
}

}  // namespace

const std::error_category& boot_error_category() {
  static const BootErrorCategory cat;
  return cat;
}

std::error_code make_error_code(BootError e) { return {static_cast<int>(e), boot_error_category()}; }

NodeBootConfig boot_config_from_dcf(const eds::DeviceDescription& dcf) {
  NodeBootConfig c;
  c.device_type = dcf_u32(dcf, 0x1000, 0);
  c.vendor_id = dcf_u32(dcf, 0x1018, 1);
  c.product_code = dcf_u32(dcf, 0x1018, 2);
  c.revision = dcf_u32(dcf, 0x1018, 3);
  const od::SubEntry* serial = dcf.od.find(0x1018, 4);
  if (serial != nullptr && serial->default_value && serial->value != *serial->default_value) {
    c.serial = dcf_u32(dcf, 0x1018, 4);
  }
  c.dcf = &dcf;
  return c;
}

std::vector<ConfigWrite> plan_configuration(const eds::DeviceDescription& dcf, PlanScope scope) {
  std::vector<ConfigWrite> out;
  if (scope == PlanScope::AllValues) {
    const auto has_value = [&](const od::Object* obj) {
      if (obj == nullptr) return false;
      for (const auto& [sub, e] : obj->subs)
        if (dcf.facts(obj->index, sub).parameter_value) return true;
      return false;
    };
    for (const auto& [index, obj] : dcf.od.objects()) {
      if (is_pdo_area(index)) {
        if (is_pdo_comm(index) &&
            (has_value(&obj) || has_value(dcf.od.find(static_cast<std::uint16_t>(index + 0x200)))))
          plan_pdo(dcf, obj, out);
        continue;
      }
      for (const auto& [sub, e] : obj.subs) {
        const eds::EntryFacts f = dcf.facts(index, sub);
        if (!f.parameter_value || (f.obj_flags & eds::kObjFlagRefuseWriteOnDownload) != 0) continue;
        if (is_configuration_entry(index, e)) out.push_back({index, sub, encode(e.value), false});
      }
    }
    return out;
  }
  for (const auto& [index, obj] : dcf.od.objects()) {
    if (is_pdo_area(index)) {
      if (is_pdo_comm(index)) plan_pdo(dcf, obj, out);
      continue;
    }
    // Writing these stores or restores parameters on the device.
    if (index == 0x1010 || index == 0x1011) continue;
    for (const auto& [sub, e] : obj.subs) {
      if (!od::writable(e.access)) continue;
      const bool differs = e.default_value && e.value != *e.default_value;
      if (index == 0x1017 || differs) out.push_back({index, sub, encode(e.value), false});
    }
  }
  return out;
}

BootConfigurator::BootConfigurator(sdo::SdoClient& client, NmtSender send_nmt, EventHandler on_event,
                                   TimeSource now)
    : client_(client), send_nmt_(std::move(send_nmt)), on_event_(std::move(on_event)), now_(std::move(now)) {}

BootConfigurator::~BootConfigurator() {
  // Cancelled requests call their handlers; make them no-ops first.
  std::vector<sdo::RequestId> pending;
  for (auto& [node, st] : nodes_) {
    if (st.run && st.run->request) pending.push_back(*st.run->request);
    st.run.reset();
  }
  for (const auto id : pending) client_.cancel(id, now_());
}

bool BootConfigurator::configure(std::uint8_t node, NodeBootConfig config) {
  if (node == 0 || node > 127) return false;
  nodes_[node].config = std::move(config);
  return true;
}

void BootConfigurator::remove(std::uint8_t node) {
  if (nodes_.count(node) == 0) return;
  stop(node, now_());
  nodes_.erase(node);
}

bool BootConfigurator::busy(std::uint8_t node) const {
  const auto it = nodes_.find(node);
  return it != nodes_.end() && it->second.run.has_value();
}

void BootConfigurator::stop(std::uint8_t node, TimePoint now) {
  auto it = nodes_.find(node);
  if (it == nodes_.end() || !it->second.run) return;
  const auto request = it->second.run->request;
  // Reset first: the cancel runs the handler, which must see a stale generation.
  it->second.run.reset();
  if (request) client_.cancel(*request, now);
}

void BootConfigurator::on_boot_up(std::uint8_t node, TimePoint now) {
  auto it = nodes_.find(node);
  if (it == nodes_.end()) return;
  begin(node, it->second.config, "reading 1000h and 1018h sub 1-4", {}, now);
}

bool BootConfigurator::on_found(std::uint8_t node, NmtState state, TimePoint now) {
  auto it = nodes_.find(node);
  if (it == nodes_.end() || it->second.run) return false;
  if (state == NmtState::PreOperational) {
    begin(node, it->second.config, "found in pre-operational without a boot-up: reading 1000h and 1018h sub 1-4", {},
          now);
    return true;
  }
  if (state != NmtState::Operational) return false;  // stopped: no SDO (7.3.2.2, table 41)
  // Running: its configuration was made by whoever started it. Check who it
  // is, but neither rewrite its parameters under a running machine nor reset it.
  NodeBootConfig check = it->second.config;
  check.dcf = nullptr;
  check.start = false;
  begin(node, std::move(check), "found operational: reading 1000h and 1018h sub 1-4 (no configuration, no restart)",
        "already operational: identity checked, not configured or restarted", now);
  return true;
}

void BootConfigurator::begin(std::uint8_t node, NodeBootConfig config, std::string identify_detail,
                             std::string done_detail, TimePoint now) {
  stop(node, now);
  auto it = nodes_.find(node);
  Run run;
  run.generation = ++generation_;
  run.config = std::move(config);
  run.done_detail = std::move(done_detail);
  const NodeBootConfig& c = run.config;
  run.ops.push_back({OpKind::Read, 0x1000, 0, {}, false, false});
  run.ops.push_back({OpKind::Read, 0x1018, 1, {}, false, false});
  run.ops.push_back({OpKind::Read, 0x1018, 2, {}, false, !c.product_code});
  run.ops.push_back({OpKind::Read, 0x1018, 3, {}, false, !c.revision});
  run.ops.push_back({OpKind::Read, 0x1018, 4, {}, false, !c.serial});
  const std::uint64_t gen = run.generation;
  it->second.run = std::move(run);
  emit(node, BootConfigEvent::Step::Identify, std::move(identify_detail));
  // The event handler may have restarted or removed the sequence.
  it = nodes_.find(node);
  if (it == nodes_.end() || !it->second.run || it->second.run->generation != gen) return;
  step(node, now);
}

void BootConfigurator::step(std::uint8_t node, TimePoint now) {
  // Loops instead of recursing when a phase ends without SDO traffic.
  for (;;) {
    auto it = nodes_.find(node);
    if (it == nodes_.end() || !it->second.run) return;
    Run& run = *it->second.run;
    if (run.next < run.ops.size()) {
      submit(node, run.ops[run.next], false, now);
      return;
    }
    if (run.phase == Phase::Identify) {
      if (!check_identity(node)) return;
      const eds::DeviceDescription* dcf = run.config.dcf;
      if (dcf != nullptr) {
        run.phase = Phase::Configure;
        run.ops.clear();
        run.next = 0;
        for (auto& w : plan_configuration(*dcf)) {
          run.ops.push_back({w.invalidate ? OpKind::Read : OpKind::Write, w.index, w.sub, std::move(w.data),
                             w.invalidate, false});
        }
        const std::uint64_t gen = run.generation;
        emit(node, BootConfigEvent::Step::Configure, std::to_string(run.ops.size()) + " SDO transfers");
        // The handler may have restarted or removed the sequence.
        it = nodes_.find(node);
        if (it == nodes_.end() || !it->second.run || it->second.run->generation != gen) return;
        continue;
      }
    }
    finish(node);
    return;
  }
}

void BootConfigurator::submit(std::uint8_t node, const Op& op, bool invalidate_write, TimePoint now) {
  const std::uint64_t gen = nodes_[node].run->generation;
  sdo::Request req;
  req.node = node;
  req.index = op.index;
  req.sub = op.sub;
  req.on_done = [this, node, gen, invalidate_write](sdo::TransferResult&& r) {
    on_done(node, gen, invalidate_write, std::move(r));
  };
  Result<sdo::RequestId> id = std::make_error_code(std::errc::invalid_argument);
  if (invalidate_write) {
    const std::uint32_t cob = nodes_[node].run->read[key(op.index, op.sub)];
    id = client_.download(std::move(req), u32_bytes(cob | kCobIdInvalid), now);
  } else if (op.kind == OpKind::Read) {
    req.expected_size = 4;
    id = client_.upload(std::move(req), now);
  } else {
    id = client_.download(std::move(req), op.data, now);
  }
  if (!id) {
    const char* what = op.kind == OpKind::Read && !invalidate_write ? "reading " : "writing ";
    fail(node, id.code(), what + object_label(op.index, op.sub) + ": " + id.error().detail);
    return;
  }
  nodes_[node].run->request = *id;
}

void BootConfigurator::on_done(std::uint8_t node, std::uint64_t generation, bool invalidate_write,
                               sdo::TransferResult&& r) {
  auto it = nodes_.find(node);
  if (it == nodes_.end() || !it->second.run || it->second.run->generation != generation) return;
  Run& run = *it->second.run;
  run.request.reset();
  const Op& op = run.ops[run.next];
  const TimePoint now = now_();
  if (!r.ok()) {
    if (op.optional && r.origin == sdo::Origin::Remote) {
      ++run.next;
      step(node, now);
      return;
    }
    std::string detail = (r.upload ? "reading " : "writing ") + object_label(op.index, op.sub) + ": " + r.error.message();
    if (!r.detail.empty()) detail += " (" + r.detail + ")";
    fail(node, r.error, std::move(detail));
    return;
  }
  if (op.kind == OpKind::Read && !invalidate_write) {
    auto v = decode(DataType::Unsigned32, r.data);
    if (!v) {
      fail(node, v.code(), "reading " + object_label(op.index, op.sub) + ": " + std::to_string(r.data.size()) +
                               " bytes, expected 4");
      return;
    }
    const auto value = static_cast<std::uint32_t>(std::get<std::uint64_t>(v->data));
    run.read[key(op.index, op.sub)] = value;
    if (op.invalidate && (value & kCobIdInvalid) == 0) {
      submit(node, op, true, now);
      return;
    }
  }
  ++run.next;
  step(node, now);
}

bool BootConfigurator::check_identity(std::uint8_t node) {
  NodeState& st = nodes_[node];
  const NodeBootConfig& c = st.run->config;
  const auto& read = st.run->read;
  struct Check {
    std::uint16_t index;
    std::uint8_t sub;
    const char* name;
    const std::optional<std::uint32_t>& expected;
    BootError error;
  };
  const Check checks[] = {
      {0x1000, 0, "device type", c.device_type, BootError::DeviceTypeMismatch},
      {0x1018, 1, "vendor-ID", c.vendor_id, BootError::VendorIdMismatch},
      {0x1018, 2, "product code", c.product_code, BootError::ProductCodeMismatch},
      {0x1018, 3, "revision number", c.revision, BootError::RevisionMismatch},
      {0x1018, 4, "serial number", c.serial, BootError::SerialNumberMismatch},
  };
  std::string summary;
  for (const Check& ch : checks) {
    const auto got = read.find(key(ch.index, ch.sub));
    if (got != read.end()) {
      if (!summary.empty()) summary += ", ";
      summary += std::string(ch.name) + " " + hex32h(got->second);
    }
    if (!ch.expected) continue;
    // A non-optional read always succeeded here, so `got` is set.
    if (got == read.end() || got->second != *ch.expected) {
      fail(node, ch.error,
           std::string(ch.name) + " (" + object_label(ch.index, ch.sub) + ") is " +
               (got == read.end() ? std::string("unknown") : hex32h(got->second)) + ", expected " +
               hex32h(*ch.expected));
      return false;
    }
  }
  const std::uint64_t gen = st.run->generation;
  auto value = [&](std::uint16_t index, std::uint8_t sub) {
    const auto it = read.find(key(index, sub));
    return it == read.end() ? 0U : it->second;
  };
  DeviceIdentity id;
  id.device_type = value(0x1000, 0);
  id.vendor_id = value(0x1018, 1);
  id.product_code = value(0x1018, 2);
  id.revision = value(0x1018, 3);
  id.serial = value(0x1018, 4);
  emit(node, BootConfigEvent::Step::CheckIdentity, summary, id);
  const auto it = nodes_.find(node);
  return it != nodes_.end() && it->second.run && it->second.run->generation == gen;
}

void BootConfigurator::finish(std::uint8_t node) {
  NodeState& st = nodes_[node];
  const std::uint64_t gen = st.run->generation;
  const bool start = st.run->config.start;
  std::string detail = std::move(st.run->done_detail);
  if (start) {
    send_nmt_(NmtCommand::Start, node);
    emit(node, BootConfigEvent::Step::Start);
  }
  const auto it = nodes_.find(node);
  if (it == nodes_.end() || !it->second.run || it->second.run->generation != gen) return;
  it->second.run.reset();
  emit(node, BootConfigEvent::Step::Done, std::move(detail));
}

void BootConfigurator::fail(std::uint8_t node, std::error_code ec, std::string detail) {
  nodes_[node].run.reset();
  BootConfigEvent e;
  e.node = node;
  e.step = BootConfigEvent::Step::Failed;
  e.error = ec;
  e.detail = std::move(detail);
  if (on_event_) on_event_(e);
}

void BootConfigurator::emit(std::uint8_t node, BootConfigEvent::Step s, std::string detail,
                            std::optional<DeviceIdentity> identity) {
  BootConfigEvent e;
  e.node = node;
  e.step = s;
  e.detail = std::move(detail);
  e.identity = identity;
  if (on_event_) on_event_(e);
}

}  // namespace canopen::master
