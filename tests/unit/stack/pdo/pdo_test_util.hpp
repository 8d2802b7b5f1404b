// Builders for PDO test dictionaries.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"

namespace canopen::pdo::test {

inline od::SubEntry entry(std::uint8_t sub, std::string name, DataType t, Value v) {
  od::SubEntry e;
  e.sub = sub;
  e.name = std::move(name);
  e.type = t;
  e.access = od::Access::ReadWrite;
  e.pdo_mappable = true;
  e.value = std::move(v);
  return e;
}

inline void add_comm(od::ObjectDictionary& d, Direction dir, std::uint16_t n, std::uint32_t cob,
                     std::uint8_t type = 255, std::uint16_t inhibit = 0, std::uint16_t timer = 0,
                     std::uint8_t sync_start = 0) {
  od::Object o;
  o.index = comm_index(dir, n);
  o.name = "comm";
  o.code = od::ObjectCode::Record;
  o.subs[0] = entry(0, "Highest sub-index supported", DataType::Unsigned8, Value::of_unsigned(DataType::Unsigned8, 6));
  o.subs[1] = entry(1, "COB-ID", DataType::Unsigned32, Value::of_unsigned(DataType::Unsigned32, cob));
  o.subs[2] = entry(2, "Transmission type", DataType::Unsigned8, Value::of_unsigned(DataType::Unsigned8, type));
  o.subs[3] = entry(3, "Inhibit time", DataType::Unsigned16, Value::of_unsigned(DataType::Unsigned16, inhibit));
  o.subs[5] = entry(5, "Event timer", DataType::Unsigned16, Value::of_unsigned(DataType::Unsigned16, timer));
  o.subs[6] = entry(6, "SYNC start value", DataType::Unsigned8, Value::of_unsigned(DataType::Unsigned8, sync_start));
  d.insert(std::move(o));
}

// count overrides sub 0 (FEh / FFh for MPDOs).
inline void add_map(od::ObjectDictionary& d, Direction dir, std::uint16_t n, const std::vector<std::uint32_t>& entries,
                    int count = -1) {
  od::Object o;
  o.index = mapping_index(dir, n);
  o.name = "mapping";
  o.code = od::ObjectCode::Record;
  const auto c = static_cast<std::uint64_t>(count < 0 ? static_cast<int>(entries.size()) : count);
  o.subs[0] = entry(0, "Number of mapped objects", DataType::Unsigned8, Value::of_unsigned(DataType::Unsigned8, c));
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const auto s = static_cast<std::uint8_t>(i + 1);
    o.subs[s] = entry(s, "Mapped object", DataType::Unsigned32, Value::of_unsigned(DataType::Unsigned32, entries[i]));
  }
  d.insert(std::move(o));
}

inline void add_var(od::ObjectDictionary& d, std::uint16_t index, std::string name, DataType t) {
  d.insert(od::make_var(index, std::move(name), t, od::Access::ReadWrite, Value::zero(t), true));
}

inline std::string text(const can::Frame& f) { return can::to_string(f); }

}  // namespace canopen::pdo::test
