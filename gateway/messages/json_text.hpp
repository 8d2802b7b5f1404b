// Small JSON text helpers for the direct event writers (internal to
// gateway_messages). They append to a caller's string and never allocate
// beyond it. Pure functions, thread-safe.
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "canopen/types.hpp"

namespace gateway::detail {

// True when s is well-formed UTF-8 (canopen/types.hpp).
using canopen::is_utf8;
// s when it is UTF-8, otherwise s read as Latin-1 (as json_value.hpp does
// for VISIBLE_STRING), so protobuf string fields and JSON stay valid.
std::string to_utf8(std::string_view s);

// "s" with JSON escapes. Precondition: s is UTF-8.
void append_json_string(std::string& out, std::string_view s);
void append_uint(std::string& out, std::uint64_t v);
void append_int(std::string& out, std::int64_t v);
// Lowercase hex, no separators, no quotes.
void append_hex(std::string& out, std::span<const std::uint8_t> bytes);
std::string to_hex(std::span<const std::uint8_t> bytes);

// "0x06020000"
std::string abort_code_text(std::uint32_t code);

// Seconds and nanoseconds since the Unix epoch (nanos in 0..999999999), as
// google.protobuf.Timestamp holds them.
struct UnixTime {
  std::int64_t seconds = 0;
  std::int32_t nanos = 0;
};
UnixTime to_unix_time(std::chrono::system_clock::time_point tp);
// Quoted RFC 3339 UTC exactly as protobuf's JSON printer writes a Timestamp:
// no fraction when nanos is 0, else 3, 6 or 9 digits.
void append_timestamp(std::string& out, UnixTime t);

// JSON text of a typed value with json_value.hpp's shapes (value_to_json),
// written directly. Precondition: holds_its_type(v).
void append_value_json(std::string& out, const canopen::Value& v);

}  // namespace gateway::detail
