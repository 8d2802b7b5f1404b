// Object dictionary (CiA 301 7.4): storage plus the SDO-side access rules.
#include "canopen/od/object_dictionary.hpp"

#include <array>
#include <cassert>
#include <cctype>
#include <cstdio>
#include <utility>

namespace canopen::od {

namespace {

std::error_code err(SdoAbort a) { return make_error_code(a); }

}  // namespace

std::string object_label(std::uint16_t index, std::uint8_t sub) {
  std::array<char, 24> buf{};
  std::snprintf(buf.data(), buf.size(), "%04Xh sub %u", static_cast<unsigned>(index), static_cast<unsigned>(sub));
  return buf.data();
}

std::string_view to_string(ObjectCode c) {
  switch (c) {
    case ObjectCode::Null: return "NULL";
    case ObjectCode::Domain: return "DOMAIN";
    case ObjectCode::DefType: return "DEFTYPE";
    case ObjectCode::DefStruct: return "DEFSTRUCT";
    case ObjectCode::Var: return "VAR";
    case ObjectCode::Array: return "ARRAY";
    case ObjectCode::Record: return "RECORD";
  }
  return "?";
}

std::string_view to_string(Access a) {
  switch (a) {
    case Access::ReadOnly: return "ro";
    case Access::WriteOnly: return "wo";
    case Access::ReadWrite: return "rw";
    case Access::ReadWriteRead: return "rwr";
    case Access::ReadWriteWrite: return "rww";
    case Access::Const: return "const";
  }
  return "?";
}

std::optional<Access> parse_access(std::string_view s) {
  std::string lower;
  lower.reserve(s.size());
  for (char c : s) lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  static constexpr std::array<Access, 6> all{Access::ReadOnly,      Access::WriteOnly,      Access::ReadWrite,
                                             Access::ReadWriteRead, Access::ReadWriteWrite, Access::Const};
  for (Access a : all) {
    if (to_string(a) == lower) return a;
  }
  return std::nullopt;
}

// ---- storage -----------------------------------------------------------------

Object& ObjectDictionary::insert(Object obj) {
  const std::uint16_t index = obj.index;
  // Assignment into an existing node keeps the Object's address stable.
  Object& slot = objects_[index];
  slot = std::move(obj);
  return slot;
}

bool ObjectDictionary::erase(std::uint16_t index) {
  // Hooks belong to the object: a later object at this index starts clean.
  read_hooks_.erase(index);
  write_hooks_.erase(index);
  dict_read_hooks_.erase(index);
  dict_write_hooks_.erase(index);
  return objects_.erase(index) > 0;
}

const Object* ObjectDictionary::find(std::uint16_t index) const {
  auto it = objects_.find(index);
  return it == objects_.end() ? nullptr : &it->second;
}

Object* ObjectDictionary::find(std::uint16_t index) {
  auto it = objects_.find(index);
  return it == objects_.end() ? nullptr : &it->second;
}

const SubEntry* ObjectDictionary::find(std::uint16_t index, std::uint8_t sub) const {
  const Object* obj = find(index);
  if (obj == nullptr) return nullptr;
  auto it = obj->subs.find(sub);
  return it == obj->subs.end() ? nullptr : &it->second;
}

SubEntry* ObjectDictionary::find(std::uint16_t index, std::uint8_t sub) {
  Object* obj = find(index);
  if (obj == nullptr) return nullptr;
  auto it = obj->subs.find(sub);
  return it == obj->subs.end() ? nullptr : &it->second;
}

// ---- SDO access ----------------------------------------------------------------

Result<Bytes> ObjectDictionary::read(std::uint16_t index, std::uint8_t sub) const {
  const Object* obj = find(index);
  if (obj == nullptr) return {err(SdoAbort::NoSuchObject), object_label(index, sub) + ": no such object"};
  auto it = obj->subs.find(sub);
  if (it == obj->subs.end()) return {err(SdoAbort::NoSuchSubIndex), object_label(index, sub) + ": no such sub-index"};
  const SubEntry& entry = it->second;
  if (!readable(entry.access)) return {err(SdoAbort::ReadOfWriteOnly), object_label(index, sub) + " is write-only"};
  if (auto h = read_hooks_.find(index); h != read_hooks_.end()) return h->second(entry);
  if (auto h = dict_read_hooks_.find(index); h != dict_read_hooks_.end()) return h->second(*this, entry);
  return encode(entry.value);
}

std::error_code ObjectDictionary::write(std::uint16_t index, std::uint8_t sub, std::span<const std::uint8_t> data) {
  SubEntry* entry = find(index, sub);
  if (entry == nullptr) return err(find(index) == nullptr ? SdoAbort::NoSuchObject : SdoAbort::NoSuchSubIndex);
  if (!writable(entry->access)) return err(SdoAbort::WriteOfReadOnly);

  // Length first, so a wrong-sized download gets the standard's length code
  // whatever decode() would say.
  if (auto size = fixed_size(entry->type)) {
    if (data.size() > *size) return err(SdoAbort::LengthTooHigh);
    if (data.size() < *size) return err(SdoAbort::LengthTooLow);
  }
  Result<Value> decoded = decode(entry->type, data);
  if (!decoded) {
    const std::error_code ec = decoded.code();
    return ec.category() == sdo_abort_category() ? ec : err(SdoAbort::LengthMismatch);
  }
  Value value = std::move(decoded).value();
  if (auto ec = check_limits(value, entry->low, entry->high)) return ec;

  // Hooks run on a copy: one may replace its own registration, or replace or
  // erase the object, so the entry is looked up again afterwards.
  if (auto h = write_hooks_.find(index); h != write_hooks_.end()) {
    WriteHook hook = h->second;
    if (auto ec = hook(*entry, value)) return ec;
  } else if (auto dh = dict_write_hooks_.find(index); dh != dict_write_hooks_.end()) {
    DictWriteHook hook = dh->second;
    if (auto ec = hook(*this, *entry, value)) return ec;
  }
  entry = find(index, sub);
  if (entry != nullptr) {
    entry->value = std::move(value);
    notify(index, sub);
  }
  return {};
}

std::optional<std::size_t> ObjectDictionary::upload_size(std::uint16_t index, std::uint8_t sub) const {
  const SubEntry* entry = find(index, sub);
  if (entry == nullptr || !readable(entry->access)) return std::nullopt;
  if (read_hooks_.contains(index) || dict_read_hooks_.contains(index)) return std::nullopt;
  return encoded_size(entry->value);
}

// ---- local access ----------------------------------------------------------------

Result<Value> ObjectDictionary::get(std::uint16_t index, std::uint8_t sub) const {
  const Object* obj = find(index);
  if (obj == nullptr) return {err(SdoAbort::NoSuchObject), object_label(index, sub) + ": no such object"};
  auto it = obj->subs.find(sub);
  if (it == obj->subs.end()) return {err(SdoAbort::NoSuchSubIndex), object_label(index, sub) + ": no such sub-index"};
  return it->second.value;
}

std::error_code ObjectDictionary::set(std::uint16_t index, std::uint8_t sub, Value v) {
  SubEntry* entry = find(index, sub);
  if (entry == nullptr) return err(find(index) == nullptr ? SdoAbort::NoSuchObject : SdoAbort::NoSuchSubIndex);
  if (v.type != entry->type || !holds_its_type(v)) return err(SdoAbort::LengthMismatch);
  entry->value = std::move(v);
  notify(index, sub);
  return {};
}

void ObjectDictionary::observe(std::uint16_t index, Observer observer) {
  observers_.emplace(index, std::move(observer));
}

void ObjectDictionary::notify(std::uint16_t index, std::uint8_t sub) const {
  auto [first, last] = observers_.equal_range(index);
  for (auto it = first; it != last; ++it) it->second(sub);
}

std::optional<std::uint64_t> ObjectDictionary::get_unsigned(std::uint16_t index, std::uint8_t sub) const {
  const SubEntry* entry = find(index, sub);
  if (entry == nullptr) return std::nullopt;
  if (const auto* u = std::get_if<std::uint64_t>(&entry->value.data)) return *u;
  if (const auto* b = std::get_if<bool>(&entry->value.data)) return *b ? 1U : 0U;
  return std::nullopt;
}

void ObjectDictionary::on_read(std::uint16_t index, ReadHook hook) {
  dict_read_hooks_.erase(index);
  if (hook) {
    read_hooks_[index] = std::move(hook);
  } else {
    read_hooks_.erase(index);
  }
}

void ObjectDictionary::on_write(std::uint16_t index, WriteHook hook) {
  dict_write_hooks_.erase(index);
  if (hook) {
    write_hooks_[index] = std::move(hook);
  } else {
    write_hooks_.erase(index);
  }
}

void ObjectDictionary::on_dict_read(std::uint16_t index, DictReadHook hook) {
  read_hooks_.erase(index);
  if (hook) {
    dict_read_hooks_[index] = std::move(hook);
  } else {
    dict_read_hooks_.erase(index);
  }
}

void ObjectDictionary::on_dict_write(std::uint16_t index, DictWriteHook hook) {
  write_hooks_.erase(index);
  if (hook) {
    dict_write_hooks_[index] = std::move(hook);
  } else {
    dict_write_hooks_.erase(index);
  }
}

// ---- builders ----------------------------------------------------------------

Object make_var(std::uint16_t index, std::string name, DataType type, Access access, Value value,
                bool pdo_mappable) {
  assert(value.type == type && "make_var: value of another type");
  Object obj;
  obj.index = index;
  obj.code = ObjectCode::Var;
  SubEntry e;
  e.sub = 0;
  e.name = name;
  e.type = type;
  e.access = access;
  e.pdo_mappable = pdo_mappable;
  e.default_value = value;
  e.value = std::move(value);
  obj.name = std::move(name);
  obj.subs.emplace(std::uint8_t{0}, std::move(e));
  return obj;
}

Object make_array(std::uint16_t index, std::string name, DataType type, Access access, std::uint8_t count,
                  Access sub0_access) {
  Object obj;
  obj.index = index;
  obj.code = ObjectCode::Array;
  SubEntry s0;
  s0.sub = 0;
  s0.name = "Highest sub-index supported";
  s0.type = DataType::Unsigned8;
  s0.access = sub0_access;
  s0.value = Value::of_unsigned(DataType::Unsigned8, count);
  s0.default_value = s0.value;
  obj.subs.emplace(std::uint8_t{0}, std::move(s0));
  for (unsigned i = 1; i <= count; ++i) {
    SubEntry e;
    e.sub = static_cast<std::uint8_t>(i);
    e.name = name + " " + std::to_string(i);
    e.type = type;
    e.access = access;
    e.value = Value::zero(type);
    e.default_value = e.value;
    obj.subs.emplace(e.sub, std::move(e));
  }
  obj.name = std::move(name);
  return obj;
}

}  // namespace canopen::od
