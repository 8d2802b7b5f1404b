// PDO configuration (CiA 301 7.4.8.1/7.4.8.2, objects 1400h-1BFFh) read from
// an object dictionary, and bit-level packing of mapped values into a PDO
// payload (little-endian, LSB of the first mapped object at bit 0 of byte 0).
//
// A remote node's TPDOs (1800h/1A00h in its EDS/DCF) are what the gateway
// receives; its RPDOs (1400h/1600h) are what the gateway sends to it.
//
// All functions are pure; PdoConfig is a plain value. Thread-safe as long as
// the dictionary passed in is not modified concurrently.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/result.hpp"
#include "canopen/types.hpp"

namespace canopen::pdo {

// Receive = RPDO (1400h + n-1 / 1600h + n-1); Transmit = TPDO (1800h / 1A00h).
enum class Direction : std::uint8_t { Receive, Transmit };

inline constexpr std::uint16_t kMaxPdoNumber = 512;
inline constexpr std::size_t kMaxMappedEntries = 64;

std::uint16_t comm_index(Direction d, std::uint16_t number);     // number 1..512
std::uint16_t mapping_index(Direction d, std::uint16_t number);  // number 1..512

// COB-ID entry (sub 1): bit 31 = PDO does not exist / is invalid, bit 30 =
// no RTR allowed, bit 29 = 29-bit identifier.
struct CobId {
  std::uint32_t raw = 0x80000000;
  bool valid() const { return (raw & 0x80000000U) == 0; }
  bool rtr_allowed() const { return (raw & 0x40000000U) == 0; }
  bool extended() const { return (raw & 0x20000000U) != 0; }
  std::uint32_t can_id() const { return extended() ? raw & 0x1FFFFFFFU : raw & 0x7FFU; }
};

struct CommParams {
  CobId cob_id;
  std::uint8_t transmission_type = 255;
  std::uint16_t inhibit_time = 0;  // units of 100 us
  std::uint16_t event_timer = 0;   // ms; 0 = off
  std::uint8_t sync_start = 0;     // 0 = SYNC counter not used by this PDO

  bool synchronous() const { return transmission_type <= 240; }
  bool cyclic() const { return transmission_type >= 1 && transmission_type <= 240; }
  bool rtr_only() const { return transmission_type == 252 || transmission_type == 253; }
  bool event_driven() const { return transmission_type >= 254; }
};

struct MappingEntry {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::uint8_t bits = 0;
  bool dummy = false;  // index 0001h-0007h (a data type), sub 0: skipped bits
  DataType type = DataType::Unsigned8;
  std::string name;  // the sub-entry's name (the object's when that is empty); empty for dummies

  static MappingEntry from_raw(std::uint32_t raw);  // index<<16 | sub<<8 | bits; type/name unset
  std::uint32_t raw() const { return std::uint32_t{index} << 16 | std::uint32_t{sub} << 8 | bits; }
};

// Mapping sub 0: 0-64 entries; FEh = SAM-MPDO, FFh = DAM-MPDO (7.2.3).
enum class MappingKind : std::uint8_t { Normal, SamMpdo, DamMpdo };

struct PdoConfig {
  Direction direction = Direction::Transmit;
  std::uint16_t number = 0;  // 1-based
  CommParams comm;
  MappingKind kind = MappingKind::Normal;
  std::vector<MappingEntry> entries;

  unsigned total_bits() const;
  std::size_t byte_length() const { return (total_bits() + 7) / 8; }  // MPDO: 8
};

// The raw values of one PDO's two records (7.5.2.35-7.5.2.38 / 7.5.2.37,
// 7.5.2.39) as a device holds them, before the mapping is resolved against a
// dictionary: what the gateway tracks for a remote node whose PDOs are
// changed at run time (pdo/remote_config.hpp).
struct PdoParameters {
  CommParams comm;
  std::uint8_t count = 0;  // mapping sub 0 (FEh / FFh: MPDO)
  // Mapping sub 1..64 as far as known; only 1..count are used, the rest is
  // kept because the remapping sequence sets sub 0 last.
  std::map<std::uint8_t, std::uint32_t> entries;
};

// Reads sub 1..6 of the communication record (missing optional subs keep
// their defaults). NoSuchObject when the record or its COB-ID is absent.
Result<CommParams> read_comm_params(const od::ObjectDictionary& od, Direction d, std::uint16_t number);
// Reads comm params and mapping. Each entry is checked: the mapped object
// exists, its type's PDO size equals the mapped length (variable-length
// types: a whole number of bytes), and the total fits `max_bytes` (8
// classic, 64 FD); errors name the offending entry.
Result<PdoConfig> read_pdo(const od::ObjectDictionary& od, Direction d, std::uint16_t number,
                           std::size_t max_bytes = 8);
// The raw records of a PDO from a dictionary (comm params as above, mapping
// sub 0 and every mapping sub 1..64 present). NoSuchObject when either
// record or the COB-ID is absent.
Result<PdoParameters> read_parameters(const od::ObjectDictionary& od, Direction d, std::uint16_t number);
// Resolves raw parameters against `description`, the dictionary that knows
// the mapped objects' types and names, with read_pdo()'s checks. read_pdo()
// is read_parameters() + resolve_pdo() on one dictionary.
Result<PdoConfig> resolve_pdo(Direction d, std::uint16_t number, const PdoParameters& parameters,
                              const od::ObjectDictionary& description, std::size_t max_bytes = 8);
// Every PDO of a direction whose communication record exists, in number order.
// PDOs that fail read_pdo() are returned in `errors` as "TPDO3: reason".
std::vector<PdoConfig> read_all(const od::ObjectDictionary& od, Direction d, std::vector<std::string>* errors = nullptr,
                                std::size_t max_bytes = 8);

// ---- bit-level access ------------------------------------------------------
// Bits [offset, offset+bits) of bytes as an unsigned number; bits <= 64.
// Precondition: offset + bits <= 8 * bytes.size().
std::uint64_t extract_bits(std::span<const std::uint8_t> bytes, std::size_t offset, unsigned bits);
// Writes the low `bits` of v at bit offset; other bits are unchanged.
void insert_bits(std::span<std::uint8_t> bytes, std::size_t offset, unsigned bits, std::uint64_t v);

// One value of `type` mapped with `bits` bits at bit `offset`.
Result<Value> unpack_value(DataType type, std::span<const std::uint8_t> bytes, std::size_t offset, unsigned bits);
// v's type must be the mapped type (LengthMismatch otherwise).
std::error_code pack_value(const Value& v, std::span<std::uint8_t> bytes, std::size_t offset, unsigned bits);

// Decodes a payload of a Normal PDO. The payload MUST be at least
// byte_length() long (extra bytes are ignored, 7.5.2.35); dummy entries give
// no value.
Result<std::vector<MappedValue>> unpack(const PdoConfig& pdo, std::span<const std::uint8_t> payload);
// Bit offset of the first entry mapping index/sub, if mapped.
std::optional<std::size_t> bit_offset_of(const PdoConfig& pdo, std::uint16_t index, std::uint8_t sub);

}  // namespace canopen::pdo
