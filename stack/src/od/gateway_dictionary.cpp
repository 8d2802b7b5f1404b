// The gateway's own object dictionary: the communication objects of CiA 301
// 7.5.2 with the value rules the standard gives for each. Every refused
// write leaves the dictionary unchanged: the hooks only check, the
// dictionary stores (except 1003h sub 0 = 0, which clears the history).
#include "canopen/od/gateway_dictionary.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <utility>
#include <vector>

namespace canopen::od {

namespace {

constexpr std::uint32_t kBit31 = 0x8000'0000U;   // COB-ID: valid (0) / invalid (1), or TIME consume
constexpr std::uint32_t kBit30 = 0x4000'0000U;   // COB-ID: SYNC gen., TIME produce, TPDO no-RTR, SDO dyn
constexpr std::uint32_t kBit29 = 0x2000'0000U;   // COB-ID: frame (29-bit CAN-ID)
constexpr std::uint32_t kBits0To29 = 0x3FFF'FFFFU;
constexpr std::uint32_t kBits0To30 = 0x7FFF'FFFFU;
constexpr std::uint32_t kExtendedIdBits = 0x1FFF'FFFFU;
constexpr std::uint32_t kStandardIdBits = 0x0000'07FFU;

constexpr std::uint32_t kSaveSignature = 0x6576'6173U;  // "save", 7.5.2.13 figure 55
constexpr std::uint32_t kLoadSignature = 0x6461'6F6CU;  // "load", 7.5.2.14 figure 57
constexpr std::uint32_t kStoreOnCommand = 0x1U;         // read of 1010h/1011h sub N: bit 0 cmd, bit 1 auto = 0

constexpr std::uint8_t kMaxMappedObjects = 0x40;  // 7.5.2.36 table 69
constexpr unsigned kMaxPdoBits = 64;              // classical CAN PDO

std::error_code err(SdoAbort a) { return make_error_code(a); }

Value u8(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned8, v); }
Value u16(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned16, v); }
Value u32(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned32, v); }

// Hooks are only installed on unsigned entries, whose values are uint64_t.
std::uint32_t as_u32(const Value& v) {
  const auto* u = std::get_if<std::uint64_t>(&v.data);
  return u == nullptr ? 0U : static_cast<std::uint32_t>(*u);
}

SubEntry entry(std::uint8_t sub, std::string name, Access access, Value value, bool pdo_mappable = false) {
  SubEntry e;
  e.sub = sub;
  e.name = std::move(name);
  e.type = value.type;
  e.access = access;
  e.pdo_mappable = pdo_mappable;
  e.default_value = value;
  e.value = std::move(value);
  return e;
}

// RECORD whose sub 0 (const) is the highest sub-index present (7.4.7.2).
Object record(std::uint16_t index, std::string name, std::vector<SubEntry> entries) {
  Object obj;
  obj.index = index;
  obj.name = std::move(name);
  obj.code = ObjectCode::Record;
  std::uint8_t highest = 0;
  for (const SubEntry& e : entries) highest = std::max(highest, e.sub);
  obj.subs.emplace(std::uint8_t{0}, entry(0, "Highest sub-index supported", Access::Const, u8(highest)));
  for (SubEntry& e : entries) obj.subs.emplace(e.sub, std::move(e));
  return obj;
}

// 7.3.5 table 40: 11-bit CAN-IDs no configurable COB may use. An SDO client
// must be able to reach a server's default channel (600h/580h + node-ID), so
// for client COB-IDs the default SDO ranges are allowed.
bool is_restricted_can_id(std::uint32_t id, bool allow_default_sdo) {
  if (id <= 0x07F) return true;                     // NMT, reserved
  if (id >= 0x101 && id <= 0x180) return true;      // reserved
  if (!allow_default_sdo && id >= 0x581 && id <= 0x5FF) return true;  // default SDO (tx)
  if (!allow_default_sdo && id >= 0x601 && id <= 0x67F) return true;  // default SDO (rx)
  if (id >= 0x6E0 && id <= 0x6FF) return true;      // reserved
  if (id >= 0x701 && id <= 0x77F) return true;      // NMT error control
  return id >= 0x780 && id <= 0x7FF;                // reserved
}

// The CAN-ID part of any COB-ID: a 29-bit CAN-ID only with bit 29 (frame)
// set; an 11-bit CAN-ID must not be restricted while the COB is in use.
// 7.3.5 restricts 11-bit CAN-IDs only.
std::error_code check_can_id(std::uint32_t cob_id, bool in_use, bool sdo_client = false) {
  if ((cob_id & kBit29) != 0) return {};
  if ((cob_id & kExtendedIdBits & ~kStandardIdBits) != 0) return err(SdoAbort::InvalidValue);
  if (in_use && is_restricted_can_id(cob_id & kStandardIdBits, sdo_client)) return err(SdoAbort::InvalidValue);
  return {};
}

// ---- 7.5.2.4 1003h pre-defined error field -------------------------------------

constexpr std::uint16_t kErrorField = 0x1003;

Result<Bytes> read_error_field(const ObjectDictionary& od, const SubEntry& e) {
  // Sub-indexes past the number of errors hold no error: abort 0800 0024h.
  if (e.sub != 0 && e.sub > od.get_unsigned(kErrorField, 0).value_or(0)) {
    return {err(SdoAbort::NoDataAvailable), "1003h sub " + std::to_string(e.sub) + ": no error recorded there"};
  }
  return encode(e.value);
}

std::error_code write_error_field(ObjectDictionary& od, SubEntry& e, const Value& v) {
  // Only sub 0 is writable, and only with 0, which empties the history.
  if (e.sub != 0 || as_u32(v) != 0) return err(SdoAbort::InvalidValue);
  if (Object* obj = od.find(kErrorField)) {
    for (auto& [sub, s] : obj->subs) {
      if (sub != 0) s.value = u32(0);
    }
  }
  return {};
}

// ---- 7.5.2.5 1005h COB-ID SYNC -----------------------------------------------------

std::error_code write_cob_id_sync(SubEntry& e, const Value& v) {
  const std::uint32_t old = as_u32(e.value);
  const std::uint32_t now = as_u32(v);
  // While SYNC is generated (bit 30) bits 0..29 must not change.
  if ((old & kBit30) != 0 && ((old ^ now) & kBits0To29) != 0) return err(SdoAbort::InvalidValue);
  return check_can_id(now, true);  // a SYNC consumer always listens
}

// ---- 7.5.2.13 / 7.5.2.14 1010h store, 1011h restore ----------------------------

// The read value is the capability, not the last signature written.
Result<Bytes> read_store_capability(const SubEntry& e) {
  if (e.sub == 0) return encode(e.value);
  return encode(u32(kStoreOnCommand));
}

WriteHook signature_hook(std::uint32_t signature, std::function<std::error_code(std::uint8_t)> action) {
  return [signature, action = std::move(action)](SubEntry& e, const Value& v) -> std::error_code {
    if (as_u32(v) != signature) return err(SdoAbort::CannotStore);  // 0800 002xh
    return action ? action(e.sub) : std::error_code{};
  };
}

// ---- 7.5.2.15 1012h COB-ID TIME ------------------------------------------------------

std::error_code write_cob_id_time(SubEntry& e, const Value& v) {
  const std::uint32_t old = as_u32(e.value);
  const std::uint32_t now = as_u32(v);
  const std::uint32_t in_use = kBit31 | kBit30;  // consume / produce
  if ((old & in_use) != 0 && ((old ^ now) & kBits0To29) != 0) return err(SdoAbort::InvalidValue);
  return check_can_id(now, (now & in_use) != 0);
}

// ---- 7.5.2.17 1014h COB-ID EMCY --------------------------------------------------------

std::error_code write_cob_id_emcy(SubEntry& e, const Value& v) {
  const std::uint32_t old = as_u32(e.value);
  const std::uint32_t now = as_u32(v);
  if ((now & kBit30) != 0) return err(SdoAbort::InvalidValue);  // reserved, always 0
  if ((old & kBit31) == 0 && ((old ^ now) & kBits0To29) != 0) return err(SdoAbort::InvalidValue);
  return check_can_id(now, (now & kBit31) == 0);
}

// ---- 7.5.2.19 1016h consumer heartbeat time ------------------------------------------

constexpr std::uint16_t kConsumerHeartbeat = 0x1016;

std::error_code write_consumer_heartbeat(ObjectDictionary& od, SubEntry& e, const Value& v) {
  // Bits 16..23 node-ID, 0..15 time in ms; an entry with time 0 or node-ID
  // 0 / > 127 is unused. Two used entries must not name the same node.
  const std::uint32_t now = as_u32(v);
  const std::uint32_t node = (now >> 16) & 0xFFU;
  if ((now & 0xFFFFU) == 0 || node == 0 || node > 127) return {};
  const Object* obj = od.find(kConsumerHeartbeat);
  if (obj == nullptr) return {};
  for (const auto& [sub, other] : obj->subs) {
    if (sub == 0 || sub == e.sub) continue;
    const std::uint32_t o = as_u32(other.value);
    if (((o >> 16) & 0xFFU) == node && (o & 0xFFFFU) != 0) return err(SdoAbort::ParameterIncompatible);
  }
  return {};
}

// ---- 7.5.2.22 1019h synchronous counter overflow value --------------------------------

std::error_code write_sync_overflow(ObjectDictionary& od, SubEntry& e, const Value& v) {
  const std::uint32_t now = as_u32(v);
  if (now == 1 || now > 240) return err(SdoAbort::InvalidValue);  // 1 and 241..255 reserved
  // "Once the communication cycle period (1006h) is non-zero, a change aborts 0800 0022h."
  if (now != as_u32(e.value) && od.get_unsigned(0x1006, 0).value_or(0) != 0) {
    return err(SdoAbort::CannotStoreDeviceState);
  }
  return {};
}

// ---- 7.5.2.34 1280h.. SDO client parameter ---------------------------------------------

std::error_code write_sdo_client(SubEntry& e, const Value& v) {
  if (e.sub != 1 && e.sub != 2) return {};  // sub 3 (server node-ID): limits 1..127
  const std::uint32_t old = as_u32(e.value);
  const std::uint32_t now = as_u32(v);
  // Same rule as for the server (7.5.2.33): bits 0..29 fixed while valid.
  if ((old & kBit31) == 0 && ((old ^ now) & kBits0To29) != 0) return err(SdoAbort::InvalidValue);
  return check_can_id(now, (now & kBit31) == 0, true);
}

// ---- 7.5.2.35 / 7.5.2.37 PDO communication parameter ------------------------------------

bool pdo_is_valid(const ObjectDictionary& od, std::uint16_t comm_index) {
  return (od.get_unsigned(comm_index, 1).value_or(kBit31) & kBit31) == 0;
}

bool transmission_type_supported(bool tpdo, std::uint32_t t) {
  if (t <= 0xF0) return true;                 // synchronous
  if (t == 0xFE || t == 0xFF) return true;    // event-driven
  return tpdo && (t == 0xFC || t == 0xFD);    // RTR-only (TPDO, table 72)
}

DictWriteHook pdo_comm_hook(std::uint16_t comm_index, bool tpdo) {
  return [comm_index, tpdo](ObjectDictionary& od, SubEntry& e, const Value& v) -> std::error_code {
    const std::uint32_t old = as_u32(e.value);
    const std::uint32_t now = as_u32(v);
    const bool valid = pdo_is_valid(od, comm_index);
    switch (e.sub) {
      case 1:
        // While the PDO exists only bit 31 may change (tables 66 and 70).
        if ((old & kBit31) == 0 && ((old ^ now) & kBits0To30) != 0) return err(SdoAbort::InvalidValue);
        return check_can_id(now, (now & kBit31) == 0);
      case 2:
        if (!transmission_type_supported(tpdo, now)) return err(SdoAbort::InvalidValue);
        [[fallthrough]];
      case 3:  // inhibit time
      case 6:  // SYNC start value (TPDO)
        // Configuration of an existing PDO is fixed: invalidate it first.
        if (valid && now != old) return err(SdoAbort::InvalidValue);
        return {};
      default:  // event timer: may change at any time
        return {};
    }
  };
}

// ---- 7.5.2.36 / 7.5.2.38 PDO mapping parameter -------------------------------------------

// 7.4.7.1: the static data types an RPDO may map as dummy entries.
bool is_dummy_index(std::uint16_t index) {
  return (index >= 0x0001 && index <= 0x0007) || index == 0x0010 || (index >= 0x0012 && index <= 0x0016) ||
         (index >= 0x0018 && index <= 0x001B);
}

// One mapping entry: index in bits 16..31, sub-index 8..15, length in bits 0..7.
std::error_code check_mapping_entry(const ObjectDictionary& od, bool tpdo, std::uint32_t mapping) {
  const auto index = static_cast<std::uint16_t>(mapping >> 16);
  const auto sub = static_cast<std::uint8_t>(mapping >> 8);
  const unsigned bits = mapping & 0xFFU;
  if (!tpdo && is_dummy_index(index) && sub == 0) {
    const auto type = data_type_from_index(index);
    return type && pdo_bit_size(*type) == bits ? std::error_code{} : err(SdoAbort::NotMappable);
  }
  const SubEntry* target = od.find(index, sub);
  if (target == nullptr) return err(SdoAbort::NoSuchObject);  // 0602 0000h for index or sub-index
  // rwr objects go out in TPDOs only, rww ones come in through RPDOs only (7.4.5).
  const bool direction_ok = tpdo ? readable(target->access) && target->access != Access::ReadWriteWrite
                                 : writable(target->access) && target->access != Access::ReadWriteRead;
  if (!target->pdo_mappable || !direction_ok) return err(SdoAbort::NotMappable);
  const unsigned size = pdo_bit_size(target->type);
  if (size == 0 || size != bits) return err(SdoAbort::NotMappable);
  return {};
}

DictWriteHook pdo_mapping_hook(std::uint16_t comm_index, std::uint16_t map_index, bool tpdo) {
  return [comm_index, map_index, tpdo](ObjectDictionary& od, SubEntry& e, const Value& v) -> std::error_code {
    const std::uint32_t now = as_u32(v);
    if (e.sub != 0) {
      // Step 3 of the re-mapping procedure: entries change only while the
      // mapping is disabled (sub 0 = 0). 0 clears an entry.
      if (od.get_unsigned(map_index, 0).value_or(0) != 0) return err(SdoAbort::InvalidValue);
      return now == 0 ? std::error_code{} : check_mapping_entry(od, tpdo, now);
    }
    // Steps 2 and 4: the count changes only while the PDO is invalid; a
    // non-zero count enables the mapping, so all its entries must hold.
    if (now != as_u32(e.value) && pdo_is_valid(od, comm_index)) return err(SdoAbort::InvalidValue);
    if (now > kMaxMappedObjects) return err(SdoAbort::InvalidValue);  // reserved, or MPDO (not supported)
    unsigned total = 0;
    for (std::uint8_t k = 1; k <= now; ++k) {
      const std::uint32_t m = static_cast<std::uint32_t>(od.get_unsigned(map_index, k).value_or(0));
      if (auto ec = check_mapping_entry(od, tpdo, m)) return ec;
      total += m & 0xFFU;
    }
    if (total > kMaxPdoBits) return err(SdoAbort::PdoLengthExceeded);
    return {};
  };
}

void add_pdo(ObjectDictionary& od, std::uint8_t node_id, unsigned n, bool tpdo) {
  // 7.5.2.35 RPDO / 7.5.2.37 TPDO communication parameter.
  const auto comm_index = static_cast<std::uint16_t>((tpdo ? 0x1800U : 0x1400U) + n);
  const auto map_index = static_cast<std::uint16_t>((tpdo ? 0x1A00U : 0x1600U) + n);
  // The first four use the pre-defined connection set (7.3.3 table 39);
  // all start invalid (bit 31): the gateway maps nothing by default.
  std::uint32_t cob_id = kBit31;
  if (n < 4) cob_id |= (tpdo ? 0x180U : 0x200U) + 0x100U * n + node_id;
  const std::string nth = std::to_string(n + 1);
  std::vector<SubEntry> comm;
  comm.push_back(entry(1, "COB-ID used by " + std::string(tpdo ? "TPDO" : "RPDO"), Access::ReadWrite, u32(cob_id)));
  // 0xFE: event-driven, manufacturer-specific (no device profile).
  comm.push_back(entry(2, "Transmission type", Access::ReadWrite, u8(0xFE)));
  comm.push_back(entry(3, "Inhibit time", Access::ReadWrite, u16(0)));
  // Sub 4 is reserved and not implemented, so it aborts 0609 0011h.
  comm.push_back(entry(5, "Event timer", Access::ReadWrite, u16(0)));
  if (tpdo) {
    // RPDOs have no SYNC start value (reads and writes abort 0609 0011h).
    SubEntry start = entry(6, "SYNC start value", Access::ReadWrite, u8(0));
    start.high = u8(240);
    comm.push_back(std::move(start));
  }
  od.insert(record(comm_index, std::string(tpdo ? "TPDO " : "RPDO ") + nth + " communication parameter",
                   std::move(comm)));
  od.on_dict_write(comm_index, pdo_comm_hook(comm_index, tpdo));

  // 7.5.2.36 RPDO / 7.5.2.38 TPDO mapping parameter: sub 0 is the number of
  // mapped objects (rw), not the highest sub-index.
  Object map;
  map.index = map_index;
  map.name = std::string(tpdo ? "TPDO " : "RPDO ") + nth + " mapping parameter";
  map.code = ObjectCode::Record;
  map.subs.emplace(std::uint8_t{0}, entry(0, "Number of mapped application objects in PDO", Access::ReadWrite, u8(0)));
  for (unsigned k = 1; k <= kMaxMappedObjects; ++k) {
    const auto sub = static_cast<std::uint8_t>(k);
    map.subs.emplace(sub, entry(sub, "Application object " + std::to_string(k), Access::ReadWrite, u32(0)));
  }
  od.insert(std::move(map));
  od.on_dict_write(map_index, pdo_mapping_hook(comm_index, map_index, tpdo));
}

}  // namespace

void install_store_restore(ObjectDictionary& od, std::function<std::error_code(std::uint8_t sub)> on_store,
                           std::function<std::error_code(std::uint8_t sub)> on_restore) {
  if (od.find(0x1010) != nullptr) {
    od.on_read(0x1010, read_store_capability);
    od.on_write(0x1010, signature_hook(kSaveSignature, std::move(on_store)));
  }
  if (od.find(0x1011) != nullptr) {
    od.on_read(0x1011, read_store_capability);
    od.on_write(0x1011, signature_hook(kLoadSignature, std::move(on_restore)));
  }
}

ObjectDictionary make_gateway_dictionary(std::uint8_t node_id, const GatewayIdentity& identity,
                                         const GatewayDictionaryOptions& options) {
  assert(node_id >= 1 && node_id <= 127 && "node-ID out of 1..127");
  ObjectDictionary od;
  const Access ro = Access::ReadOnly;
  const Access rw = Access::ReadWrite;
  const Access cst = Access::Const;

  // 7.5.2.1 device type.
  od.insert(make_var(0x1000, "Device type", DataType::Unsigned32, ro, u32(identity.device_type)));
  // 7.5.2.2 error register: kept by the EMCY producer, PDO-mappable.
  od.insert(make_var(0x1001, "Error register", DataType::Unsigned8, ro, u8(0), true));

  // 7.5.2.4 pre-defined error field: sub 0 = number of errors (00h..FEh).
  if (options.error_history_size > 0) {
    const auto size = std::min<std::uint8_t>(options.error_history_size, 0xFE);
    Object errors = make_array(kErrorField, "Pre-defined error field", DataType::Unsigned32, ro, size, rw);
    SubEntry& count = errors.subs.at(0);
    count.name = "Number of errors";
    count.value = u8(0);
    count.default_value = count.value;
    for (auto& [sub, s] : errors.subs) {
      if (sub != 0) s.name = "Standard error field " + std::to_string(sub);
    }
    od.insert(std::move(errors));
    od.on_dict_read(kErrorField, read_error_field);
    od.on_dict_write(kErrorField, write_error_field);
  }

  // 7.5.2.5 COB-ID SYNC: 80h, not generating (bit 30 = 0).
  od.insert(make_var(0x1005, "COB-ID SYNC", DataType::Unsigned32, rw, u32(0x80)));
  od.on_write(0x1005, write_cob_id_sync);
  // 7.5.2.6 communication cycle period (us), 7.5.2.7 synchronous window length (us).
  od.insert(make_var(0x1006, "Communication cycle period", DataType::Unsigned32, rw, u32(0)));
  od.insert(make_var(0x1007, "Synchronous window length", DataType::Unsigned32, rw, u32(0)));

  // 7.5.2.8 - 7.5.2.10 manufacturer device name, hardware and software version.
  od.insert(make_var(0x1008, "Manufacturer device name", DataType::VisibleString, cst,
                     Value::of_string(identity.device_name)));
  od.insert(make_var(0x1009, "Manufacturer hardware version", DataType::VisibleString, cst,
                     Value::of_string(identity.hardware_version)));
  od.insert(make_var(0x100A, "Manufacturer software version", DataType::VisibleString, cst,
                     Value::of_string(identity.software_version)));

  // 7.5.2.11 guard time (ms), 7.5.2.12 life time factor.
  od.insert(make_var(0x100C, "Guard time", DataType::Unsigned16, rw, u16(0)));
  od.insert(make_var(0x100D, "Life time factor", DataType::Unsigned8, rw, u8(0)));

  // 7.5.2.13 store parameters, 7.5.2.14 restore default parameters:
  // sub 1 all, 2 communication, 3 application.
  for (const bool store : {true, false}) {
    const auto index = static_cast<std::uint16_t>(store ? 0x1010 : 0x1011);
    Object obj = make_array(index, store ? "Store parameters" : "Restore default parameters", DataType::Unsigned32, rw,
                            3, cst);
    static constexpr std::array<const char*, 3> groups{"all", "communication", "application"};
    for (std::uint8_t sub = 1; sub <= 3; ++sub) {
      SubEntry& s = obj.subs.at(sub);
      s.name = std::string(store ? "Save " : "Restore ") + groups.at(sub - 1U) +
               (store ? " parameters" : " default parameters");
      s.value = u32(kStoreOnCommand);
      s.default_value = s.value;
    }
    od.insert(std::move(obj));
  }
  install_store_restore(od, options.on_store, options.on_restore);

  // 7.5.2.15 COB-ID TIME: 100h, neither consumer (bit 31) nor producer (bit 30).
  od.insert(make_var(0x1012, "COB-ID TIME", DataType::Unsigned32, rw, u32(0x100)));
  od.on_write(0x1012, write_cob_id_time);
  // 7.5.2.16 high resolution time stamp (us).
  od.insert(make_var(0x1013, "High resolution time stamp", DataType::Unsigned32, rw, u32(0), true));
  // 7.5.2.17 COB-ID EMCY: 80h + node-ID, valid.
  od.insert(make_var(0x1014, "COB-ID EMCY", DataType::Unsigned32, rw, u32(0x80U + node_id)));
  od.on_write(0x1014, write_cob_id_emcy);
  // 7.5.2.18 inhibit time EMCY (100 us).
  od.insert(make_var(0x1015, "Inhibit time EMCY", DataType::Unsigned16, rw, u16(0)));

  // 7.5.2.19 consumer heartbeat time: sub 0 const, 01h..7Fh entries.
  if (options.heartbeat_consumers > 0) {
    const auto n = std::min<std::uint8_t>(options.heartbeat_consumers, 0x7F);
    od.insert(make_array(kConsumerHeartbeat, "Consumer heartbeat time", DataType::Unsigned32, rw, n, cst));
    od.on_dict_write(kConsumerHeartbeat, write_consumer_heartbeat);
  }
  // 7.5.2.20 producer heartbeat time (ms), 0 = off.
  od.insert(make_var(0x1017, "Producer heartbeat time", DataType::Unsigned16, rw, u16(0)));

  // 7.5.2.21 identity object.
  od.insert(record(0x1018, "Identity object",
                   {entry(1, "Vendor-ID", ro, u32(identity.vendor_id)),
                    entry(2, "Product code", ro, u32(identity.product_code)),
                    entry(3, "Revision number", ro, u32(identity.revision)),
                    entry(4, "Serial number", ro, u32(identity.serial))}));

  // 7.5.2.22 synchronous counter overflow value: 0 = no counter.
  od.insert(make_var(0x1019, "Synchronous counter overflow value", DataType::Unsigned8, rw, u8(0)));
  od.on_dict_write(0x1019, write_sync_overflow);

  // 7.5.2.33 default SDO server: 600h/580h + node-ID, fixed.
  od.insert(record(0x1200, "SDO server parameter",
                   {entry(1, "COB-ID client to server (rx)", cst, u32(0x600U + node_id)),
                    entry(2, "COB-ID server to client (tx)", ro, u32(0x580U + node_id))}));

  // 7.5.2.34 SDO client parameters, channel k talking to node k+1 on that
  // node's default server. Unlike the standard's default (invalid), the
  // channels start valid: the gateway keeps one ready for every node. The
  // channel to the gateway's own node-ID stays invalid, as its COB-IDs are
  // the gateway's own server's. At most 127 channels (one per node-ID).
  const unsigned clients = std::min<unsigned>(options.sdo_clients, 127);
  for (unsigned k = 0; k < clients; ++k) {
    const auto index = static_cast<std::uint16_t>(0x1280U + k);
    const std::uint32_t node = k + 1;
    const std::uint32_t invalid = node == node_id ? kBit31 : 0U;
    SubEntry server = entry(3, "Node-ID of the SDO server", rw, u8(node));
    server.low = u8(1);
    server.high = u8(127);
    od.insert(record(index, "SDO client parameter " + std::to_string(k + 1),
                     {entry(1, "COB-ID client to server (tx)", rw, u32(invalid | (0x600U + node))),
                      entry(2, "COB-ID server to client (rx)", rw, u32(invalid | (0x580U + node))),
                      std::move(server)}));
    od.on_write(index, write_sdo_client);
  }

  // 7.5.2.35 - 7.5.2.38 PDOs.
  for (unsigned n = 0; n < options.rpdos; ++n) add_pdo(od, node_id, n, false);
  for (unsigned n = 0; n < options.tpdos; ++n) add_pdo(od, node_id, n, true);
  return od;
}

void push_error_history(ObjectDictionary& od, std::uint32_t error_field) {
  Object* obj = od.find(kErrorField);
  if (obj == nullptr || obj->subs.size() < 2) return;
  const std::uint8_t capacity = obj->subs.rbegin()->first;
  const std::uint64_t count = od.get_unsigned(kErrorField, 0).value_or(0);
  const auto n = static_cast<std::uint8_t>(std::min<std::uint64_t>(count + 1, capacity));
  for (std::uint8_t k = n; k >= 2; --k) {
    SubEntry* to = od.find(kErrorField, k);
    const SubEntry* from = od.find(kErrorField, static_cast<std::uint8_t>(k - 1));
    if (to != nullptr && from != nullptr) to->value = from->value;
  }
  if (SubEntry* newest = od.find(kErrorField, 1)) newest->value = u32(error_field);
  obj->subs.at(0).value = u8(n);
}

}  // namespace canopen::od
