// The contract's JSON form of a core write's values (canopen/json_value.hpp),
// so tests state what a front end decoded as the JSON a user would send.
#pragma once

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>
#include <boost/json/value.hpp>

#include "canopen/json_value.hpp"
#include "core/request.hpp"

namespace gateway::test {

inline boost::json::value json_of(const core::WriteValue& v) {
  if (const auto* typed = std::get_if<canopen::Value>(&v)) return canopen::value_to_json(*typed);
  const auto& l = std::get<canopen::Literal>(v);
  using K = canopen::Literal::Kind;
  switch (l.kind) {
    case K::boolean: return boost::json::value(l.boolean);
    case K::int64: return boost::json::value(l.int64);
    case K::uint64: return boost::json::value(l.uint64);
    case K::real: return boost::json::value(l.real);
    case K::string: return boost::json::value(l.text);
    case K::array: return boost::json::array{};
    case K::object: return boost::json::object{};
    case K::null: break;
  }
  return nullptr;
}

// {"values": [{"index", "subIndex", "value"}...]} or {"raw": "hex"} as PUT .../rpdo/{n} takes it.
inline boost::json::value rpdo_json(const core::RpdoWrite& w) {
  boost::json::array values;
  for (const auto& item : w.values) {
    boost::json::object o;
    o["index"] = item.index;
    o["subIndex"] = item.sub;
    o["value"] = json_of(item.value);
    values.push_back(std::move(o));
  }
  boost::json::object body;
  body["values"] = std::move(values);
  return body;
}

}  // namespace gateway::test
