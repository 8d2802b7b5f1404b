// CANopen data types (CiA 301 7.1) and typed values.
//
// - DataType: the standard's data type indexes (0001h BOOLEAN ... 001Bh
//   UNSIGNED64), as they appear in EDS files (DataType=0x0007).
// - Names: CiA 309-3 short names (b i8 i16 i24 i32 i40 i48 i56 i64 u8 ...
//   r32 r64 t td vs os us d) used by the REST/MQTT contract, and the
//   standard's names (UNSIGNED16).
// - Value: a type tag plus the C++ representation of the value.
// - Little-endian codecs (7.1.3.2 transfer syntax) and text conversion with
//   range checks. JSON conversion is in json_value.hpp (separate target).
//
// All functions are pure and thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "canopen/result.hpp"

namespace canopen {

using Bytes = std::vector<std::uint8_t>;

enum class DataType : std::uint16_t {
  Boolean = 0x0001,
  Integer8 = 0x0002,
  Integer16 = 0x0003,
  Integer32 = 0x0004,
  Unsigned8 = 0x0005,
  Unsigned16 = 0x0006,
  Unsigned32 = 0x0007,
  Real32 = 0x0008,
  VisibleString = 0x0009,
  OctetString = 0x000A,
  UnicodeString = 0x000B,
  TimeOfDay = 0x000C,
  TimeDifference = 0x000D,
  Domain = 0x000F,
  Integer24 = 0x0010,
  Real64 = 0x0011,
  Integer40 = 0x0012,
  Integer48 = 0x0013,
  Integer56 = 0x0014,
  Integer64 = 0x0015,
  Unsigned24 = 0x0016,
  Unsigned40 = 0x0018,
  Unsigned48 = 0x0019,
  Unsigned56 = 0x001A,
  Unsigned64 = 0x001B,
};

// The type for an EDS/SDO data type index; nullopt for indexes that are not
// a basic or extended type listed above (e.g. 0020h PDO_COMMUNICATION_PARAMETER).
std::optional<DataType> data_type_from_index(std::uint16_t index);

std::string_view cia309_name(DataType t);    // "u16"
std::string_view standard_name(DataType t);  // "UNSIGNED16"
// Accepts a CiA 309-3 name or a standard name (case-insensitive for the latter).
std::optional<DataType> parse_type_name(std::string_view name);

// Size in bytes of a fixed-size type; nullopt for VISIBLE_STRING,
// OCTET_STRING, UNICODE_STRING and DOMAIN. BOOLEAN is 1 byte on SDO.
std::optional<std::size_t> fixed_size(DataType t);
// Size in bits when mapped into a PDO (BOOLEAN is 1 bit); 0 for variable-length types.
unsigned pdo_bit_size(DataType t);

bool is_signed_integer(DataType t);    // INTEGER8..INTEGER64
bool is_unsigned_integer(DataType t);  // UNSIGNED8..UNSIGNED64
bool is_real(DataType t);              // REAL32, REAL64
bool is_variable_length(DataType t);   // !fixed_size

// TIME_OF_DAY and TIME_DIFFERENCE (7.1.6.5/6): milliseconds after midnight
// (28 bits), days since 1984-01-01 (TIME_OF_DAY) or number of days.
struct TimeOfDay {
  std::uint32_t ms = 0;
  std::uint16_t days = 0;
  friend bool operator==(const TimeOfDay&, const TimeOfDay&) = default;
};

// C++ representation by type:
//   BOOLEAN -> bool; INTEGERn -> int64_t; UNSIGNEDn -> uint64_t;
//   REAL32 -> float; REAL64 -> double; VISIBLE_STRING -> std::string;
//   OCTET_STRING, DOMAIN -> Bytes; UNICODE_STRING -> std::u16string;
//   TIME_OF_DAY, TIME_DIFFERENCE -> TimeOfDay.
using ValueData = std::variant<bool, std::int64_t, std::uint64_t, float, double, std::string, Bytes,
                               std::u16string, TimeOfDay>;

struct Value {
  DataType type = DataType::Domain;
  ValueData data = Bytes{};

  // Builders that pick the representation for `type`; integers are range
  // checked by the callers that take user input (parse_value, JSON), not here.
  static Value of_bool(bool b) { return {DataType::Boolean, b}; }
  static Value of_signed(DataType t, std::int64_t v) { return {t, v}; }
  static Value of_unsigned(DataType t, std::uint64_t v) { return {t, v}; }
  static Value of_real32(float v) { return {DataType::Real32, v}; }
  static Value of_real64(double v) { return {DataType::Real64, v}; }
  static Value of_string(std::string s) { return {DataType::VisibleString, std::move(s)}; }
  static Value of_bytes(DataType t, Bytes b) { return {t, std::move(b)}; }
  // The zero / empty value of a type.
  static Value zero(DataType t);

  friend bool operator==(const Value&, const Value&) = default;
};

// Whether v.data is the representation listed above for v.type. encode()
// requires it; code that takes Values from outside checks it first.
bool holds_its_type(const Value& v);

// Minimum and maximum of an integer type as int64/uint64 (e.g. i24: -8388608..8388607).
std::int64_t signed_min(DataType t);
std::int64_t signed_max(DataType t);
std::uint64_t unsigned_max(DataType t);

// Little-endian transfer syntax (7.1.3.2). encode() of a value whose data
// does not match its type is a programming error (asserts).
Bytes encode(const Value& v);
// Number of bytes encode(v) produces, without encoding (cheap for a large DOMAIN).
std::size_t encoded_size(const Value& v);
void encode_into(const Value& v, Bytes& out);  // appends
// Decodes `bytes` as `type`. Fixed-size types need exactly their size
// (LengthTooLow / LengthTooHigh otherwise); VISIBLE_STRING stops at the
// first NUL; UNICODE_STRING needs an even length.
Result<Value> decode(DataType type, std::span<const std::uint8_t> bytes);

// Text form, as in EDS files and command lines: integers in decimal, 0x hex
// or leading-0 octal, with a sign for signed types; reals in decimal or
// exponent form; BOOLEAN as 0/1/true/false; VISIBLE_STRING as is; OCTET_STRING
// and DOMAIN as hex digits (spaces allowed); UNICODE_STRING as UTF-8;
// TIME_OF_DAY as "days ms" or RFC 3339 UTC; TIME_DIFFERENCE as "days ms".
// Out-of-range values give ValueTooHigh / ValueTooLow; unparsable text
// InvalidValue; the detail names the text and the type.
Result<Value> parse_value(DataType type, std::string_view text);
std::string format_value(const Value& v);

// True when s is well-formed UTF-8 (no overlongs, surrogates or code
// points above U+10FFFF). Does not allocate.
bool is_utf8(std::string_view s);
// Length of the well-formed UTF-8 sequence at s[i] (i < s.size()), its code
// point in *cp; 0 when the bytes there are not one (as is_utf8 judges).
std::size_t utf8_sequence(std::string_view s, std::size_t i, char32_t* cp);
// Bytes read as Latin-1 (ISO 8859-1), written as UTF-8: how text that is not
// valid UTF-8 (vendor files, device strings) is turned into valid JSON and
// protobuf strings. Callers check for valid UTF-8 first and keep such text
// as it is.
std::string latin1_to_utf8(std::string_view s);

// Checks low <= v <= high for numeric types (either bound optional).
// ValueTooLow / ValueTooHigh with a detail naming the limit.
std::error_code check_limits(const Value& v, const std::optional<Value>& low, const std::optional<Value>& high,
                             std::string* detail = nullptr);

// 1984-01-01 based TIME_OF_DAY <-> Unix time in milliseconds (correct across
// leap years; CiA 301 7.1.6.5).
TimeOfDay time_of_day_from_unix_ms(std::int64_t unix_ms);
std::int64_t unix_ms_from_time_of_day(const TimeOfDay& t);

}  // namespace canopen
