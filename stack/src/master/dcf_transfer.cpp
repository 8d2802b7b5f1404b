#include "canopen/master/dcf_transfer.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "canopen/sdo/abort.hpp"
#include "runs.hpp"

namespace canopen::master {

namespace {

std::string hex4(std::uint32_t v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04X", v & 0xFFFFU);
  return buf;
}

std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08X", v);
  return buf;
}

bool excluded_index(std::uint16_t index) {
  return index < 0x1000 || index > 0x9FFF || index == 0x1003 || index == 0x1010 || index == 0x1011 ||
         (index >= 0x1F50 && index <= 0x1F5F);
}

// A value as an EDS/DCF value: unsigned integers in hex where the EDS wrote
// the entry's default in hex; one line (a string cannot span lines).
std::string dcf_text(const Value& v, bool hex) {
  if (const auto* u = std::get_if<std::uint64_t>(&v.data); u != nullptr && hex) {
    char buf[24];
    std::snprintf(buf, sizeof buf, "0x%llX", static_cast<unsigned long long>(*u));
    return buf;
  }
  std::string s = format_value(v);
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

void line(std::string& out, std::string_view key, std::string_view value) {
  out.append(key).append("=").append(value).append("\n");
}

void write_entry(std::string& out, const eds::DeviceDescription& eds, std::uint16_t index, const od::SubEntry& e,
                 bool domain_object, const std::map<ObjectAddress, Value>& values) {
  const eds::EntryFacts f = eds.facts(index, e.sub);
  line(out, "ParameterName", e.name);
  line(out, "ObjectType", domain_object ? "0x2" : "0x7");
  line(out, "DataType", "0x" + hex4(static_cast<std::uint16_t>(e.type)));
  line(out, "AccessType", od::to_string(e.access));
  if (e.default_value && e.type != DataType::Domain) line(out, "DefaultValue", dcf_text(*e.default_value, f.hex_default));
  line(out, "PDOMapping", e.pdo_mappable ? "1" : "0");
  if (e.low) line(out, "LowLimit", dcf_text(*e.low, f.hex_default));
  if (e.high) line(out, "HighLimit", dcf_text(*e.high, f.hex_default));
  if (f.obj_flags != 0) line(out, "ObjFlags", "0x" + hex4(f.obj_flags));
  if (const auto it = values.find({index, e.sub}); it != values.end() && e.type != DataType::Domain)
    line(out, "ParameterValue", dcf_text(it->second, f.hex_default));
}

void object_list(std::string& out, const char* name, const std::vector<std::uint16_t>& list) {
  out.append("[").append(name).append("]\n");
  line(out, "SupportedObjects", std::to_string(list.size()));
  for (std::size_t i = 0; i < list.size(); ++i) line(out, std::to_string(i + 1), "0x" + hex4(list[i]));
  out.append("\n");
}

std::string failure_text(const sdo::TransferResult& r) {
  std::string s = r.error.message();
  if (!r.detail.empty()) s += " (" + r.detail + ")";
  return s;
}

bool ends_early(const sdo::TransferResult& r) {
  return r.cancelled || (r.origin == sdo::Origin::Local && r.error == SdoAbort::Timeout);
}

}  // namespace

bool is_configuration_entry(std::uint16_t index, const od::SubEntry& e) {
  if (excluded_index(index) || e.type == DataType::Domain) return false;
  if (!od::readable(e.access) || !od::writable(e.access)) return false;
  return index < 0x2000 || !e.pdo_mappable;
}

std::vector<ObjectAddress> configurable_objects(const eds::DeviceDescription& description) {
  std::vector<ObjectAddress> out;
  for (const auto& [index, obj] : description.od.objects()) {
    if (obj.code == od::ObjectCode::Domain) continue;
    for (const auto& [sub, e] : obj.subs) {
      if (!is_configuration_entry(index, e)) continue;
      if ((description.facts(index, sub).obj_flags & eds::kObjFlagRefuseReadOnScan) != 0) continue;
      out.push_back({index, sub});
    }
  }
  return out;
}

std::string write_dcf(const eds::DeviceDescription& eds, std::uint8_t node_id,
                      const std::map<ObjectAddress, Value>& values) {
  std::string out;
  const eds::FileInfo& fi = eds.file;
  out += "[FileInfo]\n";
  const std::string base = fi.file_name.empty() ? std::string("device.eds") : fi.file_name;
  line(out, "FileName", "node" + std::to_string(node_id) + ".dcf");
  if (!fi.file_version.empty()) line(out, "FileVersion", fi.file_version);
  if (!fi.file_revision.empty()) line(out, "FileRevision", fi.file_revision);
  line(out, "EDSVersion", fi.eds_version.empty() ? "4.0" : fi.eds_version);
  line(out, "Description", "configuration read back from node " + std::to_string(node_id) + " (" + base + ")");
  if (!fi.creation_time.empty()) line(out, "CreationTime", fi.creation_time);
  if (!fi.creation_date.empty()) line(out, "CreationDate", fi.creation_date);
  if (!fi.created_by.empty()) line(out, "CreatedBy", fi.created_by);
  line(out, "LastEDS", base);
  out += "\n[DeviceInfo]\n";
  const eds::DeviceInfo& di = eds.device;
  if (!di.vendor_name.empty()) line(out, "VendorName", di.vendor_name);
  if (di.vendor_number) line(out, "VendorNumber", hex32(*di.vendor_number));
  if (!di.product_name.empty()) line(out, "ProductName", di.product_name);
  if (di.product_number) line(out, "ProductNumber", hex32(*di.product_number));
  if (di.revision_number) line(out, "RevisionNumber", hex32(*di.revision_number));
  if (!di.order_code.empty()) line(out, "OrderCode", di.order_code);
  for (const unsigned kbit : {10U, 20U, 50U, 125U, 250U, 500U, 800U, 1000U}) {
    const bool has = std::find(di.baud_rates_kbit.begin(), di.baud_rates_kbit.end(), kbit) != di.baud_rates_kbit.end();
    line(out, "BaudRate_" + std::to_string(kbit), has ? "1" : "0");
  }
  line(out, "SimpleBootUpMaster", di.simple_boot_up_master ? "1" : "0");
  line(out, "SimpleBootUpSlave", di.simple_boot_up_slave ? "1" : "0");
  line(out, "Granularity", std::to_string(di.granularity));
  line(out, "DynamicChannelsSupported", std::to_string(di.dynamic_channels_supported));
  line(out, "GroupMessaging", di.group_messaging ? "1" : "0");
  line(out, "NrOfRXPDO", std::to_string(di.nr_of_rx_pdo));
  line(out, "NrOfTXPDO", std::to_string(di.nr_of_tx_pdo));
  line(out, "LSS_Supported", di.lss_supported ? "1" : "0");
  if (di.compact_pdo != 0) line(out, "CompactPDO", "0x" + hex4(di.compact_pdo));
  out += "\n[DeviceComissioning]\n";
  line(out, "NodeID", std::to_string(node_id));
  if (eds.commissioning) {
    const eds::Commissioning& c = *eds.commissioning;
    if (!c.node_name.empty()) line(out, "NodeName", c.node_name);
    if (c.baud_rate_kbit) line(out, "Baudrate", std::to_string(*c.baud_rate_kbit));
    if (c.net_number) line(out, "NetNumber", std::to_string(*c.net_number));
    if (!c.network_name.empty()) line(out, "NetworkName", c.network_name);
    line(out, "CANopenManager", c.canopen_manager ? "1" : "0");
    if (c.lss_serial_number) line(out, "LSS_SerialNumber", hex32(*c.lss_serial_number));
  }
  out += "\n";
  if (!eds.dummy_usage.empty()) {
    out += "[DummyUsage]\n";
    for (std::uint16_t t = 1; t <= 7; ++t) {
      const bool used = std::find(eds.dummy_usage.begin(), eds.dummy_usage.end(), t) != eds.dummy_usage.end();
      line(out, "Dummy" + hex4(t), used ? "1" : "0");
    }
    out += "\n";
  }
  // The lists name exactly the sections written (CiA 306 4.5.2).
  std::vector<std::uint16_t> mandatory, optional, manufacturer;
  for (const auto& [index, obj] : eds.od.objects()) {
    if (index == 0x1000 || index == 0x1001 || index == 0x1018) {
      mandatory.push_back(index);
    } else if (index >= 0x2000 && index <= 0x5FFF) {
      manufacturer.push_back(index);
    } else {
      optional.push_back(index);
    }
  }
  object_list(out, "MandatoryObjects", mandatory);
  object_list(out, "OptionalObjects", optional);
  object_list(out, "ManufacturerObjects", manufacturer);
  for (const auto& [index, obj] : eds.od.objects()) {
    const bool is_var = obj.code == od::ObjectCode::Var || obj.code == od::ObjectCode::Domain;
    out += "[" + hex4(index) + "]\n";
    if (is_var) {
      if (const auto it = obj.subs.find(0); it != obj.subs.end()) {
        od::SubEntry e = it->second;
        e.name = obj.name.empty() ? e.name : obj.name;
        write_entry(out, eds, index, e, obj.code == od::ObjectCode::Domain, values);
      }
      out += "\n";
      continue;
    }
    line(out, "ParameterName", obj.name);
    line(out, "ObjectType", obj.code == od::ObjectCode::Array ? "0x8" : "0x9");
    char n[8];
    std::snprintf(n, sizeof n, "0x%X", static_cast<unsigned>(obj.subs.size()));
    line(out, "SubNumber", n);
    out += "\n";
    for (const auto& [sub, e] : obj.subs) {
      char name[24];
      std::snprintf(name, sizeof name, "[%ssub%X]\n", hex4(index).c_str(), static_cast<unsigned>(sub));
      out += name;
      write_entry(out, eds, index, e, false, values);
      out += "\n";
    }
  }
  return out;
}

// ---- DcfReader ----------------------------------------------------------------

struct DcfReader::Run {
  std::uint64_t generation = 0;
  struct Item {
    ObjectAddress at;
    DataType type;
  };
  std::vector<Item> items;
  std::size_t next = 0;
  std::optional<sdo::RequestId> request;
  DcfReadReport report;
  Done done;
};

DcfReader::DcfReader(sdo::SdoClient& client, EventHandler on_event, TimeSource now)
    : client_(client), on_event_(std::move(on_event)), now_(std::move(now)) {}

DcfReader::~DcfReader() { detail::drop_runs(client_, runs_, now_()); }

bool DcfReader::busy(std::uint8_t node) const { return runs_.contains(node); }

std::error_code DcfReader::start(std::uint8_t node, const eds::DeviceDescription& description, Done done,
                                 TimePoint now) {
  if (node < 1 || node > 127) return make_error_code(TransferError::BadNode);
  if (busy(node)) return make_error_code(TransferError::Busy);
  Run run;
  for (const ObjectAddress& a : configurable_objects(description))
    run.items.push_back({a, description.od.find(a.index, a.sub)->type});
  if (run.items.empty()) return make_error_code(TransferError::NothingToTransfer);
  run.generation = ++generation_;
  run.report.node = node;
  run.report.total = run.items.size();
  run.done = std::move(done);
  const std::uint64_t gen = run.generation;
  runs_.emplace(node, std::move(run));
  submit(node, now);
  auto it = runs_.find(node);
  if (it == runs_.end() || it->second.generation != gen) return {};
  if (!it->second.request) {
    const std::error_code ec = it->second.report.stopped;
    runs_.erase(it);
    return ec;
  }
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::DcfRead;
  ev.total = it->second.report.total;
  ev.detail = "reading " + std::to_string(ev.total) + " objects";
  if (on_event_) on_event_(ev);
  return {};
}

void DcfReader::submit(std::uint8_t node, TimePoint now) {
  Run& run = runs_.at(node);
  const auto& item = run.items[run.next];
  const std::uint64_t gen = run.generation;
  sdo::Request req;
  req.node = node;
  req.index = item.at.index;
  req.sub = item.at.sub;
  req.expected_size = fixed_size(item.type);
  req.on_done = [this, node, gen](sdo::TransferResult&& r) { on_done(node, gen, std::move(r)); };
  auto id = client_.upload(std::move(req), now);
  if (!id) {
    run.report.stopped = id.code();
    if (run.next > 0) finish(node, id.code(), "reading " + od::object_label(item.at.index, item.at.sub) + ": " + id.code().message());
    return;
  }
  run.request = *id;
}

void DcfReader::on_done(std::uint8_t node, std::uint64_t gen, sdo::TransferResult&& r) {
  auto it = runs_.find(node);
  if (it == runs_.end() || it->second.generation != gen) return;
  Run& run = it->second;
  run.request.reset();
  const auto& item = run.items[run.next];
  const std::string label = od::object_label(item.at.index, item.at.sub);
  if (ends_early(r)) {
    finish(node, r.error, "reading " + label + ": " + (r.cancelled ? std::string("cancelled") : failure_text(r)),
           r.cancelled);
    return;
  }
  if (!r.ok()) {
    run.report.failed.push_back({item.at.index, item.at.sub, r.error, r.origin, failure_text(r)});
  } else if (auto v = decode(item.type, r.data); !v) {
    run.report.failed.push_back({item.at.index, item.at.sub, v.code(), sdo::Origin::Local,
                                 std::to_string(r.data.size()) + " bytes are no " +
                                     std::string(standard_name(item.type))});
  } else {
    run.report.values.emplace(item.at, std::move(*v));
  }
  ++run.next;
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::DcfRead;
  ev.done = run.next;
  ev.total = run.report.total;
  if (run.next >= run.items.size()) {
    finish(node, {}, {});
    return;
  }
  ev.detail = label;
  if (on_event_) on_event_(ev);
  it = runs_.find(node);
  if (it == runs_.end() || it->second.generation != gen) return;
  submit(node, now_());
}

void DcfReader::finish(std::uint8_t node, std::error_code stopped, std::string detail, bool cancelled) {
  Run& run = runs_.at(node);
  DcfReadReport report = std::move(run.report);
  report.stopped = stopped;
  report.detail = std::move(detail);
  report.cancelled = cancelled;
  Done done = std::move(run.done);
  const std::size_t finished = run.next;
  runs_.erase(node);
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::DcfRead;
  ev.done = finished;
  ev.total = report.total;
  if (stopped) {
    ev.status = TransferEvent::Status::Failed;
    ev.error = stopped;
    ev.detail = report.detail;
  } else {
    ev.status = TransferEvent::Status::Done;
    ev.detail = std::to_string(report.values.size()) + " objects read, " + std::to_string(report.failed.size()) +
                " aborted";
  }
  if (on_event_) on_event_(ev);
  if (done) done(report);
}

bool DcfReader::cancel(std::uint8_t node, TimePoint now) {
  const auto it = runs_.find(node);
  if (it == runs_.end()) return false;
  if (it->second.request && client_.cancel(*it->second.request, now)) return true;
  finish(node, make_error_code(SdoAbort::GeneralError), "cancelled", true);
  return true;
}

// ---- DcfApplier ---------------------------------------------------------------

struct DcfApplier::Run {
  std::uint64_t generation = 0;
  DcfApplyOptions options;
  enum class Kind : std::uint8_t { Write, Invalidate, Store };
  struct Op {
    Kind kind = Kind::Write;
    std::uint16_t index = 0;
    std::uint8_t sub = 0;
    Bytes data;
  };
  std::vector<Op> ops;
  std::size_t next = 0;
  bool invalidate_write = false;  // Invalidate: the COB-ID was read, its write is running
  std::uint32_t cob_id = 0;
  std::size_t written = 0;  // Write ops finished (with or without error)
  std::size_t written_ok = 0;
  std::optional<sdo::RequestId> request;
  DcfApplyReport report;
  Done done;
};

DcfApplier::DcfApplier(sdo::SdoClient& client, NmtSender send_nmt, EventHandler on_event, TimeSource now)
    : client_(client), send_nmt_(std::move(send_nmt)), on_event_(std::move(on_event)), now_(std::move(now)) {}

DcfApplier::~DcfApplier() { detail::drop_runs(client_, runs_, now_()); }

bool DcfApplier::busy(std::uint8_t node) const { return runs_.contains(node); }

std::error_code DcfApplier::start(std::uint8_t node, const eds::DeviceDescription& dcf, DcfApplyOptions options,
                                  Done done, TimePoint now) {
  if (node < 1 || node > 127) return make_error_code(TransferError::BadNode);
  if (busy(node)) return make_error_code(TransferError::Busy);
  Run run;
  for (auto& w : plan_configuration(dcf, PlanScope::AllValues))
    run.ops.push_back({w.invalidate ? Run::Kind::Invalidate : Run::Kind::Write, w.index, w.sub, std::move(w.data)});
  // Objects, not transfers: the invalidation is part of its PDO's COB-ID write.
  std::size_t writes = 0;
  for (const auto& op : run.ops) writes += op.kind == Run::Kind::Write ? 1 : 0;
  if (options.store) run.ops.push_back({Run::Kind::Store, 0x1010, 1, encode(Value::of_unsigned(DataType::Unsigned32, kStoreSignature))});
  if (run.ops.empty() && !options.reset) return make_error_code(TransferError::NothingToTransfer);
  run.generation = ++generation_;
  run.options = options;
  run.report.node = node;
  run.report.total = writes;
  run.done = std::move(done);
  const std::uint64_t gen = run.generation;
  runs_.emplace(node, std::move(run));
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::DcfApply;
  ev.total = writes;
  ev.detail = "writing " + std::to_string(writes) + " objects";
  Run& r = runs_.at(node);
  if (!r.ops.empty()) {
    step(node, now);
    auto it = runs_.find(node);
    if (it == runs_.end() || it->second.generation != gen) return {};
    if (!it->second.request) {
      const std::error_code ec = it->second.report.stopped;
      runs_.erase(it);
      return ec;
    }
    if (on_event_) on_event_(ev);
    return {};
  }
  // Only a reset was asked: nothing to wait for.
  if (on_event_) on_event_(ev);
  if (runs_.contains(node) && runs_.at(node).generation == gen) finish(node, {}, {});
  return {};
}

void DcfApplier::step(std::uint8_t node, TimePoint now) {
  Run& run = runs_.at(node);
  if (run.next >= run.ops.size()) {
    finish(node, {}, {});
    return;
  }
  const Run::Op& op = run.ops[run.next];
  const std::uint64_t gen = run.generation;
  sdo::Request req;
  req.node = node;
  req.index = op.index;
  req.sub = op.sub;
  req.timeout = run.options.timeout;
  req.on_done = [this, node, gen](sdo::TransferResult&& r) { on_done(node, gen, std::move(r)); };
  Result<sdo::RequestId> id = make_error_code(std::errc::invalid_argument);
  if (op.kind == Run::Kind::Invalidate && !run.invalidate_write) {
    req.expected_size = 4;
    id = client_.upload(std::move(req), now);
  } else if (op.kind == Run::Kind::Invalidate) {
    id = client_.download(std::move(req), encode(Value::of_unsigned(DataType::Unsigned32, run.cob_id | 0x80000000U)),
                          now);
  } else {
    id = client_.download(std::move(req), op.data, now);
  }
  if (!id) {
    run.report.stopped = id.code();
    if (run.next > 0 || run.invalidate_write)
      finish(node, id.code(), "writing " + od::object_label(op.index, op.sub) + ": " + id.code().message());
    return;
  }
  run.request = *id;
}

void DcfApplier::on_done(std::uint8_t node, std::uint64_t gen, sdo::TransferResult&& r) {
  auto it = runs_.find(node);
  if (it == runs_.end() || it->second.generation != gen) return;
  Run& run = it->second;
  run.request.reset();
  const Run::Op& op = run.ops[run.next];
  const std::string label = od::object_label(op.index, op.sub);
  if (ends_early(r)) {
    finish(node, r.error, "writing " + label + ": " + (r.cancelled ? std::string("cancelled") : failure_text(r)),
           r.cancelled);
    return;
  }
  bool object_done = false;
  switch (op.kind) {
    case Run::Kind::Invalidate:
      if (!run.invalidate_write && r.ok()) {
        auto v = decode(DataType::Unsigned32, r.data);
        if (v && (std::get<std::uint64_t>(v->data) & 0x80000000U) == 0) {
          // A valid PDO: disable it before remapping (7.5.2.35), bits 0-29 kept.
          run.cob_id = static_cast<std::uint32_t>(std::get<std::uint64_t>(v->data));
          run.invalidate_write = true;
          step(node, now_());
          return;
        }
      }
      // Already invalid, or the read/disable failed: the remapping writes
      // that follow say whether the device accepts them.
      if (!r.ok()) {
        run.report.objects.push_back({op.index, op.sub, r.error, r.origin, "disabling the PDO: " + failure_text(r)});
        ++run.report.failed;
      }
      run.invalidate_write = false;
      break;
    case Run::Kind::Write:
      object_done = true;
      run.report.objects.push_back({op.index, op.sub, r.error, r.origin, r.ok() ? std::string() : failure_text(r)});
      ++run.written;
      if (r.ok()) ++run.written_ok;
      else ++run.report.failed;
      break;
    case Run::Kind::Store:
      if (r.ok()) {
        run.report.stored = true;
      } else {
        run.report.store_error = ObjectResult{op.index, op.sub, r.error, r.origin, failure_text(r)};
      }
      break;
  }
  ++run.next;
  if (object_done) {
    TransferEvent ev;
    ev.node = node;
    ev.operation = TransferEvent::Operation::DcfApply;
    ev.done = run.written;
    ev.total = run.report.total;
    ev.detail = label + (r.ok() ? "" : ": " + failure_text(r));
    if (on_event_) on_event_(ev);
    it = runs_.find(node);
    if (it == runs_.end() || it->second.generation != gen) return;
  }
  step(node, now_());
}

void DcfApplier::finish(std::uint8_t node, std::error_code stopped, std::string detail, bool cancelled) {
  Run& run = runs_.at(node);
  DcfApplyReport report = std::move(run.report);
  report.stopped = stopped;
  report.detail = std::move(detail);
  report.cancelled = cancelled;
  // A reset after a refused save would throw the written values away.
  if (!stopped && run.options.reset && (!run.options.store || report.stored)) {
    if (send_nmt_) send_nmt_(NmtCommand::ResetNode, node);
    report.reset = true;
  }
  Done done = std::move(run.done);
  const std::size_t written = run.written, written_ok = run.written_ok;
  runs_.erase(node);
  TransferEvent ev;
  ev.node = node;
  ev.operation = TransferEvent::Operation::DcfApply;
  ev.done = written;
  ev.total = report.total;
  if (stopped) {
    ev.status = TransferEvent::Status::Failed;
    ev.error = stopped;
    ev.detail = report.detail;
  } else {
    ev.status = TransferEvent::Status::Done;
    ev.detail = std::to_string(written_ok) + " of " + std::to_string(report.total) + " objects written";
    if (report.failed != 0) ev.detail += ", " + std::to_string(report.failed) + " refused";
    if (report.store_error) ev.detail += "; store refused: " + report.store_error->detail;
    else if (report.stored) ev.detail += ", stored";
    if (report.reset) ev.detail += ", node reset";
  }
  if (on_event_) on_event_(ev);
  if (done) done(report);
}

bool DcfApplier::cancel(std::uint8_t node, TimePoint now) {
  const auto it = runs_.find(node);
  if (it == runs_.end()) return false;
  if (it->second.request && client_.cancel(*it->second.request, now)) return true;
  finish(node, make_error_code(SdoAbort::GeneralError), "cancelled", true);
  return true;
}

}  // namespace canopen::master
