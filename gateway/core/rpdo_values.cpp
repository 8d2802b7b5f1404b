#include "core/rpdo_values.hpp"

#include "canopen/literal.hpp"
#include "core/format.hpp"

namespace gateway::core {

std::optional<RpdoBody> typed_rpdo_values(const RpdoWrite& write, const canopen::pdo::PdoConfig& pdo,
                                          const canopen::od::ObjectDictionary& od, std::string_view what,
                                          std::string& error) {
  auto fail = [&](std::string detail) -> std::optional<RpdoBody> {
    error = std::move(detail);
    return std::nullopt;
  };
  if (!write.invalid.empty()) return fail(write.invalid);
  RpdoBody out;
  if (write.raw) {
    if (write.raw->size() != pdo.byte_length())
      return fail(std::string(what) + " carries " + std::to_string(pdo.byte_length()) + " bytes, not " +
                  std::to_string(write.raw->size()));
    out.raw = write.raw;
    return out;
  }
  for (const auto& item : write.values) {
    if (!item.invalid.empty()) return fail(item.invalid);
    const canopen::pdo::MappingEntry* entry = nullptr;
    for (const auto& e : pdo.entries)
      if (!e.dummy && e.index == item.index && e.sub == item.sub) entry = &e;
    const std::string obj = canopen::od::object_label(item.index, item.sub);
    if (entry == nullptr) return fail(std::string(what) + " does not map " + obj);
    // Type and limit errors name the type themselves: "6040h sub 0: 70000 is above 65535 (u16)".
    canopen::Result<canopen::Value> v = canopen::Error{};
    if (const auto* typed = std::get_if<canopen::Value>(&item.value)) {
      if (typed->type != entry->type)
        return fail(obj + ": a " + std::string(canopen::cia309_name(typed->type)) + " value for an object " + std::string(what) +
                    " maps as " + std::string(canopen::cia309_name(entry->type)));
      v = *typed;
    } else {
      v = canopen::value_from_literal(entry->type, std::get<canopen::Literal>(item.value));
    }
    if (!v) return fail(obj + ": " + v.error().detail);
    if (const auto* se = od.find(item.index, item.sub)) {
      std::string detail;
      if (canopen::check_limits(*v, se->low, se->high, &detail)) return fail(obj + ": " + detail);
    }
    out.values.push_back(canopen::MappedValue{item.index, item.sub, entry->name, std::move(*v)});
  }
  return out;
}

}  // namespace gateway::core
