// One way to write CANopen numbers as text, for replies, audit and log
// lines: object addresses ("1017h", "1017h sub 0" is canopen::od::object_label),
// fixed-width upper-case hex ("0A", "1017"), byte strings as hex ("0f00",
// lower-case in the API, upper-case in log lines) and SDO abort codes
// ("0x06020000").
//
// And the one reader of decimal numbers in paths and topics.
//
// Pure functions, thread-safe.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "canopen/od/object_dictionary.hpp"

namespace gateway::core {

enum class HexCase : std::uint8_t { lower, upper };

// "1017h sub 0" (CiA 301 notation, as the stack's own errors say it).
using canopen::od::object_label;

// `v` as `digits` upper-case hex digits, zero-padded ("0A", "1017"); wider
// values keep all their digits.
std::string hex_number(std::uint32_t v, int digits);
// An object index: "1017h".
std::string index_text(std::uint16_t index);
// "0x06020000"
std::string abort_code_text(std::uint32_t code);

// Bytes as hex without separators ("0f00"; upper-case "0F00").
void append_hex(std::string& out, std::span<const std::uint8_t> bytes, HexCase c = HexCase::lower);
std::string hex_bytes(std::span<const std::uint8_t> bytes, HexCase c = HexCase::lower);

// A decimal number in a path or topic level ("1", "127"): 1 to 9 digits,
// nothing else (no sign, no spaces). nullopt otherwise.
std::optional<std::uint32_t> parse_decimal(std::string_view s);

}  // namespace gateway::core
