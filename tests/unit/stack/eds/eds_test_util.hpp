// Helpers shared by the EDS/DCF reader tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

#include "canopen/eds/eds.hpp"

namespace canopen::eds::test {

inline std::filesystem::path source_dir() { return CANOPEN_SOURCE_DIR; }
inline std::filesystem::path deploy_eds(std::string_view name) { return source_dir() / "deploy" / "eds" / name; }
inline std::filesystem::path test_data(std::string_view name) {
  return source_dir() / "tests" / "support" / "eds" / name;
}

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// 1-based number of the first line containing `needle` at or after the first
// line containing `after` (0 if none), so tests name lines by content.
inline std::size_t line_of(std::string_view text, std::string_view needle, std::string_view after = {}) {
  std::size_t line = 1;
  bool armed = after.empty();
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto nl = text.find('\n', pos);
    const auto l = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    if (!armed && l.find(after) != std::string_view::npos) armed = true;
    if (armed && l.find(needle) != std::string_view::npos) return line;
    if (nl == std::string_view::npos) break;
    pos = nl + 1;
    ++line;
  }
  return 0;
}

// A valid file: [FileInfo], [DeviceInfo], 1000h as the only mandatory object,
// `optional` listed in [OptionalObjects], then `body`.
inline std::string file_with(std::string_view body, std::initializer_list<std::uint16_t> optional = {}) {
  std::string s =
      "[FileInfo]\n"
      "FileName=test.eds\n"
      "[DeviceInfo]\n"
      "VendorName=Test\n"
      "[MandatoryObjects]\n"
      "SupportedObjects=1\n"
      "1=0x1000\n"
      "[1000]\n"
      "ParameterName=Device type\n"
      "ObjectType=0x7\n"
      "DataType=0x0007\n"
      "AccessType=ro\n"
      "DefaultValue=0x00000191\n"
      "PDOMapping=0\n";
  if (optional.size() != 0) {
    s += "[OptionalObjects]\nSupportedObjects=" + std::to_string(optional.size()) + "\n";
    int n = 1;
    for (auto idx : optional) {
      char buf[16];
      std::snprintf(buf, sizeof buf, "0x%04X", static_cast<unsigned>(idx));
      s += std::to_string(n++) + "=" + buf + "\n";
    }
  }
  s += body;
  return s;
}

inline DeviceDescription parse(std::string_view text, std::optional<std::uint8_t> node_id = {},
                               std::string name = "test.eds") {
  return parse_device_description(text, std::move(name), node_id);
}

// The EdsError parsing `text` throws; a test failure if it does not throw.
inline EdsError parse_error(std::string_view text, std::optional<std::uint8_t> node_id = {},
                            std::string name = "test.eds") {
  try {
    (void)parse_device_description(text, std::move(name), node_id);
  } catch (const EdsError& e) {
    return e;
  }
  ADD_FAILURE() << "expected an EdsError";
  return EdsError("", 0, "");
}

inline bool has_warning(const DeviceDescription& d, std::string_view part) {
  for (const auto& w : d.warnings) {
    if (w.find(part) != std::string::npos) return true;
  }
  return false;
}

inline std::uint64_t u(const Value& v) { return std::get<std::uint64_t>(v.data); }
inline std::int64_t i(const Value& v) { return std::get<std::int64_t>(v.data); }

}  // namespace canopen::eds::test
