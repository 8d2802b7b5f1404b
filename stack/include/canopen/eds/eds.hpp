// EDS/DCF reader (CiA 306 device description files, INI format): turns an
// Electronic Data Sheet or a Device Configuration File into an object
// dictionary plus the file's device information.
//
// What is read: [FileInfo], [DeviceInfo], [DeviceComissioning] (DCF),
// [DummyUsage], [Comments], the object lists ([MandatoryObjects],
// [OptionalObjects], [ManufacturerObjects]), object sections [1018],
// sub-object sections [1018sub2], CompactSubObj with [xxxxName] and
// [xxxxValue], and [xxxxObjectLinks]. Section and key names are
// case-insensitive; numbers are decimal, 0x hex or leading-0 octal; integer
// values may use $NODEID ("$NODEID+0x180", "0x180+$NODEID", "$NODEID").
//
// Real vendor files are full of slips; the rule is: accept every file
// whose meaning is unambiguous, with a warning ("file:line: text") in
// DeviceDescription::warnings for each assumption made, and refuse only what
// cannot be read without guessing. Accepted with a warning: unknown sections
// and keys; object-list counts that disagree with their entries; listed
// objects without a section (left out) and sections not listed (loaded);
// SubNumber / NrOfEntries / ObjectLinks counts that disagree with what is
// present (what is present wins); sub-object sections of a VAR or without
// an object section (ignored); defaults outside LowLimit/HighLimit (kept);
// a DefaultValue or ParameterValue that cannot be read as its type (a
// fraction on an integer, out of the type's range, a typo, a placeholder):
// that entry has no default / no value (values_left_out); TIME_OF_DAY and
// TIME_DIFFERENCE as a bare number of ms (0: midnight, day 0);
// limits that contradict each other or do not fit the type (ignored); a
// signed type's value in hex two's complement; 0x0/0x1 for 0/1 keys and
// BOOLEAN values; inline ';' or '#' comments after numbers and '#' comment
// lines; C literal suffixes (0x10LL, 1U, 0.0f); a REAL given as its bit
// pattern in hex; a DOMAIN default that is not hex (empty DOMAIN); symbolic
// ObjectType/DataType (VAR, UNSIGNED8); CompactSubObj=255 (1..254 used); a
// DCF NodeID of 0 or FFh (ignored); text that is not UTF-8 (read as
// Latin-1); a key repeated with the same value, or once empty; lines ending
// in CR alone (classic Mac OS); a line without '=' inside a section
// (skipped); an object-list number given twice with two objects (both
// taken); a [xxxxsubFF] section (the structure sub-index: skipped). An object
// that cannot be read without guessing (unknown ObjectType, DataType or
// AccessType, a structure type on a VAR, no sub-objects) is left out with a
// warning. Refused with EdsError naming file and line: a malformed line
// (a bad section header, no key, no '=' outside any section), a
// key repeated with a different value, a limit or count that does not fit
// its type after the repairs above, a section naming the same thing twice,
// CompactSubObj together with sub-object sections.
//
// Callers: pass the node-ID the device has on the bus whenever the file may
// use $NODEID (every EDS with default PDO/SDO/EMCY COB-IDs does); catch
// EdsError and show what() to the operator; log the warnings.
//
// Thread safety: the functions are pure (no shared state) and may run
// concurrently; a DeviceDescription is a plain value (its dictionary is not
// thread-safe, see object_dictionary.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/od/object_dictionary.hpp"

namespace canopen::eds {

// A file that cannot be used as given. what() is "file:line: reason", or
// "file: reason" when the problem is not on one line (line() == 0, e.g. the
// file cannot be read).
class EdsError : public std::runtime_error {
 public:
  EdsError(std::string file, std::size_t line, std::string reason);
  const std::string& file() const noexcept { return file_; }
  std::size_t line() const noexcept { return line_; }  // 1-based; 0 = whole file
  const std::string& reason() const noexcept { return reason_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string reason_;
};

// [FileInfo]: informative only, kept as written.
struct FileInfo {
  std::string file_name;
  std::string file_version;   // FileVersion
  std::string file_revision;  // FileRevision
  std::string eds_version;    // EDSVersion, e.g. "4.0"
  std::string description;
  std::string creation_time, creation_date, created_by;
  std::string modification_time, modification_date, modified_by;
  std::string last_eds;  // LastEDS (DCF): the EDS the DCF was made from
};

// [DeviceInfo]. Numbers absent from the file stay nullopt / 0 / false.
struct DeviceInfo {
  std::string vendor_name;
  std::optional<std::uint32_t> vendor_number;
  std::string product_name;
  std::optional<std::uint32_t> product_number;
  std::optional<std::uint32_t> revision_number;
  std::string order_code;
  std::vector<unsigned> baud_rates_kbit;  // BaudRate_xxx=1, ascending (10 ... 1000)
  bool simple_boot_up_master = false;
  bool simple_boot_up_slave = false;
  std::uint8_t granularity = 0;  // 0: no dynamic PDO mapping; else mapping granularity in bits
  std::uint8_t dynamic_channels_supported = 0;
  bool group_messaging = false;
  std::uint16_t nr_of_rx_pdo = 0;
  std::uint16_t nr_of_tx_pdo = 0;
  bool lss_supported = false;
  std::uint8_t compact_pdo = 0;  // CompactPDO bit field
  bool canopen_safety_supported = false;
};

// [DeviceComissioning] (CiA 306 spells it with one 'm'): DCF only.
struct Commissioning {
  std::optional<std::uint8_t> node_id;  // 1..127
  std::string node_name;
  std::optional<std::uint16_t> baud_rate_kbit;
  std::optional<std::uint32_t> net_number;
  std::string network_name;
  bool canopen_manager = false;
  std::optional<std::uint32_t> lss_serial_number;
};

// CiA 306 ObjFlags bits: hints for configuration tools.
inline constexpr std::uint32_t kObjFlagRefuseWriteOnDownload = 0x1;  // bit 0: do not write it in a DCF download
inline constexpr std::uint32_t kObjFlagRefuseReadOnScan = 0x2;       // bit 1: do not read it when scanning a device

// What the file says about one sub-entry that the dictionary does not keep.
struct EntryFacts {
  std::uint32_t obj_flags = 0;   // ObjFlags of the object section and of the sub-object section, OR-ed
  bool parameter_value = false;  // a ParameterValue or [xxxxValue] entry gave the value
  bool hex_default = false;      // DefaultValue was written in hex (0x...)
  // The physical unit and scale vendors write into their files (no CiA 306
  // key exists): the value in `unit` is the raw value times `factor`. Read
  // from the entry's own section (a sub-object inherits nothing from its
  // object section; CompactSubObj entries take the object section's):
  // `Unit=mV` / `PhysicalUnit=mV` with `Factor=0.1`; `Unit=0.01A per unit`
  // (factor 0.01, unit "A"); else a short unit in brackets ending the name
  // ("Voltage [mV]"), or in parentheses if it is a common unit symbol
  // ("Frequency (Hz)"). A Factor that is not a non-zero number is ignored
  // with a warning. Empty / nullopt when the file says nothing, and then
  // values are shown raw; a factor may come without a unit.
  std::string unit;
  std::optional<double> factor;
};

struct DeviceDescription {
  FileInfo file;
  DeviceInfo device;
  // Every VAR, DOMAIN, ARRAY and RECORD object of the file (DEFTYPE,
  // DEFSTRUCT and NULL objects are skipped with a warning), without hooks.
  // Per sub-entry: default_value is DefaultValue (nullopt if absent, or if
  // it needs an unknown $NODEID while ParameterValue makes it unnecessary);
  // value is the [xxxxValue] entry, else ParameterValue, else DefaultValue,
  // else the type's zero. DOMAIN objects default to DataType DOMAIN and rw.
  // CompactSubObj=N gives sub 0 "Highest sub-index supported" (UNSIGNED8,
  // ro, N) and subs 1..N with the object's DataType, AccessType, PDOMapping,
  // limits and DefaultValue, named from [xxxxName] or else ParameterName
  // followed by the sub-index in decimal ("Gain1").
  od::ObjectDictionary od;
  bool is_dcf = false;  // a [DeviceComissioning] section or a .dcf file name
  // The node-ID $NODEID was resolved with: the caller's, else the DCF's.
  std::optional<std::uint8_t> node_id;
  std::optional<Commissioning> commissioning;
  std::vector<std::uint16_t> mandatory_objects;  // as listed, duplicates removed
  std::vector<std::uint16_t> optional_objects;
  std::vector<std::uint16_t> manufacturer_objects;
  std::vector<std::uint16_t> dummy_usage;                            // data type indexes with DummyXXXX=1, ascending
  std::vector<std::string> comments;                                 // [Comments] Line1..LineN
  std::map<std::uint16_t, std::vector<std::uint16_t>> object_links;  // [xxxxObjectLinks]
  std::vector<std::string> warnings;                                 // harmless oddities, each "file:line: text"
  // The DefaultValue/ParameterValue entries that could not be read and were
  // left out (also in `warnings`), each "file:line: text": the entry has no
  // default or no value, so a DCF's entry is not written at boot. Callers
  // SHOULD log these louder than the other warnings.
  std::vector<std::string> values_left_out;
  // Per sub-entry of `od`, key index << 8 | sub; see facts().
  std::map<std::uint32_t, EntryFacts> entry_facts;
  // The facts of an entry; all defaults for an entry not in the file.
  EntryFacts facts(std::uint16_t index, std::uint8_t sub) const {
    const auto it = entry_facts.find(static_cast<std::uint32_t>(index) << 8 | sub);
    return it == entry_facts.end() ? EntryFacts{} : it->second;
  }
};

// Reads and parses a file; file names in messages are path.string().
// node_id (1..127) resolves $NODEID and overrides a DCF's NodeID (with a
// warning when they differ); fallback_node_id resolves $NODEID only when
// neither node_id nor the DCF gives one (a checker with no node in mind).
// Throws EdsError (also when the file cannot be read or a node-ID is out of
// range).
DeviceDescription load_device_description(const std::filesystem::path& path, std::optional<std::uint8_t> node_id = {},
                                          std::optional<std::uint8_t> fallback_node_id = {});

// The same on text already in memory; file_name is used in messages only
// (and a ".dcf" ending marks a DCF).
DeviceDescription parse_device_description(std::string_view text, std::string file_name,
                                           std::optional<std::uint8_t> node_id = {},
                                           std::optional<std::uint8_t> fallback_node_id = {});

}  // namespace canopen::eds
