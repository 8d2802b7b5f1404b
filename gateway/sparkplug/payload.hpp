// Sparkplug B 3.0 payloads (proto/sparkplug_b.proto; the facts in
// ../shared/ref/sparkplug-ascii-lss-facts.md A.7): the metric model the edge
// session keeps, a writer for the event path, the decoder of NCMD/DCMD and
// the CANopen -> Sparkplug datatype mapping of the contract's "Sparkplug B"
// section.
//
// Encoding is a small hand-written proto2 writer, not the generated code:
// a DDATA is written straight from the session's metrics into the output
// (sizes counted first, no temporary message, no heap allocation per
// metric), where the generated Payload needs every value copied into it
// first. bench/sparkplug_bench.cpp, a 4-metric DDATA (RelWithDebInfo):
// 87 ns against 158 ns for the generated code with its Payload reused.
// The generated parser (sparkplug_proto) decodes the commands, which are
// rare, and the tests use it to check the writer's output byte for byte.
//
// Pure functions, thread-safe.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "canopen/types.hpp"

namespace gateway::sparkplug {

// Sparkplug's DataType enum (the values are the specification's; a
// static_assert in payload.cpp keeps them equal to the generated enum).
enum class DataType : std::uint32_t {
  Unknown = 0,
  Int8 = 1,
  Int16 = 2,
  Int32 = 3,
  Int64 = 4,
  UInt8 = 5,
  UInt16 = 6,
  UInt32 = 7,
  UInt64 = 8,
  Float = 9,
  Double = 10,
  Boolean = 11,
  String = 12,
  DateTime = 13,
  Text = 14,
  UUID = 15,
  DataSet = 16,
  Bytes = 17,
  File = 18,
  Template = 19,
  PropertySet = 20,
  PropertySetList = 21,
};

// The contract's mapping: b Boolean, i8..i64 Int8..Int64, u8..u64
// UInt8..UInt64, 24/40/48/56-bit to the next wider, r32 Float, r64 Double,
// vs String, os/d Bytes, t DateTime. The contract names neither us nor td:
// us -> String (the caller converts UTF-16 to UTF-8), td -> Int64 (ms), as
// the facts (A.13) suggest.
DataType datatype_of(canopen::DataType t);

// A metric's value: monostate is null (is_null, no value). Signed integers
// in int64_t, unsigned ones and DateTime (UTC ms) in uint64_t, strings as
// UTF-8, Bytes/File as bytes.
using Value = std::variant<std::monostate, bool, std::int64_t, std::uint64_t, float, double, std::string, canopen::Bytes>;

// The CANopen object behind a metric: the properties `index` (UInt16) and
// `subIndex` (UInt8) in births.
struct ObjectRef {
  std::uint16_t index = 0;
  std::uint8_t sub_index = 0;
  friend bool operator==(const ObjectRef&, const ObjectRef&) = default;
};

struct Metric {
  std::string name;                    // unique per device (per node for node metrics)
  std::optional<std::uint64_t> alias;  // unique over the whole edge node
  DataType datatype = DataType::Unknown;
  Value value;
  std::uint64_t timestamp = 0;  // UTC ms of the value
  std::optional<ObjectRef> object;
};

// Birth: name, alias (if any), datatype, properties, value. Data: the alias
// when there is one, else the name; no datatype or properties (spec ch6
// "Metric": datatype SHOULD NOT be in DATA; aliases: DATA carries alias only).
enum class Form : std::uint8_t { Birth, Data };

// Appends one Payload to `out` in pieces, so a caller can pick metrics from
// wherever it keeps them: header(), then metric() for each, then seq() (or
// nothing, for NDEATH). The result is one valid Payload (a top-level message
// has no length prefix, so fields may simply follow each other).
void append_header(std::string& out, std::uint64_t timestamp);
void append_metric(std::string& out, const Metric& m, Form form);
void append_seq(std::string& out, std::uint64_t seq);

// A decoded command metric (NCMD/DCMD). `value` is as it came on the wire:
// int_value and long_value as uint64_t; typed_value() gives it the
// metric's type.
struct CommandMetric {
  std::string name;  // "" when only the alias came
  std::optional<std::uint64_t> alias;
  std::optional<DataType> datatype;  // if the host sent one
  Value value;
};
struct Command {
  std::optional<std::uint64_t> timestamp;
  std::vector<CommandMetric> metrics;
};
// nullopt when the bytes are not a Payload.
std::optional<Command> decode_command(std::string_view payload);

// A wire value (from decode_command) as a value of type `t`: Int8..Int32 from
// the two's complement of their width in int_value, Int64 from long_value,
// unsigned and DateTime as they are. nullopt when it does not fit the type
// (a bool for an Int32, a string for a Float ...).
std::optional<Value> typed_value(const Value& wire, DataType t);

}  // namespace gateway::sparkplug
