// Typed values <-> JSON, with the REST/MQTT contract's rules
// (../shared/api-contract.md). The JSON shape depends only on the type, so
// a field never changes shape with its value:
//
//   b                      true / false
//   i8..i48, u8..u48       JSON integer (all fit in 53 bits)
//   i56, i64, u56, u64     decimal string ("-9223372036854775808")
//   r32, r64               JSON number; non-finite values as the strings
//                          "nan", "inf", "-inf" (JSON has no NaN/infinity)
//   vs                     string (bytes that are not UTF-8 are read as Latin-1)
//   os, d                  lowercase hex string without separators ("0aff")
//   us                     UTF-8 string
//   t                      RFC 3339 UTC with milliseconds ("2026-11-22T10:15:30.123Z")
//   td                     JSON integer: milliseconds (days * 86400000 + ms)
//
// value_from_json() accepts these shapes and, in addition: numbers as
// strings (decimal or 0x hex; leading zeros are decimal here, unlike EDS
// text) for integer and real types, 0/1 and "true"/"false"/"0"/"1" for b,
// hex in either case (spaces allowed) for os/d, "days ms" for t and td, and
// integral JSON numbers such as 5.0 for integer types. Errors are
// InvalidValue (wrong JSON kind, fractional number for an integer type,
// unparsable text) or ValueTooHigh / ValueTooLow (same details as
// parse_value(), e.g. "70000 is above 65535 (u16)").
//
// Pure functions, thread-safe. The returned JSON uses the default memory
// resource.
#pragma once

#include <boost/json/value.hpp>
#include <string>
#include <string_view>

#include "canopen/literal.hpp"
#include "canopen/result.hpp"
#include "canopen/types.hpp"

namespace canopen {

// Precondition: v.data matches v.type (as for encode()).
boost::json::value value_to_json(const Value& v);

Result<Value> value_from_json(DataType type, const boost::json::value& json);

// The JSON value as a Literal (literal.hpp): value_from_json(t, j) is
// value_from_literal(t, literal_from_json(j)).
Literal literal_from_json(const boost::json::value& json);

}  // namespace canopen
