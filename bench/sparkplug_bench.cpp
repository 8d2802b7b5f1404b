// A DDATA payload of a 4-value TPDO (gateway/sparkplug/payload.hpp): the
// hand-written writer against protobuf's generated code with the Payload
// message reused between calls (its cleared metrics and strings are reused,
// so neither allocates per metric once warm). The writer is what the edge
// session uses; this keeps the reason measured.
#include <benchmark/benchmark.h>

#include "sparkplug/payload.hpp"
#include "sparkplug_b.pb.h"

namespace {

namespace pb = org::eclipse::tahu::protobuf;
using namespace gateway::sparkplug;

std::vector<Metric> tpdo_metrics() {
  std::vector<Metric> v(4);
  const char* names[] = {"Statusword", "Position actual value", "Velocity actual value", "Modes of operation display"};
  const DataType types[] = {DataType::UInt16, DataType::Int32, DataType::Int32, DataType::Int8};
  for (std::size_t i = 0; i < v.size(); ++i) {
    v[i].name = names[i];
    v[i].datatype = types[i];
    v[i].timestamp = 1'767'225'600'000;
    v[i].value = std::int64_t(1000 + i);
  }
  v[0].value = std::uint64_t{0x0237};
  return v;
}

void BM_SparkplugDdataWriter(benchmark::State& state) {
  auto metrics = tpdo_metrics();
  std::string out;
  std::uint64_t seq = 0;
  for (auto _ : state) {
    out.clear();
    append_header(out, 1'767'225'600'001);
    for (const auto& m : metrics) append_metric(out, m, Form::Data);
    append_seq(out, ++seq & 0xFF);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SparkplugDdataWriter);

void BM_SparkplugDdataGeneratedReused(benchmark::State& state) {
  auto metrics = tpdo_metrics();
  pb::Payload p;
  std::string out;
  std::uint64_t seq = 0;
  for (auto _ : state) {
    p.Clear();
    p.set_timestamp(1'767'225'600'001);
    for (const auto& m : metrics) {
      auto* x = p.add_metrics();
      x->set_name(m.name);
      x->set_timestamp(m.timestamp);
      if (const auto* u = std::get_if<std::uint64_t>(&m.value))
        x->set_int_value(static_cast<std::uint32_t>(*u));
      else
        x->set_int_value(static_cast<std::uint32_t>(std::get<std::int64_t>(m.value)));
    }
    p.set_seq(++seq & 0xFF);
    out.clear();
    p.AppendToString(&out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SparkplugDdataGeneratedReused);

}  // namespace
