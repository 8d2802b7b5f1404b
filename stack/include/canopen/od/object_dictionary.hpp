// Object dictionary (CiA 301 7.4): objects and sub-entries with data type,
// access, PDO mappability, limits, default and current value, plus
// application hooks that compute a value on read or validate a write.
//
// The same type serves two purposes: the gateway's own dictionary (served by
// the SDO server) and the description of a remote node read from its EDS/DCF
// (used to type SDO requests and decode PDOs).
//
// Not thread-safe: owned by one io_context / test. Hooks run synchronously
// inside read()/write() and must not block.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <system_error>

#include "canopen/result.hpp"
#include "canopen/sdo/abort.hpp"
#include "canopen/types.hpp"

namespace canopen::od {

// Object codes (7.4.3, table 42).
enum class ObjectCode : std::uint8_t { Null = 0x0, Domain = 0x2, DefType = 0x5, DefStruct = 0x6, Var = 0x7,
                                       Array = 0x8, Record = 0x9 };

// Access types (7.4.5). rwr / rww are read-write objects that are mapped for
// transmission (TPDO) / reception (RPDO) only.
enum class Access : std::uint8_t { ReadOnly, WriteOnly, ReadWrite, ReadWriteRead, ReadWriteWrite, Const };

std::string_view to_string(ObjectCode c);  // "VAR", "ARRAY", ...
std::string_view to_string(Access a);      // "ro", "wo", "rw", "rwr", "rww", "const"
// How messages name an object: "1018h sub 2".
std::string object_label(std::uint16_t index, std::uint8_t sub);
// EDS spellings, case-insensitive: ro wo rw rwr rww const.
std::optional<Access> parse_access(std::string_view s);
inline bool readable(Access a) { return a != Access::WriteOnly; }
inline bool writable(Access a) { return a != Access::ReadOnly && a != Access::Const; }

struct SubEntry {
  std::uint8_t sub = 0;
  std::string name;
  DataType type = DataType::Unsigned8;
  Access access = Access::ReadOnly;
  bool pdo_mappable = false;
  std::optional<Value> low;            // LowLimit
  std::optional<Value> high;           // HighLimit
  std::optional<Value> default_value;  // DefaultValue
  Value value;                         // current value (ParameterValue in a DCF)
};

struct Object {
  std::uint16_t index = 0;
  std::string name;
  ObjectCode code = ObjectCode::Var;
  // VAR and DOMAIN: sub 0 only. ARRAY and RECORD: sub 0 is the highest
  // sub-index supported (UNSIGNED8), then the entries, possibly with gaps.
  std::map<std::uint8_t, SubEntry> subs;
};

// Computes the bytes to upload for a sub-entry (e.g. a live counter).
// Returning an error aborts the upload with that code.
using ReadHook = std::function<Result<Bytes>(const SubEntry& entry)>;
// Called for a write after access, type, length and limit checks passed,
// before the value is stored. Return an error code (normally an SdoAbort) to
// refuse it; the stored value is then unchanged. The hook may change other
// entries (e.g. 1003h sub 0 = 0 clears the history).
using WriteHook = std::function<std::error_code(SubEntry& entry, const Value& new_value)>;

class ObjectDictionary;
// Hooks that need other entries (1019h looks at 1006h, a PDO mapping at the
// mapped objects) get the dictionary as a parameter instead of capturing it,
// so they stay correct when the dictionary is moved or copied.
using DictReadHook = std::function<Result<Bytes>(const ObjectDictionary& od, const SubEntry& entry)>;
using DictWriteHook = std::function<std::error_code(ObjectDictionary& od, SubEntry& entry, const Value& new_value)>;

class ObjectDictionary {
 public:
  // Adds or replaces the object at obj.index.
  Object& insert(Object obj);
  bool erase(std::uint16_t index);

  const Object* find(std::uint16_t index) const;
  Object* find(std::uint16_t index);
  const SubEntry* find(std::uint16_t index, std::uint8_t sub) const;
  SubEntry* find(std::uint16_t index, std::uint8_t sub);
  const std::map<std::uint16_t, Object>& objects() const { return objects_; }

  // ---- SDO access: what a remote client may do -----------------------------
  // Upload: NoSuchObject, NoSuchSubIndex, ReadOfWriteOnly, or the hook's error.
  Result<Bytes> read(std::uint16_t index, std::uint8_t sub) const;
  // Download: NoSuchObject, NoSuchSubIndex, WriteOfReadOnly, LengthMismatch /
  // LengthTooHigh / LengthTooLow for fixed-size types, ValueTooHigh /
  // ValueTooLow against the limits, InvalidValue, or the hook's error.
  // Nothing changes unless the result is success.
  std::error_code write(std::uint16_t index, std::uint8_t sub, std::span<const std::uint8_t> data);
  // Size an upload of this entry will have, when known without running a
  // read hook (for the size indication of segmented/block upload).
  std::optional<std::size_t> upload_size(std::uint16_t index, std::uint8_t sub) const;

  // ---- local access: the application itself, no access-rights check -------
  Result<Value> get(std::uint16_t index, std::uint8_t sub) const;
  // The value's type must equal the entry's type (LengthMismatch otherwise);
  // write hooks are not called.
  std::error_code set(std::uint16_t index, std::uint8_t sub, Value v);
  std::optional<std::uint64_t> get_unsigned(std::uint16_t index, std::uint8_t sub) const;

  // Observers run after a value of the index has changed through write() or
  // set() (hooks run before, and may refuse; observers only learn). Any
  // number per index, called in the order added, with the sub-index. They
  // must not add or remove observers of the same dictionary.
  using Observer = std::function<void(std::uint8_t sub)>;
  void observe(std::uint16_t index, Observer observer);

  // Hooks apply to every sub-entry of the index; one of each kind per index.
  void on_read(std::uint16_t index, ReadHook hook);
  void on_write(std::uint16_t index, WriteHook hook);
  // The same with the dictionary passed in. Each index has at most one read
  // and one write hook: setting either form replaces the other; an empty
  // function removes it. erase() removes an index's hooks, insert() keeps them.
  void on_dict_read(std::uint16_t index, DictReadHook hook);
  void on_dict_write(std::uint16_t index, DictWriteHook hook);

 private:
  std::map<std::uint16_t, Object> objects_;
  void notify(std::uint16_t index, std::uint8_t sub) const;
  std::multimap<std::uint16_t, Observer> observers_;
  std::map<std::uint16_t, ReadHook> read_hooks_;
  std::map<std::uint16_t, WriteHook> write_hooks_;
  std::map<std::uint16_t, DictReadHook> dict_read_hooks_;
  std::map<std::uint16_t, DictWriteHook> dict_write_hooks_;
};

// Builders for the common object shapes (name, type, access per sub-entry).
Object make_var(std::uint16_t index, std::string name, DataType type, Access access, Value value,
                bool pdo_mappable = false);
// ARRAY with sub 0 = count (ro unless given) and entries 1..count of one type.
Object make_array(std::uint16_t index, std::string name, DataType type, Access access, std::uint8_t count,
                  Access sub0_access = Access::ReadOnly);

}  // namespace canopen::od
