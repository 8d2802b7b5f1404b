#include "ini.hpp"

#include <algorithm>
#include <cctype>

#include "canopen/eds/eds.hpp"
#include "canopen/types.hpp"

namespace canopen::eds {

namespace {
std::string make_what(const std::string& file, std::size_t line, const std::string& reason) {
  if (line == 0) return file + ": " + reason;
  return file + ":" + std::to_string(line) + ": " + reason;
}
}  // namespace

EdsError::EdsError(std::string file, std::size_t line, std::string reason)
    : std::runtime_error(make_what(file, line, reason)),
      file_(std::move(file)),
      line_(line),
      reason_(std::move(reason)) {}

}  // namespace canopen::eds

namespace canopen::eds::detail {

void Diagnostics::fail(std::size_t line, std::string reason) const { throw EdsError(file_, line, std::move(reason)); }

void Diagnostics::warn(std::size_t line, std::string_view text) {
  std::string w = file_;
  if (line != 0) w += ":" + std::to_string(line);
  w += ": ";
  w += text;
  warnings_.push_back(std::move(w));
}

std::string to_lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); });
  return out;
}

std::string_view trim(std::string_view s) {
  constexpr std::string_view ws = " \t\r\n\f\v";
  const auto first = s.find_first_not_of(ws);
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(ws);
  return s.substr(first, last - first + 1);
}

const IniEntry* IniSection::find(std::string_view lkey) const {
  for (const auto& e : entries) {
    if (e.lkey == lkey) return &e;
  }
  return nullptr;
}

IniEntry* IniSection::find(std::string_view lkey) {
  return const_cast<IniEntry*>(static_cast<const IniSection&>(*this).find(lkey));
}

namespace {
// Long lines in messages are cut so one message stays one readable line.
std::string quote_cut(std::string_view s) {
  constexpr std::size_t max = 60;
  if (s.size() > max) return "'" + std::string(s.substr(0, max)) + "...'";
  return "'" + std::string(s) + "'";
}
}  // namespace

namespace {
// 1-based line of the first byte that is not part of valid UTF-8, 0 if none.
std::size_t first_non_utf8_line(std::string_view text) {
  std::size_t line = 1;
  std::size_t start = 0;
  while (start < text.size()) {
    const auto nl = text.find('\n', start);
    const auto end = nl == std::string_view::npos ? text.size() : nl;
    if (!is_utf8(text.substr(start, end - start))) return line;
    start = end + 1;
    ++line;
  }
  return 0;
}
}  // namespace

bool is_object_list(std::string_view lname) {
  return lname == "mandatoryobjects" || lname == "optionalobjects" || lname == "manufacturerobjects";
}

IniFile parse_ini(std::string_view text, Diagnostics& diag) {
  constexpr std::string_view bom = "\xEF\xBB\xBF";
  if (text.starts_with(bom)) text.remove_prefix(bom.size());

  // CiA 306 files are ASCII; vendors write names in Latin-1 (umlauts,
  // degree signs). Such a file is read as Latin-1 so every name is valid
  // UTF-8 for JSON and protobuf.
  std::string converted;
  if (!is_utf8(text)) {
    diag.warn(first_non_utf8_line(text), "text is not UTF-8; the file is read as Latin-1 (ISO 8859-1)");
    converted = latin1_to_utf8(text);
    text = converted;
  }

  IniFile file;
  std::size_t first_hash_comment = 0;
  std::map<std::string, std::size_t, std::less<>> by_name;  // lname -> position in file.sections
  IniSection* current = nullptr;
  std::size_t line_no = 0;
  // Lines end with LF, CR LF, or CR alone (classic Mac OS files).
  bool cr_only_warned = false;
  while (!text.empty()) {
    const auto nl = text.find_first_of("\r\n");
    const std::string_view raw = text.substr(0, nl);
    std::size_t skip = nl == std::string_view::npos ? text.size() : nl + 1;
    if (nl != std::string_view::npos && text[nl] == '\r') {
      if (nl + 1 < text.size() && text[nl + 1] == '\n') {
        ++skip;
      } else if (!cr_only_warned && nl + 1 < text.size()) {
        cr_only_warned = true;
        diag.warn(line_no + 1, "lines end with CR alone (classic Mac OS); read as line ends");
      }
    }
    text.remove_prefix(skip);
    ++line_no;

    const std::string_view line = trim(raw);
    if (line.empty() || line.front() == ';') continue;
    if (line.front() == '#') {  // not CiA 306, but unambiguous
      if (first_hash_comment == 0) {
        first_hash_comment = line_no;
        diag.warn(line_no, "'#' comment line(s) ignored (CiA 306 comments start with ';')");
      }
      continue;
    }

    if (line.front() == '[') {
      const auto close = line.find(']');
      if (close == std::string_view::npos) {
        diag.fail(line_no, "malformed section header " + quote_cut(line) + " (no closing ']')");
      }
      const std::string_view name = trim(line.substr(1, close - 1));
      if (name.empty()) diag.fail(line_no, "empty section name");
      if (name.find('[') != std::string_view::npos) diag.fail(line_no, "malformed section header " + quote_cut(line));
      if (const auto rest = trim(line.substr(close + 1)); !rest.empty()) {
        if (rest.front() != ';' && rest.front() != '#') {
          diag.fail(line_no, "text after the section header " + quote_cut(line));
        }
        diag.warn(line_no, "comment after the section header [" + std::string(name) + "] ignored");
      }
      std::string lname = to_lower(name);
      if (auto it = by_name.find(lname); it != by_name.end()) {
        current = &file.sections[it->second];
        diag.warn(line_no, "section [" + std::string(name) + "] repeated (first at line " +
                               std::to_string(current->line) + "); its keys are merged");
        continue;
      }
      by_name.emplace(lname, file.sections.size());
      file.sections.push_back(IniSection{std::string(name), std::move(lname), line_no, {}});
      current = &file.sections.back();
      continue;
    }

    const auto eq = line.find('=');
    if (eq == std::string_view::npos) {
      if (current == nullptr) diag.fail(line_no, "malformed line " + quote_cut(line) + " (no '=')");
      // A stray word in a section (a vendor's comment without ';'): no key, no value.
      diag.warn(line_no, "line " + quote_cut(line) + " in [" + current->name + "] has no '='; ignored");
      continue;
    }
    const std::string_view key = trim(line.substr(0, eq));
    const std::string_view value = trim(line.substr(eq + 1));
    if (key.empty()) diag.fail(line_no, "malformed line " + quote_cut(line) + " (no key before '=')");
    if (current == nullptr) diag.fail(line_no, "key " + quote_cut(key) + " outside any section");

    std::string lkey = to_lower(key);
    if (IniEntry* prev = current->find(lkey)) {
      // An empty value is an absent one: the key given once with a value is
      // not a conflict.
      if (prev->value.empty() != value.empty()) {
        diag.warn(line_no, "key '" + std::string(key) + "' in [" + current->name + "] given again " +
                               (value.empty() ? "empty" : "with a value") + " (first at line " +
                               std::to_string(prev->line) + "); the value " +
                               quote_cut(value.empty() ? std::string_view(prev->value) : value) + " is used");
        if (prev->value.empty()) {
          prev->value = std::string(value);
          prev->line = line_no;
        }
        continue;
      }
      if (prev->value != value && is_object_list(current->lname)) {
        // Two objects under one number (a tool that renumbered badly): the
        // list is a set of objects, so both are taken.
        diag.warn(line_no, "key '" + std::string(key) + "' in [" + current->name + "] repeated with another object " +
                               quote_cut(value) + " (first " + quote_cut(prev->value) + " at line " +
                               std::to_string(prev->line) + "); both are taken");
        current->entries.push_back(IniEntry{std::string(key), std::move(lkey), std::string(value), line_no});
        continue;
      }
      if (prev->value != value) {
        diag.fail(line_no, "key '" + std::string(key) + "' in [" + current->name +
                               "] repeated with a different value: " + quote_cut(prev->value) + " at line " +
                               std::to_string(prev->line) + ", " + quote_cut(value) + " here");
      }
      diag.warn(line_no, "key '" + std::string(key) + "' in [" + current->name +
                             "] repeated with the same value (first at line " + std::to_string(prev->line) + ")");
      continue;
    }
    current->entries.push_back(IniEntry{std::string(key), std::move(lkey), std::string(value), line_no});
  }
  return file;
}

}  // namespace canopen::eds::detail
