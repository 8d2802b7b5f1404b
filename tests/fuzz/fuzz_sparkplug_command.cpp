// Fuzzes what the gateway decodes from Sparkplug hosts: an NCMD/DCMD
// payload (anyone who may publish to spBv1.0/<G>/NCMD|DCMD/... sends it)
// through decode_command, each metric's wire value typed as every Sparkplug
// datatype the gateway maps CANopen objects to (typed_value), as the edge
// session does before a write.
// Invariants: nothing crashes or throws; a typed value holds the variant
// alternative of its type and fits the type's range; a typed value written
// back by the gateway's own payload writer (a DDATA metric) parses with the
// generated code to the same value, and is decoded again by decode_command
// to a wire value that types to the same value (a fixed point).
// fuzz-libs: gateway_sparkplug sparkplug_proto
// fuzz-seeds: tests/fuzz/corpus/sparkplug_command
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <variant>

#include "sparkplug/payload.hpp"

namespace sp = gateway::sparkplug;

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "invariant broken: %s\n", what);
    std::abort();
  }
}

constexpr sp::DataType kTypes[] = {
    sp::DataType::Int8,   sp::DataType::Int16,  sp::DataType::Int32,   sp::DataType::Int64,
    sp::DataType::UInt8,  sp::DataType::UInt16, sp::DataType::UInt32,  sp::DataType::UInt64,
    sp::DataType::Float,  sp::DataType::Double, sp::DataType::Boolean, sp::DataType::String,
    sp::DataType::DateTime, sp::DataType::Bytes};

void check_range(const sp::Value& v, sp::DataType t) {
  switch (t) {
    case sp::DataType::Int8:
    case sp::DataType::Int16:
    case sp::DataType::Int32: {
      const auto* i = std::get_if<std::int64_t>(&v);
      check(i != nullptr, "IntN typed as int64_t");
      const int bits = t == sp::DataType::Int8 ? 8 : t == sp::DataType::Int16 ? 16 : 32;
      check(*i >= -(std::int64_t{1} << (bits - 1)) && *i < (std::int64_t{1} << (bits - 1)), "IntN in range");
      break;
    }
    case sp::DataType::Int64: check(std::holds_alternative<std::int64_t>(v), "Int64 typed as int64_t"); break;
    case sp::DataType::UInt8:
    case sp::DataType::UInt16:
    case sp::DataType::UInt32: {
      const auto* u = std::get_if<std::uint64_t>(&v);
      check(u != nullptr, "UIntN typed as uint64_t");
      const int bits = t == sp::DataType::UInt8 ? 8 : t == sp::DataType::UInt16 ? 16 : 32;
      check(*u < (std::uint64_t{1} << bits), "UIntN in range");
      break;
    }
    case sp::DataType::UInt64:
    case sp::DataType::DateTime: check(std::holds_alternative<std::uint64_t>(v), "UInt64 typed as uint64_t"); break;
    case sp::DataType::Float: check(std::holds_alternative<float>(v), "Float typed as float"); break;
    case sp::DataType::Double: check(std::holds_alternative<double>(v), "Double typed as double"); break;
    case sp::DataType::Boolean: check(std::holds_alternative<bool>(v), "Boolean typed as bool"); break;
    case sp::DataType::String: check(std::holds_alternative<std::string>(v), "String typed as string"); break;
    case sp::DataType::Bytes: check(std::holds_alternative<canopen::Bytes>(v), "Bytes typed as bytes"); break;
    default: break;
  }
}

// NaN != NaN: compare floating values by their bits.
bool same(const sp::Value& a, const sp::Value& b) {
  if (const auto* f = std::get_if<float>(&a)) {
    const auto* g = std::get_if<float>(&b);
    return g != nullptr && std::memcmp(f, g, sizeof *f) == 0;
  }
  if (const auto* d = std::get_if<double>(&a)) {
    const auto* e = std::get_if<double>(&b);
    return e != nullptr && std::memcmp(d, e, sizeof *d) == 0;
  }
  return a == b;
}

void round_trip(const sp::Value& typed, sp::DataType t) {
  sp::Metric m;
  m.name = "m";
  m.datatype = t;
  m.value = typed;
  std::string out;
  sp::append_header(out, 1);
  sp::append_metric(out, m, sp::Form::Birth);  // carries the datatype, as a host's DCMD may
  sp::append_seq(out, 0);
  const auto again = sp::decode_command(out);
  check(again.has_value(), "the writer's payload decodes");
  check(again->metrics.size() == 1, "one metric written, one decoded");
  const auto retyped = sp::typed_value(again->metrics[0].value, t);
  check(retyped.has_value(), "a written value types again");
  check(same(*retyped, typed), "write -> decode -> type is the identity");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  const auto cmd = sp::decode_command(in);
  if (!cmd) return 0;
  for (const auto& cm : cmd->metrics) {
    for (const auto t : kTypes) {
      const auto typed = sp::typed_value(cm.value, t);
      if (!typed) continue;
      check_range(*typed, t);
      round_trip(*typed, t);
    }
  }
  return 0;
}
