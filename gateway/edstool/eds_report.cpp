#include "edstool/eds_report.hpp"

#include "core/format.hpp"

#include <boost/json/array.hpp>

#include "canopen/json_value.hpp"
#include "log.hpp"

namespace gateway::edstool {

namespace json = boost::json;

namespace {

json::value optional_value(const std::optional<canopen::Value>& v) {
  if (!v) return nullptr;
  return canopen::value_to_json(*v);
}

std::string index_hex(std::uint16_t index) { return gateway::core::hex_number(index, 4); }

}  // namespace

// Lines quote the file's text: printable() keeps a control character in
// it from ending the line or driving the terminal.
std::string warning_line(const std::string& file, const std::string& warning) {
  // The reader writes "file:line: text" or "file: text" (eds.hpp).
  if (!warning.starts_with(file)) return gateway::printable(file + ": warning: " + warning);
  const auto text = warning.find(": ", file.size());
  if (text == std::string::npos) return gateway::printable(file + ": warning: " + warning.substr(file.size()));
  return gateway::printable(warning.substr(0, text) + ": warning: " + warning.substr(text + 2));
}

std::string error_line(const canopen::eds::EdsError& e) {
  std::string out = e.file();
  if (e.line() != 0) out += ":" + std::to_string(e.line());
  return gateway::printable(out + ": error: " + e.reason());
}

CheckResult check_file(const std::filesystem::path& file, std::optional<std::uint8_t> node_id) {
  CheckResult r;
  try {
    const auto d = canopen::eds::load_device_description(file, node_id, kFallbackNodeId);
    r.accepted = true;
    if (d.warnings.empty()) {
      r.lines.push_back(gateway::printable(file.string()) + ": ok");
    } else {
      r.lines.push_back(gateway::printable(file.string()) + ": ok, " + std::to_string(d.warnings.size()) +
                        (d.warnings.size() == 1 ? " warning" : " warnings"));
      for (const auto& w : d.warnings) r.lines.push_back(warning_line(file.string(), w));
    }
  } catch (const canopen::eds::EdsError& e) {
    r.lines.push_back(error_line(e));
  }
  return r;
}

json::object dictionary_json(const canopen::eds::DeviceDescription& d) {
  json::object o;
  o["vendorName"] = d.device.vendor_name;
  o["productName"] = d.device.product_name;
  o["dcf"] = d.is_dcf;
  o["objects"] = objects_json(d.od, &d);
  return o;
}

json::array objects_json(const canopen::od::ObjectDictionary& od, const canopen::eds::DeviceDescription* facts) {
  json::array objects;
  for (const auto& [index, obj] : od.objects()) {
    json::object jo;
    jo["index"] = index;
    jo["indexHex"] = index_hex(index);
    jo["name"] = obj.name;
    jo["objectCode"] = std::string(canopen::od::to_string(obj.code));
    json::array subs;
    for (const auto& [sub, e] : obj.subs) {
      json::object js;
      js["subIndex"] = sub;
      js["name"] = e.name;
      js["type"] = std::string(canopen::cia309_name(e.type));
      js["access"] = std::string(canopen::od::to_string(e.access));
      js["pdoMappable"] = e.pdo_mappable;
      js["default"] = optional_value(e.default_value);
      js["low"] = optional_value(e.low);
      js["high"] = optional_value(e.high);
      // Unit and factor as the file gives them (null: show the raw value).
      const auto f = facts != nullptr ? facts->facts(index, sub) : canopen::eds::EntryFacts{};
      js["unit"] = f.unit.empty() ? json::value(nullptr) : json::value(f.unit);
      js["factor"] = f.factor ? json::value(*f.factor) : json::value(nullptr);
      subs.push_back(std::move(js));
    }
    jo["subs"] = std::move(subs);
    objects.push_back(std::move(jo));
  }
  return objects;
}

}  // namespace gateway::edstool
