// Internal to canopen_eds: the INI layer of CiA 306 files (sections, keys,
// comments, line numbers) and the diagnostics collector. Not installed.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace canopen::eds::detail {

// Collects warnings and throws EdsError, both prefixed "file:line: ".
class Diagnostics {
 public:
  explicit Diagnostics(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void fail(std::size_t line, std::string reason) const;
  void warn(std::size_t line, std::string_view text);
  const std::string& file() const { return file_; }
  std::vector<std::string> take_warnings() { return std::move(warnings_); }
  const std::string& warnings_back() const { return warnings_.back(); }  // the latest warn(); after one only

 private:
  std::string file_;
  std::vector<std::string> warnings_;
};

struct IniEntry {
  std::string key;    // as written
  std::string lkey;   // lower case, for lookups
  std::string value;  // trimmed; may be empty
  std::size_t line = 0;
};

struct IniSection {
  std::string name;               // as written at its first header
  std::string lname;              // lower case
  std::size_t line = 0;           // line of its first header
  std::vector<IniEntry> entries;  // file order, one per key (case-insensitive)

  const IniEntry* find(std::string_view lkey) const;
  IniEntry* find(std::string_view lkey);
};

struct IniFile {
  std::vector<IniSection> sections;  // file order; repeated headers merged
};

// Splits the text into sections and keys; lines end with LF, CR LF or CR.
// Strips a UTF-8 BOM, surrounding whitespace and ';' comment lines. Throws
// (through diag) on a malformed header, a line without '=' outside any
// section, a key outside any section or a key repeated with another value
// (except in the object lists, is_object_list()); warns on a repeated
// section header, a key repeated with the same value or once empty and
// once not (the value wins), a line without '=' in a section (ignored),
// CR-only line ends, '#' comment lines, and text that is not UTF-8 (then
// read as Latin-1, so every value is UTF-8).
IniFile parse_ini(std::string_view text, Diagnostics& diag);

// [MandatoryObjects], [OptionalObjects], [ManufacturerObjects] (lower case):
// a key repeated there with another value is a second object, kept as a
// second entry under the same key.
bool is_object_list(std::string_view lname);

std::string to_lower(std::string_view s);
std::string_view trim(std::string_view s);

}  // namespace canopen::eds::detail
