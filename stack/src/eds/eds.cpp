// CiA 306 semantics on top of the INI layer (ini.hpp): metadata sections,
// object lists, object and sub-object sections, CompactSubObj, $NODEID.
#include "canopen/eds/eds.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <span>
#include <sstream>
#include <tuple>
#include <utility>

#include "ini.hpp"

namespace canopen::eds {

using detail::Diagnostics;
using detail::IniEntry;
using detail::IniFile;
using detail::IniSection;
using detail::to_lower;
using detail::trim;

namespace {

std::string hex4(std::uint32_t v) {
  static constexpr std::array<char, 16> digits = {'0', '1', '2', '3', '4', '5', '6', '7',
                                                  '8', '9', 'A', 'B', 'C', 'D', 'E', 'F'};
  std::string s = "0000";
  for (int i = 3; i >= 0; --i) {
    s[static_cast<std::size_t>(i)] = digits[v & 0xF];
    v >>= 4;
  }
  return s;
}

bool is_hex_digit(char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; }
bool all_hex(std::string_view s) { return !s.empty() && std::all_of(s.begin(), s.end(), is_hex_digit); }
bool all_dec(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}
std::uint32_t hex_value(std::string_view s) {  // precondition: all_hex, at most 8 digits
  std::uint32_t v = 0;
  for (char c : s) {
    const auto lc = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    v = v * 16 + static_cast<std::uint32_t>(lc <= '9' ? lc - '0' : lc - 'a' + 10);
  }
  return v;
}

bool is_integer(DataType t) { return is_signed_integer(t) || is_unsigned_integer(t); }
bool is_numeric(DataType t) { return is_integer(t) || is_real(t) || t == DataType::Boolean; }
// Types for which an empty DefaultValue / ParameterValue means "empty", not "absent".
bool empty_is_a_value(DataType t) {
  return t == DataType::VisibleString || t == DataType::OctetString || t == DataType::UnicodeString ||
         t == DataType::Domain;
}

std::string type_text(DataType t) { return std::string(standard_name(t)); }

std::string subject(const IniSection& s) { return "[" + s.name + "]"; }

std::string invalid(const std::string& label, const std::string& text, DataType type, const std::string& detail) {
  return label + " '" + text + "' is not a valid " + type_text(type) + (detail.empty() ? "" : ": " + detail);
}

// Vendor files decorate numbers: an inline comment ("0x3ED ; prevent
// homing", "0 # No") or a C literal suffix ("0x10LL", "1U", "0.0f").
// Returns the bare number and says what was removed in *what; nullopt when
// there is nothing to remove.
std::optional<std::string> bare_number(std::string_view text, std::string* what) {
  std::string out(text);
  std::string removed;
  if (const auto c = out.find_first_of(";#"); c != std::string::npos && c > 0) {
    out = std::string(trim(std::string_view(out).substr(0, c)));
    removed = "an inline comment";
  }
  const bool hex = out.size() > 2 && out[0] == '0' && (out[1] == 'x' || out[1] == 'X');
  std::size_t keep = out.size();
  while (keep > 1 && std::string_view("uUlL").find(out[keep - 1]) != std::string_view::npos) --keep;
  if (keep == out.size() && !hex && keep > 1 && (out.back() == 'f' || out.back() == 'F')) --keep;
  if (keep < out.size() && keep > 0 && std::isxdigit(static_cast<unsigned char>(out[keep - 1])) != 0) {
    removed += std::string(removed.empty() ? "" : " and ") + "the C suffix '" + out.substr(keep) + "'";
    out.resize(keep);
  }
  if (removed.empty() || out.empty()) return std::nullopt;
  if (what != nullptr) *what = removed;
  return out;
}

// Symbolic ObjectType values some tools write ("VAR" for 0x7).
std::optional<std::uint8_t> object_type_by_name(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, std::uint8_t>, 7> names = {{
      {"null", 0x0}, {"domain", 0x2}, {"deftype", 0x5}, {"defstruct", 0x6}, {"var", 0x7}, {"array", 0x8}, {"record", 0x9}}};
  const auto lower = to_lower(name);
  for (const auto& [n, code] : names) {
    if (n == lower) return code;
  }
  return std::nullopt;
}

// Thrown inside one object's reading when that object cannot be read
// without guessing (unknown AccessType, a structure type on a VAR, ...):
// the object is left out with a warning, the rest of the file is used.
struct SkipObject {
  std::size_t line;
  std::string reason;
};

// ---------------------------------------------------------------------------
// Units. CiA 306 has no key for a physical unit; vendor files write one in
// these ways, and the reader understands them (an explicit key wins over
// the name):
//  - `Unit=mV` with `Factor=0.1` (python-canopen's files; `PhysicalUnit=`
//    is read like `Unit=`): value in mV = raw x 0.1;
//  - `Unit=0.01A per unit` (Curtis/Sevcon files): the number is the factor;
//  - a unit in square brackets ending ParameterName ("Voltage UB Power
//    [mV]"): a short token only (no spaces, at most 8 characters, not an
//    array index like "LmTable[9]", no '?' left by a lost 'µ');
//  - in parentheses only a symbol from kUnitSymbols, because vendors put
//    words there ("(manufacturer specific)", "(tx)").

constexpr std::array<std::string_view, 22> kUnitSymbols = {
    "Hz", "kHz", "V", "mV", "A", "mA", "W", "kW", "\u00B0C", "degC", "K", "rpm", "%", "ms", "s", "mm", "m", "bar", "mbar",
    "Pa", "kPa", "Nm"};

std::size_t code_points(std::string_view s) {
  return static_cast<std::size_t>(std::count_if(s.begin(), s.end(), [](char c) {
    return (static_cast<unsigned char>(c) & 0xC0) != 0x80;  // not a UTF-8 continuation byte
  }));
}

// "[mV]" / "(Hz)" at the end of a ParameterName; empty if none.
std::string unit_from_name(std::string_view name) {
  name = trim(name);
  if (name.size() < 3) return {};
  const char close = name.back();
  const char open = close == ']' ? '[' : close == ')' ? '(' : '\0';
  if (open == '\0') return {};
  const auto pos = name.rfind(open);
  if (pos == std::string_view::npos) return {};
  const auto token = name.substr(pos + 1, name.size() - pos - 2);
  if (open == '(') {
    return std::find(kUnitSymbols.begin(), kUnitSymbols.end(), token) != kUnitSymbols.end() ? std::string(token)
                                                                                          : std::string{};
  }
  if (token.empty() || code_points(token) > 8 || all_dec(token)) return {};
  if (token.find_first_of(" \t?[(") != std::string_view::npos) return {};
  return std::string(token);
}

// A finite, non-zero number, the whole text; nullopt otherwise.
std::optional<double> factor_number(std::string_view text) {
  text = trim(text);
  double v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc{} || end != text.data() + text.size() || !std::isfinite(v) || v == 0) return std::nullopt;
  return v;
}

// "0.01A per unit" -> factor 0.01, unit "A"; any other text is the unit as written.
std::pair<std::string, std::optional<double>> split_unit(std::string_view text) {
  text = trim(text);
  static constexpr std::string_view kPerUnit = " per unit";
  if (text.size() > kPerUnit.size() && to_lower(text.substr(text.size() - kPerUnit.size())) == kPerUnit) {
    const auto head = trim(text.substr(0, text.size() - kPerUnit.size()));
    double v = 0;
    const auto [end, ec] = std::from_chars(head.data(), head.data() + head.size(), v);
    const auto unit = trim(head.substr(static_cast<std::size_t>(end - head.data())));
    if (ec == std::errc{} && std::isfinite(v) && v != 0 && !unit.empty()) return {std::string(unit), v};
  }
  return {std::string(text), std::nullopt};
}

// ---------------------------------------------------------------------------
// Section kinds derived from the name.

// Structure: [xxxxsubFF], the sub-index CiA 301 7.4.3 reserves for the
// object's structure (never a dictionary entry): skipped.
enum class ObjKind { Object, Sub, Name, Value, Denotation, ObjectLinks, Structure };
struct ObjRef {
  ObjKind kind = ObjKind::Object;
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
};

// Leading zeros do not count ("[01000]" is 1000h).
std::string_view significant_digits(std::string_view hex) {
  return hex.substr(std::min(hex.find_first_not_of('0'), hex.size()));
}

std::uint16_t object_index(std::string_view hex, const IniSection& s, const Diagnostics& d) {
  hex = significant_digits(hex);
  if (hex.size() > 4) d.fail(s.line, "section " + subject(s) + ": index above 0xFFFF");
  const auto index = static_cast<std::uint16_t>(hex_value(hex));
  if (index == 0) d.fail(s.line, "section " + subject(s) + ": index 0 is not an object");
  return index;
}

// nullopt: not an object-related section name.
std::optional<ObjRef> classify(const IniSection& s, const Diagnostics& d) {
  const std::string_view n = s.lname;
  static constexpr std::array<std::pair<std::string_view, ObjKind>, 4> suffixes = {{
      {"objectlinks", ObjKind::ObjectLinks},
      {"denotation", ObjKind::Denotation},
      {"value", ObjKind::Value},
      {"name", ObjKind::Name},
  }};
  for (const auto& [suffix, kind] : suffixes) {
    if (n.size() > suffix.size() && n.ends_with(suffix)) {
      const auto prefix = n.substr(0, n.size() - suffix.size());
      if (all_hex(prefix)) return ObjRef{kind, object_index(prefix, s, d), 0};
    }
  }
  if (const auto pos = n.find("sub"); pos != std::string_view::npos && pos > 0 && all_hex(n.substr(0, pos))) {
    const auto index = object_index(n.substr(0, pos), s, d);
    const auto sub = n.substr(pos + 3);
    if (!all_hex(sub)) d.fail(s.line, "malformed sub-object section name " + subject(s));
    const auto digits = significant_digits(sub);
    if (digits.size() > 2) d.fail(s.line, "section " + subject(s) + ": sub-index above 0xFF");
    if (hex_value(digits) == 0xFF) return ObjRef{ObjKind::Structure, index, 0xFF};
    return ObjRef{ObjKind::Sub, index, static_cast<std::uint8_t>(hex_value(digits))};
  }
  if (all_hex(n)) return ObjRef{ObjKind::Object, object_index(n, s, d), 0};
  return std::nullopt;
}

struct ObjSections {
  const IniSection* main = nullptr;
  std::map<std::uint8_t, const IniSection*> subs;
  const IniSection* names = nullptr;
  const IniSection* values = nullptr;
  const IniSection* links = nullptr;
};

// One value-bearing key (DefaultValue, ParameterValue, LowLimit, ...).
struct Parsed {
  std::optional<Value> value;
  const IniEntry* entry = nullptr;
  std::string label;           // how messages name it: the key, or "[xxxxValue] entry n"
  bool needs_node_id = false;  // uses $NODEID and no node-ID is known
};

// What a section says about one sub-entry (or about all of a compact object's).
struct Template {
  std::string name;
  DataType type = DataType::Unsigned8;
  od::Access access = od::Access::ReadOnly;
  bool pdo_mappable = false;
  std::optional<Value> low, high;
  Parsed def, param;
  std::uint32_t obj_flags = 0;
  std::string unit;  // from Unit= / PhysicalUnit=; empty: taken from the entry's name, if any
  std::optional<double> factor;
};

constexpr std::array<std::string_view, 18> kObjectKeys = {
    "parametername", "objecttype",     "datatype",   "accesstype", "defaultvalue", "pdomapping",
    "subnumber",     "lowlimit",       "highlimit",  "objflags",   "compactsubobj", "parametervalue",
    "denotation",    "uploadfile",     "downloadfile", "unit",     "physicalunit", "factor"};
constexpr std::array<std::string_view, 16> kSubKeys = {
    "parametername", "objecttype", "datatype",       "accesstype", "defaultvalue", "pdomapping",
    "lowlimit",      "highlimit",  "objflags",       "parametervalue", "denotation", "uploadfile",
    "downloadfile",  "unit",       "physicalunit",   "factor"};

// ---------------------------------------------------------------------------

class Builder {
 public:
  Builder(Diagnostics& diag, const IniFile& ini, const std::string& file_name, std::optional<std::uint8_t> node_id,
          std::optional<std::uint8_t> fallback_node_id)
      : d_(diag), ini_(ini), node_id_arg_(node_id), fallback_node_id_(fallback_node_id) {
    const auto lname = to_lower(file_name);
    out_.is_dcf = lname.ends_with(".dcf");
  }

  DeviceDescription run();

 private:
  // -- values --
  std::uint64_t number(const IniEntry& e, DataType t);
  bool flag(const IniEntry& e);
  std::uint16_t data_type_code(const IniEntry& e);
  std::uint8_t object_type_code(const IniEntry& e);
  // parse_value() plus the repairs for what vendor files write (bare_number,
  // two's complement hex for signed types, 0x0/0x1 for BOOLEAN, a REAL's bit
  // pattern in hex, a DOMAIN default that is not hex); each repair warns.
  Result<Value> parse_lenient(const IniEntry& e, std::string_view text, DataType type, const std::string& label);
  // Warns once per file for a quirk that repeats on every object.
  void warn_once(const std::string& kind, std::size_t line, const std::string& text);
  // leave_out_bad: a value that cannot be read is a warning and no value
  // (left_out()); else an EdsError.
  Parsed parse_object_value(const IniEntry* e, DataType type, std::string label = {}, bool leave_out_bad = false);
  Parsed left_out(Parsed p, const std::string& why);
  Value resolve_node_id(const IniEntry& e, const std::string& label, DataType type) const;

  // -- sections --
  void warn_unknown_keys(const IniSection& s, std::span<const std::string_view> known);
  void read_file_info(const IniSection& s);
  void read_device_info(const IniSection& s);
  void read_commissioning(const IniSection& s);
  void read_dummy_usage(const IniSection& s);
  void read_comments(const IniSection& s);
  std::vector<std::uint16_t> read_list(const IniSection& s);

  // -- objects --
  void collect_object_sections();
  void build_object(std::uint16_t index, const ObjSections& secs);  // skips (with a warning) what read_object cannot read
  void read_object(std::uint16_t index, const ObjSections& secs);
  Template read_template(const IniSection& s, bool domain_defaults);
  std::uint32_t obj_flags(const IniSection& s);
  void read_unit(const IniSection& s, Template& t);
  od::SubEntry finish(const Template& t, std::uint8_t sub, const Parsed* override_value);
  void check_in_limits(const Template& t, const Parsed& p) const;
  // [xxxxName] / [xxxxValue]: numbered entries 1..count.
  std::map<std::uint8_t, const IniEntry*> numbered(const IniSection& s, std::uint8_t count);

  Diagnostics& d_;
  const IniFile& ini_;
  std::optional<std::uint8_t> node_id_arg_;
  std::optional<std::uint8_t> fallback_node_id_;
  DeviceDescription out_;
  std::map<std::uint16_t, ObjSections> objs_;
  std::map<std::uint16_t, std::size_t> listed_;  // index -> line of its first list entry
  bool warned_param_in_eds_ = false;
  std::uint16_t cur_index_ = 0;  // the object read_object() is building (for entry_facts)
  std::set<std::string> warned_kinds_;
};

void Builder::warn_once(const std::string& kind, std::size_t line, const std::string& text) {
  if (!warned_kinds_.insert(kind).second) return;
  d_.warn(line, text + " (reported once per file)");
}

std::uint64_t Builder::number(const IniEntry& e, DataType t) {
  const auto r = parse_lenient(e, e.value, t, e.key);
  if (!r) d_.fail(e.line, invalid(e.key, e.value, t, r.error().detail));
  if (t == DataType::Boolean) return std::get<bool>(r->data) ? 1 : 0;
  return std::get<std::uint64_t>(r->data);
}

// 0/1 keys (PDOMapping, BaudRate_500, ...); some tools write them in hex.
bool Builder::flag(const IniEntry& e) {
  if (auto r = parse_value(DataType::Boolean, e.value)) return std::get<bool>(r->data);
  auto r = parse_value(DataType::Unsigned8, e.value);
  if (!r) {
    if (auto bare = bare_number(e.value, nullptr)) r = parse_value(DataType::Unsigned8, *bare);
  }
  if (!r || std::get<std::uint64_t>(r->data) > 1) d_.fail(e.line, e.key + "=" + e.value + ": expected 0 or 1");
  warn_once("flag:" + e.lkey, e.line, e.key + "=" + e.value + " read as " + std::to_string(std::get<std::uint64_t>(r->data)));
  return std::get<std::uint64_t>(r->data) == 1;
}

std::uint16_t Builder::data_type_code(const IniEntry& e) {
  if (!parse_value(DataType::Unsigned16, e.value)) {
    if (const auto t = parse_type_name(e.value)) {
      warn_once("symbolic-datatype", e.line,
                "DataType=" + e.value + " read as 0x" + hex4(static_cast<std::uint16_t>(*t)));
      return static_cast<std::uint16_t>(*t);
    }
  }
  return static_cast<std::uint16_t>(number(e, DataType::Unsigned16));
}

std::uint8_t Builder::object_type_code(const IniEntry& e) {
  if (const auto code = object_type_by_name(e.value)) {
    warn_once("symbolic-objecttype", e.line, "ObjectType=" + e.value + " read as 0x" + hex4(*code).substr(3));
    return *code;
  }
  return static_cast<std::uint8_t>(number(e, DataType::Unsigned8));
}

// "$NODEID", "$NODEID+0x180", "0x180+$NODEID" (CiA 306): a sum with exactly
// one $NODEID term, checked against the type's range.
Value Builder::resolve_node_id(const IniEntry& e, const std::string& label, DataType type) const {
  std::uint64_t sum = 0;
  int node_terms = 0;
  std::string_view rest = e.value;
  while (true) {
    const auto plus = rest.find('+');
    const auto term = trim(rest.substr(0, plus));
    std::uint64_t v = 0;
    if (to_lower(term) == "$nodeid") {
      ++node_terms;
      v = *out_.node_id;
    } else {
      if (term.empty() || term.find('$') != std::string_view::npos) {
        d_.fail(e.line, label + " '" + e.value + "': malformed $NODEID expression (expected $NODEID+number)");
      }
      auto r = parse_value(DataType::Unsigned64, term);
      if (!r) d_.fail(e.line, label + " '" + e.value + "': " + r.error().detail);
      v = std::get<std::uint64_t>(r->data);
    }
    if (v > std::numeric_limits<std::uint64_t>::max() - sum) d_.fail(e.line, label + " '" + e.value + "' overflows");
    sum += v;
    if (plus == std::string_view::npos) break;
    rest.remove_prefix(plus + 1);
  }
  if (node_terms != 1) d_.fail(e.line, label + " '" + e.value + "': malformed $NODEID expression (one $NODEID term)");
  auto r = parse_value(type, std::to_string(sum));
  if (!r) {
    d_.fail(e.line, label + " '" + e.value + "' with node-ID " + std::to_string(*out_.node_id) + " is not a valid " +
                        type_text(type) + ": " + r.error().detail);
  }
  return std::move(r).value();
}

Parsed Builder::parse_object_value(const IniEntry* e, DataType type, std::string label, bool leave_out_bad) {
  Parsed p;
  p.entry = e;
  if (e == nullptr) return p;
  p.label = label.empty() ? e->key : std::move(label);
  if (e->value.empty()) {
    if (empty_is_a_value(type)) {
      p.value = Value::zero(type);
    } else {
      p.entry = nullptr;  // an empty optional key is an absent one
    }
    return p;
  }
  // In a string '$' is text; in a number it can only be $NODEID.
  if (e->value.find('$') != std::string::npos && !empty_is_a_value(type)) {
    if (!is_integer(type)) {
      if (leave_out_bad) return left_out(p, "$NODEID in a value of type " + type_text(type));
      d_.fail(e->line, p.label + " '" + e->value + "': $NODEID in a value of type " + type_text(type));
    }
    if (!out_.node_id) {
      p.needs_node_id = true;
      return p;
    }
    p.value = resolve_node_id(*e, p.label, type);
    return p;
  }
  auto r = parse_lenient(*e, e->value, type, p.label);
  if (!r && leave_out_bad) return left_out(p, "not a valid " + type_text(type) + ": " + r.error().detail);
  if (!r) d_.fail(e->line, invalid(p.label, e->value, type, r.error().detail));
  p.value = std::move(r).value();
  return p;
}

// A value nobody can read without guessing (a fraction on an integer, out
// of the type's range, a typo, a vendor tool's placeholder): the rest of the
// file is still good, so the entry goes on without it.
Parsed Builder::left_out(Parsed p, const std::string& why) {
  const std::string what = to_lower(p.label) == "defaultvalue" ? "no default"
                                                               : "no value (in a DCF: not written at boot)";
  const std::string text = p.label + " '" + p.entry->value + "' left out (" + why + "); the entry has " + what;
  d_.warn(p.entry->line, text);
  out_.values_left_out.push_back(d_.warnings_back());
  p.entry = nullptr;
  p.value.reset();
  return p;
}

Result<Value> Builder::parse_lenient(const IniEntry& e, std::string_view text, DataType type, const std::string& label) {
  auto r = parse_value(type, text);
  if (r) return r;
  const std::string quoted = label + " '" + std::string(text) + "'";
  if (is_numeric(type)) {
    std::string what;
    if (auto bare = bare_number(text, &what)) {
      auto again = parse_lenient(e, *bare, type, label);
      if (again) {
        warn_once("bare:" + e.lkey, e.line, quoted + ": " + what + " ignored");
        return again;
      }
    }
  }
  // TIME_OF_DAY / TIME_DIFFERENCE as one number: ms after midnight of day 0
  // (DefaultValue=0 is the usual way to say "zero").
  if (type == DataType::TimeOfDay || type == DataType::TimeDifference) {
    if (auto ms = parse_value(DataType::Unsigned32, text); ms && std::get<std::uint64_t>(ms->data) < 86'400'000)
      return Value{type, TimeOfDay{static_cast<std::uint32_t>(std::get<std::uint64_t>(ms->data)), 0}};
  }
  const auto lower = to_lower(text);
  const bool hex = lower.starts_with("0x");
  // A signed type's bit pattern in hex (LowLimit=0x80000000 for INTEGER32,
  // INTEGER8 0xFF for -1): unambiguous, read as two's complement.
  if (is_signed_integer(type) && hex && r.code() == make_error_code(SdoAbort::ValueTooHigh)) {
    if (auto u = parse_value(DataType::Unsigned64, text)) {
      const auto bits = std::get<std::uint64_t>(u->data);
      const auto smax = static_cast<std::uint64_t>(signed_max(type));
      if (bits <= smax * 2 + 1) {
        const auto v = static_cast<std::int64_t>(bits - smax - 1) + signed_min(type);
        d_.warn(e.line, quoted + " read as two's complement " + std::to_string(v) + " (" + type_text(type) + ")");
        return Value::of_signed(type, v);
      }
    }
  }
  // BOOLEAN written as a number (0x00, 0x01).
  if (type == DataType::Boolean) {
    if (auto u = parse_value(DataType::Unsigned8, text); u && std::get<std::uint64_t>(u->data) <= 1) {
      warn_once("bool:" + e.lkey, e.line, quoted + " read as BOOLEAN " + std::to_string(std::get<std::uint64_t>(u->data)));
      return Value::of_bool(std::get<std::uint64_t>(u->data) == 1);
    }
  }
  // A REAL's IEEE 754 bit pattern in hex (0x40490FDB is 3.14159274f).
  if (is_real(type) && hex) {
    const auto bits_type = type == DataType::Real32 ? DataType::Unsigned32 : DataType::Unsigned64;
    if (auto u = parse_value(bits_type, text)) {
      auto v = decode(type, encode(*u));
      if (v) {
        d_.warn(e.line, quoted + " read as the bit pattern of " + format_value(*v) + " (" + type_text(type) + ")");
        return v;
      }
    }
  }
  // A DOMAIN's default that is no hex data ("0", "NULL", "@ABCD", a file
  // name): a DOMAIN is data the device makes; it starts empty.
  if (type == DataType::Domain) {
    d_.warn(e.line, quoted + " is not hex data; the DOMAIN starts empty");
    return Value::zero(type);
  }
  return r;
}

void Builder::warn_unknown_keys(const IniSection& s, std::span<const std::string_view> known) {
  for (const auto& e : s.entries) {
    if (std::find(known.begin(), known.end(), e.lkey) == known.end()) {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
    }
  }
}

// ---------------------------------------------------------------------------
// Metadata sections.

void Builder::read_file_info(const IniSection& s) {
  const std::array<std::pair<std::string_view, std::string*>, 12> keys = {{
      {"filename", &out_.file.file_name},
      {"fileversion", &out_.file.file_version},
      {"filerevision", &out_.file.file_revision},
      {"edsversion", &out_.file.eds_version},
      {"description", &out_.file.description},
      {"creationtime", &out_.file.creation_time},
      {"creationdate", &out_.file.creation_date},
      {"createdby", &out_.file.created_by},
      {"modificationtime", &out_.file.modification_time},
      {"modificationdate", &out_.file.modification_date},
      {"modifiedby", &out_.file.modified_by},
      {"lasteds", &out_.file.last_eds},
  }};
  for (const auto& e : s.entries) {
    const auto it = std::find_if(keys.begin(), keys.end(), [&](const auto& k) { return k.first == e.lkey; });
    if (it == keys.end()) {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
    } else {
      *it->second = e.value;
    }
  }
  // Informative only (nothing here depends on it); tools write "402", "4", "3".
  if (const auto* v = s.find("edsversion"); v != nullptr && v->value != "4.0" && v->value != "3.0") {
    d_.warn(v->line, "EDSVersion=" + v->value + " is not a CiA 306 version (4.0); read as a 4.0 file");
  }
}

void Builder::read_device_info(const IniSection& s) {
  auto& dev = out_.device;
  static constexpr std::array<unsigned, 8> rates = {10, 20, 50, 125, 250, 500, 800, 1000};
  for (const auto& e : s.entries) {
    const auto& k = e.lkey;
    if (k == "vendorname") {
      dev.vendor_name = e.value;
    } else if (k == "productname") {
      dev.product_name = e.value;
    } else if (k == "ordercode") {
      dev.order_code = e.value;
    } else if (e.value.empty()) {
      continue;  // numbers and flags are optional
    } else if (k == "vendornumber") {
      dev.vendor_number = static_cast<std::uint32_t>(number(e, DataType::Unsigned32));
    } else if (k == "productnumber") {
      dev.product_number = static_cast<std::uint32_t>(number(e, DataType::Unsigned32));
    } else if (k == "revisionnumber") {
      dev.revision_number = static_cast<std::uint32_t>(number(e, DataType::Unsigned32));
    } else if (k.starts_with("baudrate_")) {
      const auto rate = std::string_view(k).substr(9);
      const auto it = std::find_if(rates.begin(), rates.end(), [&](unsigned r) { return std::to_string(r) == rate; });
      if (it == rates.end()) {
        d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
      } else if (flag(e)) {
        dev.baud_rates_kbit.push_back(*it);
      }
    } else if (k == "simplebootupmaster") {
      dev.simple_boot_up_master = flag(e);
    } else if (k == "simplebootupslave") {
      dev.simple_boot_up_slave = flag(e);
    } else if (k == "granularity") {
      dev.granularity = static_cast<std::uint8_t>(number(e, DataType::Unsigned8));
      if (dev.granularity > 64) d_.fail(e.line, "Granularity " + e.value + " is above 64");
    } else if (k == "dynamicchannelssupported") {
      dev.dynamic_channels_supported = static_cast<std::uint8_t>(number(e, DataType::Unsigned8));
    } else if (k == "groupmessaging") {
      dev.group_messaging = flag(e);
    } else if (k == "nrofrxpdo") {
      dev.nr_of_rx_pdo = static_cast<std::uint16_t>(number(e, DataType::Unsigned16));
    } else if (k == "nroftxpdo") {
      dev.nr_of_tx_pdo = static_cast<std::uint16_t>(number(e, DataType::Unsigned16));
    } else if (k == "lss_supported") {
      dev.lss_supported = flag(e);
    } else if (k == "compactpdo") {
      dev.compact_pdo = static_cast<std::uint8_t>(number(e, DataType::Unsigned8));
    } else if (k == "canopensafetysupported") {
      dev.canopen_safety_supported = flag(e);
    } else {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
    }
  }
  std::sort(dev.baud_rates_kbit.begin(), dev.baud_rates_kbit.end());
}

void Builder::read_commissioning(const IniSection& s) {
  Commissioning c;
  for (const auto& e : s.entries) {
    const auto& k = e.lkey;
    if (k == "nodename") {
      c.node_name = e.value;
    } else if (k == "networkname") {
      c.network_name = e.value;
    } else if (e.value.empty()) {
      continue;
    } else if (k == "nodeid") {
      // 0 and FFh (unconfigured, LSS) appear in DCFs whose node-ID the
      // configuration gives; only $NODEID values need one.
      const auto id = number(e, DataType::Unsigned8);
      if (id < 1 || id > 127) {
        d_.warn(e.line, "NodeID " + e.value + " is not a node-ID 1..127; ignored (the configured node-ID is used)");
      } else {
        c.node_id = static_cast<std::uint8_t>(id);
      }
    } else if (k == "baudrate") {
      c.baud_rate_kbit = static_cast<std::uint16_t>(number(e, DataType::Unsigned16));
    } else if (k == "netnumber") {
      c.net_number = static_cast<std::uint32_t>(number(e, DataType::Unsigned32));
    } else if (k == "canopenmanager") {
      c.canopen_manager = flag(e);
    } else if (k == "lss_serialnumber") {
      c.lss_serial_number = static_cast<std::uint32_t>(number(e, DataType::Unsigned32));
    } else {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
    }
  }
  out_.commissioning = c;
}

void Builder::read_dummy_usage(const IniSection& s) {
  std::set<std::uint16_t> used;
  for (const auto& e : s.entries) {
    const std::string_view k = e.lkey;
    if (!k.starts_with("dummy") || !all_hex(k.substr(5)) || k.size() > 9) {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
      continue;
    }
    if (e.value.empty()) continue;
    if (flag(e)) used.insert(static_cast<std::uint16_t>(hex_value(k.substr(5))));
  }
  out_.dummy_usage.assign(used.begin(), used.end());
}

void Builder::read_comments(const IniSection& s) {
  std::map<std::uint64_t, std::string> lines;
  const IniEntry* count = nullptr;
  for (const auto& e : s.entries) {
    const std::string_view k = e.lkey;
    if (k == "lines") {
      count = &e;
    } else if (k.starts_with("line") && all_dec(k.substr(4)) && k.size() < 10) {
      lines[std::stoull(std::string(k.substr(4)))] = e.value;
    } else {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
    }
  }
  if (count != nullptr && !count->value.empty() && number(*count, DataType::Unsigned16) != lines.size()) {
    d_.warn(count->line, "Lines=" + count->value + " but " + std::to_string(lines.size()) + " comment lines follow");
  }
  for (auto& [n, text] : lines) out_.comments.push_back(std::move(text));
}

std::vector<std::uint16_t> Builder::read_list(const IniSection& s) {
  const IniEntry* count = nullptr;
  // entry number -> entry; a number given twice with two objects has both (parse_ini)
  std::multimap<std::uint64_t, const IniEntry*> entries;
  for (const auto& e : s.entries) {
    if (e.lkey == "supportedobjects") {
      count = &e;
    } else if (all_dec(e.lkey) && e.lkey.size() < 6) {
      entries.emplace(std::stoull(e.lkey), &e);
    } else {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
    }
  }
  // The entries present are the list; a count that disagrees is a slip of
  // the tool that wrote the file.
  if (count == nullptr || count->value.empty()) {
    d_.warn(s.line, subject(s) + " has no SupportedObjects; using its " + std::to_string(entries.size()) + " entries");
  } else {
    const auto n = number(*count, DataType::Unsigned16);
    std::size_t outside = 0, missing = 0;
    for (const auto& [k, e] : entries) outside += (k == 0 || k > n) ? 1 : 0;
    for (std::uint64_t k = 1; k <= n; ++k) missing += entries.contains(k) ? 0 : 1;
    if (outside != 0 || missing != 0) {
      d_.warn(count->line, "SupportedObjects=" + count->value + " but " + subject(s) + " has " +
                               std::to_string(entries.size()) + " entries (" + std::to_string(outside) +
                               " numbered above it, " + std::to_string(missing) + " numbers missing); the " +
                               std::to_string(entries.size()) + " entries are used");
    }
  }
  std::vector<std::uint16_t> list;
  for (const auto& [k, e] : entries) {
    const auto index = static_cast<std::uint16_t>(number(*e, DataType::Unsigned16));
    if (index == 0) d_.fail(e->line, "index 0 is not an object");
    if (const auto it = listed_.find(index); it != listed_.end()) {
      d_.warn(e->line, "object 0x" + hex4(index) + " listed again (first at line " + std::to_string(it->second) + ")");
      continue;
    }
    listed_.emplace(index, e->line);
    if (!objs_.contains(index) || objs_.at(index).main == nullptr) {
      d_.warn(e->line, "object 0x" + hex4(index) + " is listed in " + subject(s) + " but has no [" + hex4(index) +
                           "] section; not in the dictionary");
      continue;
    }
    list.push_back(index);
  }
  return list;
}

// ---------------------------------------------------------------------------
// Objects.

void Builder::collect_object_sections() {
  std::map<std::pair<std::uint16_t, int>, const IniSection*> seen;  // (index, sub or -kind) -> section
  for (const auto& s : ini_.sections) {
    const auto ref = classify(s, d_);
    if (!ref) continue;
    if (ref->kind == ObjKind::Structure) {
      d_.warn(s.line, "section " + subject(s) + " ignored: sub-index FFh is the object's structure (CiA 301 7.4.3), "
                                               "not an entry");
      continue;
    }
    const int slot = ref->kind == ObjKind::Sub ? ref->sub : -1 - static_cast<int>(ref->kind);
    if (const auto [it, fresh] = seen.emplace(std::pair{ref->index, slot}, &s); !fresh) {
      d_.fail(s.line, "section " + subject(s) + " describes the same thing as " + subject(*it->second) + " (line " +
                          std::to_string(it->second->line) + ")");
    }
    auto& o = objs_[ref->index];
    switch (ref->kind) {
      case ObjKind::Object:
        o.main = &s;
        break;
      case ObjKind::Sub:
        o.subs[ref->sub] = &s;
        break;
      case ObjKind::Name:
        o.names = &s;
        break;
      case ObjKind::Value:
        o.values = &s;
        break;
      case ObjKind::ObjectLinks:
        o.links = &s;
        break;
      case ObjKind::Denotation:
        break;  // DCF names for the user's tools; nothing to use here
      case ObjKind::Structure:
        break;  // skipped above
    }
  }
  for (const auto& [index, o] : objs_) {
    if (o.main != nullptr) continue;
    if (!o.subs.empty()) {
      const auto* sub = o.subs.begin()->second;
      d_.warn(sub->line, "sub-object section " + subject(*sub) + (o.subs.size() > 1 ? " and others" : "") +
                             " without an object section [" + hex4(index) + "]; ignored");
    }
    for (const auto* s : {o.names, o.values, o.links}) {
      if (s != nullptr) d_.warn(s->line, "section " + subject(*s) + " has no object section; ignored");
    }
  }
}

std::map<std::uint8_t, const IniEntry*> Builder::numbered(const IniSection& s, std::uint8_t count) {
  std::map<std::uint8_t, const IniEntry*> out;
  const IniEntry* declared = nullptr;
  for (const auto& e : s.entries) {
    if (e.lkey == "nrofentries") {
      declared = &e;
      continue;
    }
    if (!all_dec(e.lkey)) {
      d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(s) + " ignored");
      continue;
    }
    if (e.lkey.size() > 3 || std::stoul(e.lkey) == 0 || std::stoul(e.lkey) > count) {
      d_.warn(e.line, subject(s) + ": sub-index " + e.key + " is outside 1..CompactSubObj=" + std::to_string(count) +
                          "; ignored");
      continue;
    }
    out[static_cast<std::uint8_t>(std::stoul(e.lkey))] = &e;
  }
  if (declared != nullptr && !declared->value.empty() && number(*declared, DataType::Unsigned8) != out.size()) {
    d_.warn(declared->line, "NrOfEntries=" + declared->value + " but " + subject(s) + " has " +
                                std::to_string(out.size()) + " entries; those are used");
  }
  return out;
}

// A default outside the limits is kept as the file says (the device holds
// it at power-on); writes through the gateway are still checked.
void Builder::check_in_limits(const Template& t, const Parsed& p) const {
  if (!p.value || (!t.low && !t.high)) return;
  std::string detail;
  if (check_limits(*p.value, t.low, t.high, &detail)) {
    d_.warn(p.entry->line, p.label + " " + format_value(*p.value) + " is outside LowLimit/HighLimit (" + detail +
                               "); kept as given");
  }
}

// CiA 306 ObjFlags: hints for tools, so a value that is no number ("NV")
// is ignored with a warning instead of refusing the file.
std::uint32_t Builder::obj_flags(const IniSection& s) {
  const auto* e = s.find("objflags");
  if (e == nullptr || e->value.empty()) return 0;
  std::string what;
  const auto bare = bare_number(e->value, &what);
  auto v = parse_value(DataType::Unsigned32, bare ? std::string_view(*bare) : std::string_view(e->value));
  if (!v) {
    d_.warn(e->line, "ObjFlags '" + e->value + "' is not an UNSIGNED32; ignored");
    return 0;
  }
  return static_cast<std::uint32_t>(std::get<std::uint64_t>(v->data));
}

// Unit= (else PhysicalUnit=) and Factor= of one section; a Factor that is
// no number is ignored with a warning (the unit stays, without a factor).
void Builder::read_unit(const IniSection& s, Template& t) {
  const auto* unit = s.find("unit");
  if (unit == nullptr || unit->value.empty()) unit = s.find("physicalunit");
  if (unit != nullptr && !unit->value.empty()) std::tie(t.unit, t.factor) = split_unit(unit->value);
  const auto* factor = s.find("factor");
  if (factor == nullptr || factor->value.empty()) return;
  const auto bare = std::string_view(factor->value).substr(0, factor->value.find_first_of(";#"));
  if (const auto v = factor_number(bare)) {
    t.factor = v;  // the Factor key wins over a "0.01A per unit" number
  } else {
    d_.warn(factor->line, "Factor '" + factor->value + "' in " + subject(s) +
                              " is not a non-zero number; ignored (values are shown without a factor)");
  }
}

Template Builder::read_template(const IniSection& s, bool domain_defaults) {
  Template t;
  const auto* name = s.find("parametername");
  if (name == nullptr || name->value.empty()) {
    d_.warn(s.line, subject(s) + " has no ParameterName");
  } else {
    t.name = name->value;
  }

  const auto* type = s.find("datatype");
  if (type != nullptr && !type->value.empty()) {
    const auto code = data_type_code(*type);
    const auto dt = data_type_from_index(code);
    if (!dt) {
      throw SkipObject{type->line, "DataType 0x" + hex4(code) + " of " + subject(s) +
                                       (code >= 0x20 && code < 0x60 ? " is a structure, not a value type"
                                                                    : " is not a CiA 301 data type")};
    }
    t.type = *dt;
  } else if (domain_defaults) {
    t.type = DataType::Domain;
  } else {
    throw SkipObject{s.line, subject(s) + " has no DataType"};
  }

  const auto* access = s.find("accesstype");
  if (access != nullptr && !access->value.empty()) {
    const auto a = od::parse_access(trim(std::string_view(access->value).substr(0, access->value.find_first_of(";#"))));
    if (!a) {
      throw SkipObject{access->line, "unknown AccessType '" + access->value + "' in " + subject(s) +
                                         " (expected ro, wo, rw, rwr, rww or const)"};
    }
    t.access = *a;
  } else if (domain_defaults) {
    t.access = od::Access::ReadWrite;
  } else {
    throw SkipObject{s.line, subject(s) + " has no AccessType"};
  }

  if (const auto* pdo = s.find("pdomapping"); pdo != nullptr && !pdo->value.empty()) t.pdo_mappable = flag(*pdo);

  Parsed low, high;
  for (auto [key, p] : {std::pair{"lowlimit", &low}, std::pair{"highlimit", &high}}) {
    const auto* e = s.find(key);
    if (e == nullptr || e->value.empty()) continue;
    if (!is_numeric(t.type)) {
      d_.warn(e->line, e->key + " ignored: " + type_text(t.type) + " has no limits");
      continue;
    }
    if (e->value.find('$') != std::string::npos && !out_.node_id) {
      d_.fail(e->line, e->key + " '" + e->value +
                           "' uses $NODEID but no node-ID is known (pass one, or use a DCF with "
                           "[DeviceComissioning] NodeID)");
    }
    // A limit that does not fit the type limits nothing the device can hold.
    try {
      *p = parse_object_value(e, t.type);
    } catch (const EdsError& err) {
      d_.warn(e->line, err.reason() + "; the limit is ignored");
    }
  }
  t.low = low.value;
  t.high = high.value;
  if (t.low && t.high && check_limits(*t.low, std::nullopt, t.high)) {
    d_.warn(low.entry->line, "LowLimit " + format_value(*t.low) + " is above HighLimit " + format_value(*t.high) +
                                 " in " + subject(s) + "; both ignored");
    t.low.reset();
    t.high.reset();
  }

  t.obj_flags = obj_flags(s);
  read_unit(s, t);
  t.def = parse_object_value(s.find("defaultvalue"), t.type, {}, true);
  t.param = parse_object_value(s.find("parametervalue"), t.type, {}, true);
  check_in_limits(t, t.def);
  check_in_limits(t, t.param);
  if (t.param.entry != nullptr && !out_.is_dcf && !warned_param_in_eds_) {
    warned_param_in_eds_ = true;
    d_.warn(t.param.entry->line, "ParameterValue in a file that is not a DCF; used as the current value");
  }
  return t;
}

od::SubEntry Builder::finish(const Template& t, std::uint8_t sub, const Parsed* override_value) {
  od::SubEntry e;
  e.sub = sub;
  e.name = t.name;
  e.type = t.type;
  e.access = t.access;
  e.pdo_mappable = t.pdo_mappable;
  e.low = t.low;
  e.high = t.high;
  e.default_value = t.def.value;
  eds::EntryFacts& facts = out_.entry_facts[static_cast<std::uint32_t>(cur_index_) << 8 | sub];
  facts.obj_flags = t.obj_flags;
  facts.parameter_value = (override_value != nullptr && override_value->entry != nullptr) || t.param.entry != nullptr;
  if (t.def.entry != nullptr) {
    const std::string lower = to_lower(t.def.entry->value);
    facts.hex_default = lower.find("0x") != std::string::npos;
  }
  facts.unit = t.unit.empty() ? unit_from_name(e.name) : t.unit;
  facts.factor = t.factor;
  // The most specific value wins: [xxxxValue] entry, ParameterValue, DefaultValue.
  const Parsed* chosen = nullptr;
  for (const Parsed* p : {override_value, &t.param, &t.def}) {
    if (p != nullptr && p->entry != nullptr) {
      chosen = p;
      break;
    }
  }
  if (chosen == nullptr) {
    e.value = Value::zero(t.type);
  } else if (chosen->needs_node_id) {
    d_.fail(chosen->entry->line, chosen->label + " '" + chosen->entry->value +
                                     "' uses $NODEID but no node-ID is known (pass one, or use a DCF with "
                                     "[DeviceComissioning] NodeID)");
  } else {
    e.value = *chosen->value;
  }
  return e;
}

void Builder::build_object(std::uint16_t index, const ObjSections& secs) {
  cur_index_ = index;
  try {
    read_object(index, secs);
  } catch (const SkipObject& skip) {
    // Facts of the sub-entries read before the object was given up.
    const auto first = static_cast<std::uint32_t>(index) << 8;
    out_.entry_facts.erase(out_.entry_facts.lower_bound(first), out_.entry_facts.lower_bound(first + 0x100));
    d_.warn(skip.line, skip.reason + "; object " + subject(*secs.main) + " left out");
  }
}

void Builder::read_object(std::uint16_t index, const ObjSections& secs) {
  const IniSection& s = *secs.main;
  warn_unknown_keys(s, kObjectKeys);

  od::ObjectCode code = od::ObjectCode::Var;
  if (const auto* ot = s.find("objecttype"); ot != nullptr && !ot->value.empty()) {
    switch (object_type_code(*ot)) {
      case 0x2:
        code = od::ObjectCode::Domain;
        break;
      case 0x7:
        code = od::ObjectCode::Var;
        break;
      case 0x8:
        code = od::ObjectCode::Array;
        break;
      case 0x9:
        code = od::ObjectCode::Record;
        break;
      case 0x0:
      case 0x5:
      case 0x6:
        d_.warn(ot->line, "ObjectType " + ot->value + " (NULL/DEFTYPE/DEFSTRUCT) of " + subject(s) +
                              " is not used; object skipped");
        return;
      default:
        throw SkipObject{ot->line, "unknown ObjectType " + ot->value + " in " + subject(s) +
                                       " (expected 0x2 DOMAIN, 0x7 VAR, 0x8 ARRAY or 0x9 RECORD)"};
    }
  }

  const auto* compact_e = s.find("compactsubobj");
  std::uint8_t compact = 0;
  if (compact_e != nullptr && !compact_e->value.empty()) {
    auto n = number(*compact_e, DataType::Unsigned8);
    if (n > 0xFE) {  // sub-index FFh is the object's structure (CiA 301 7.4.3), never an entry
      d_.warn(compact_e->line, "CompactSubObj=" + compact_e->value + ": sub-index FFh is reserved; entries 1..254 used");
      n = 0xFE;
    }
    compact = static_cast<std::uint8_t>(n);
  }
  const bool is_var = code == od::ObjectCode::Var || code == od::ObjectCode::Domain;

  const auto* subnumber = s.find("subnumber");
  if (subnumber != nullptr && !subnumber->value.empty()) {
    const auto n = number(*subnumber, DataType::Unsigned8);
    if (compact != 0 && !is_var) {
      if (n != 0 && n != compact + 1u) {
        d_.warn(subnumber->line, "SubNumber=" + subnumber->value + " ignored: CompactSubObj=" + compact_e->value +
                                     " gives " + std::to_string(compact + 1) + " sub-objects");
      }
    } else if (n != secs.subs.size() && !is_var) {
      d_.warn(subnumber->line, "SubNumber=" + subnumber->value + " but " + subject(s) + " has " +
                                   std::to_string(secs.subs.size()) + " sub-object sections; those are used");
    }
  }

  od::Object obj;
  obj.index = index;
  obj.code = code;
  if (const auto* name = s.find("parametername")) obj.name = name->value;

  if (is_var) {
    if (!secs.subs.empty()) {
      const auto* sub = secs.subs.begin()->second;
      d_.warn(sub->line, std::string(od::to_string(code)) + " object " + subject(s) +
                             " cannot have sub-object sections; " + subject(*sub) +
                             (secs.subs.size() > 1 ? " and the others" : "") + " ignored");
    }
    if (compact != 0) d_.warn(compact_e->line, "CompactSubObj ignored: " + subject(s) + " is not an ARRAY or RECORD");
    obj.subs.emplace(0, finish(read_template(s, code == od::ObjectCode::Domain), 0, nullptr));
  } else if (compact != 0) {
    if (!secs.subs.empty()) {
      const auto* sub = secs.subs.begin()->second;
      d_.fail(sub->line, subject(s) + " has CompactSubObj and also sub-object section " + subject(*sub));
    }
    const Template t = read_template(s, false);
    od::SubEntry sub0;
    sub0.sub = 0;
    sub0.name = "Highest sub-index supported";
    sub0.type = DataType::Unsigned8;
    sub0.access = od::Access::ReadOnly;
    sub0.default_value = Value::of_unsigned(DataType::Unsigned8, compact);
    sub0.value = *sub0.default_value;
    obj.subs.emplace(0, std::move(sub0));

    std::map<std::uint8_t, const IniEntry*> names, values;
    if (secs.names != nullptr) names = numbered(*secs.names, compact);
    if (secs.values != nullptr) values = numbered(*secs.values, compact);
    for (unsigned i = 1; i <= compact; ++i) {
      const auto sub = static_cast<std::uint8_t>(i);
      Template ti = t;
      ti.name = names.contains(sub) ? names.at(sub)->value : t.name + std::to_string(i);
      Parsed override_value;
      if (values.contains(sub)) {
        override_value =
            parse_object_value(values.at(sub), t.type, subject(*secs.values) + " entry " + std::to_string(i), true);
        check_in_limits(t, override_value);
      }
      obj.subs.emplace(sub, finish(ti, sub, &override_value));
    }
  } else {
    if (secs.subs.empty()) {
      throw SkipObject{s.line, std::string(od::to_string(code)) + " object " + subject(s) + " has no sub-objects (no [" +
                                   hex4(index) + "subN] sections and no CompactSubObj)"};
    }
    const std::uint32_t object_flags = obj_flags(s);  // the object section's apply to its sub-objects
    for (const auto& [sub, ss] : secs.subs) {
      warn_unknown_keys(*ss, kSubKeys);
      bool domain = false;
      if (const auto* ot = ss->find("objecttype"); ot != nullptr && !ot->value.empty()) {
        const auto c = object_type_code(*ot);
        if (c != 0x7 && c != 0x2) {
          d_.warn(ot->line, "sub-object " + subject(*ss) + " has ObjectType " + ot->value +
                                "; a sub-object is a VAR (ObjectType 0x7), read as one");
        }
        domain = c == 0x2;
      }
      Template ts = read_template(*ss, domain);
      ts.obj_flags |= object_flags;
      obj.subs.emplace(sub, finish(ts, sub, nullptr));
    }
    if (!obj.subs.contains(0)) {
      const auto highest = obj.subs.rbegin()->first;
      d_.warn(s.line, subject(s) + " has no sub-index 0; assumed UNSIGNED8 ro = " + std::to_string(highest));
      od::SubEntry sub0;
      sub0.name = "Highest sub-index supported";
      sub0.default_value = Value::of_unsigned(DataType::Unsigned8, highest);
      sub0.value = *sub0.default_value;
      obj.subs.emplace(0, std::move(sub0));
    } else if (obj.subs.at(0).type != DataType::Unsigned8) {
      d_.warn(secs.subs.at(0)->line,
              "sub-index 0 of " + subject(s) + " is " + type_text(obj.subs.at(0).type) + ", not UNSIGNED8");
    }
    for (const auto* extra : {secs.names, secs.values}) {
      if (extra != nullptr) d_.warn(extra->line, "section " + subject(*extra) + " ignored: no CompactSubObj");
    }
  }

  if (secs.links != nullptr) {
    const IniSection& ls = *secs.links;
    const IniEntry* count = nullptr;
    std::map<std::uint64_t, const IniEntry*> entries;
    for (const auto& e : ls.entries) {
      if (e.lkey == "objectlinks") {
        count = &e;
      } else if (all_dec(e.lkey) && e.lkey.size() < 6) {
        entries[std::stoull(e.lkey)] = &e;
      } else {
        d_.warn(e.line, "unknown key '" + e.key + "' in " + subject(ls) + " ignored");
      }
    }
    if (count != nullptr && !count->value.empty() && number(*count, DataType::Unsigned16) != entries.size()) {
      d_.warn(count->line, "ObjectLinks=" + count->value + " but " + subject(ls) + " has " +
                               std::to_string(entries.size()) + " entries; those are used");
    }
    auto& links = out_.object_links[index];
    for (const auto& [k, e] : entries) {
      const auto target = static_cast<std::uint16_t>(number(*e, DataType::Unsigned16));
      if (target == 0) d_.fail(e->line, "index 0 is not an object");
      links.push_back(target);
    }
  }

  out_.od.insert(std::move(obj));
}

DeviceDescription Builder::run() {
  const IniSection* file_info = nullptr;
  const IniSection* device_info = nullptr;
  const IniSection* commissioning = nullptr;
  const IniSection* dummy = nullptr;
  const IniSection* comments = nullptr;
  std::array<const IniSection*, 3> lists{};  // mandatory, optional, manufacturer
  for (const auto& s : ini_.sections) {
    const auto& n = s.lname;
    if (n == "fileinfo") {
      file_info = &s;
    } else if (n == "deviceinfo") {
      device_info = &s;
    } else if (n == "dummyusage") {
      dummy = &s;
    } else if (n == "comments") {
      comments = &s;
    } else if (n == "mandatoryobjects") {
      lists[0] = &s;
    } else if (n == "optionalobjects") {
      lists[1] = &s;
    } else if (n == "manufacturerobjects") {
      lists[2] = &s;
    } else if (n == "devicecomissioning" || n == "devicecommissioning") {
      if (commissioning != nullptr) {
        d_.fail(s.line,
                "both [DeviceComissioning] and " + subject(s) + " (line " + std::to_string(commissioning->line) + ")");
      }
      if (n == "devicecommissioning") d_.warn(s.line, "CiA 306 spells the section [DeviceComissioning]; accepted");
      commissioning = &s;
    } else if (!classify(s, d_)) {
      d_.warn(s.line, "unknown section " + subject(s) + " ignored");
    }
  }

  if (file_info != nullptr) {
    read_file_info(*file_info);
  } else {
    d_.warn(0, "no [FileInfo] section");
  }
  if (device_info != nullptr) {
    read_device_info(*device_info);
  } else {
    d_.warn(0, "no [DeviceInfo] section");
  }
  if (commissioning != nullptr) {
    read_commissioning(*commissioning);
    out_.is_dcf = true;
  }
  if (dummy != nullptr) read_dummy_usage(*dummy);
  if (comments != nullptr) read_comments(*comments);

  out_.node_id = node_id_arg_;
  if (out_.commissioning && out_.commissioning->node_id) {
    if (!out_.node_id) {
      out_.node_id = out_.commissioning->node_id;
    } else if (*out_.node_id != *out_.commissioning->node_id) {
      const auto* e = commissioning->find("nodeid");
      d_.warn(e->line, "node-ID " + std::to_string(*out_.node_id) + " given overrides NodeID=" + e->value);
    }
  }
  if (!out_.node_id) out_.node_id = fallback_node_id_;

  collect_object_sections();
  std::array<std::vector<std::uint16_t>*, 3> targets = {&out_.mandatory_objects, &out_.optional_objects,
                                                        &out_.manufacturer_objects};
  for (std::size_t i = 0; i < lists.size(); ++i) {
    if (lists[i] != nullptr) *targets[i] = read_list(*lists[i]);
  }
  for (const auto& [index, secs] : objs_) {
    if (secs.main == nullptr) continue;
    // Data type definitions (below 0260h) are not listed by convention.
    if (!listed_.contains(index) && index >= 0x0260) {
      d_.warn(secs.main->line, "object section " + subject(*secs.main) + " is not in any object list; loaded anyway");
    }
    build_object(index, secs);
  }
  out_.warnings = d_.take_warnings();
  return std::move(out_);
}

}  // namespace

DeviceDescription parse_device_description(std::string_view text, std::string file_name,
                                           std::optional<std::uint8_t> node_id,
                                           std::optional<std::uint8_t> fallback_node_id) {
  Diagnostics diag(file_name);
  for (const auto& id : {node_id, fallback_node_id}) {
    if (id && (*id < 1 || *id > 127)) diag.fail(0, "node-ID " + std::to_string(*id) + " is outside 1..127");
  }
  const IniFile ini = detail::parse_ini(text, diag);
  return Builder(diag, ini, file_name, node_id, fallback_node_id).run();
}

DeviceDescription load_device_description(const std::filesystem::path& path, std::optional<std::uint8_t> node_id,
                                          std::optional<std::uint8_t> fallback_node_id) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw EdsError(path.string(), 0, "cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw EdsError(path.string(), 0, "cannot read the file");
  return parse_device_description(text.str(), path.string(), node_id, fallback_node_id);
}

}  // namespace canopen::eds
