// A value as a person or a wire format wrote it, before its CANopen type is
// known: what a REST or MQTT body gives for an SDO or RPDO write, typed later
// by whoever knows the object (the gateway's request core, by the request's
// `type` or the EDS/DCF entry's). The kinds are JSON's, since that is the
// richest text form the contract takes; the JSON codec (json_value.hpp)
// turns a JSON value into a Literal, nothing here depends on JSON.
//
// value_from_literal() takes the shapes json_value.hpp lists for each type
// (numbers as numbers or decimal / 0x text, b as true/false/0/1, os and d as
// hex text, "days ms" for t and td ...) with the same errors: InvalidValue
// (wrong kind, fractional number for an integer type, unparsable text) or
// ValueTooHigh / ValueTooLow ("70000 is above 65535 (u16)").
//
// Plain value type and pure functions; thread-safe.
#pragma once

#include <concepts>
#include <cstdint>
#include <string>
#include <type_traits>

#include "canopen/result.hpp"
#include "canopen/types.hpp"

namespace canopen {

struct Literal {
  // array and object carry no contents: no CANopen type takes them, they
  // are kept only to say what was given instead.
  enum class Kind : std::uint8_t { null, boolean, int64, uint64, real, string, array, object };
  Kind kind = Kind::null;
  bool boolean = false;
  std::int64_t int64 = 0;
  std::uint64_t uint64 = 0;
  double real = 0;
  std::string text;

  Literal() = default;
  // Implicit, as a number or a text is written: Literal l = 5; = "0x10";
  Literal(bool b) : kind(Kind::boolean), boolean(b) {}  // NOLINT(google-explicit-constructor)
  template <std::integral I>
    requires(!std::same_as<I, bool>)
  Literal(I i) {  // NOLINT(google-explicit-constructor)
    if constexpr (std::is_signed_v<I>) {
      kind = Kind::int64;
      int64 = i;
    } else {
      kind = Kind::uint64;
      uint64 = i;
    }
  }
  Literal(double d) : kind(Kind::real), real(d) {}             // NOLINT(google-explicit-constructor)
  Literal(std::string s) : kind(Kind::string), text(std::move(s)) {}  // NOLINT(google-explicit-constructor)
  Literal(const char* s) : Literal(std::string(s)) {}               // NOLINT(google-explicit-constructor)
  static Literal of_kind(Kind k) {
    Literal l;
    l.kind = k;
    return l;
  }
  bool operator==(const Literal&) const = default;
};

Result<Value> value_from_literal(DataType type, const Literal& literal);

// Shortest round-trip text of `d` ("0.1", "1e+300"), as errors quote numbers.
std::string format_number(double d);

}  // namespace canopen
