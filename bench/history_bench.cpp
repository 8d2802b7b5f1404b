// The PDO value history (gateway/history/value_history): what it costs on
// the event path and to answer a chart.
//   BM_HistoryRecordPdo      a TPDO event with 4 INTEGER16 values into
//                            objects already recorded (the steady state),
//                            10 ms apart; items = samples
//   BM_HistoryRecordSpread   one sample each to 4064 objects in turn (127
//                            nodes x 4 TPDOs x 8 objects: every sample a
//                            cache miss), 1 ms apart; items = samples
//   BM_HistoryQuery24h       the 24-h window (1440 60-s buckets) of a node
//                            with 8 full objects; items = queries
// The memory figures are in docs/reference/rest.md and bench/README.md.
#include <benchmark/benchmark.h>

#include <chrono>

#include "history/value_history.hpp"

namespace {

using namespace std::chrono_literals;
using canopen::DataType;
using canopen::Value;
using gateway::history::ValueHistory;
using gateway::history::WallTime;

const WallTime kT0 = WallTime(std::chrono::seconds(1764000000));

void BM_HistoryRecordPdo(benchmark::State& state) {
  ValueHistory h;
  canopen::PdoEvent p;
  p.node = 10;
  p.number = 2;
  for (std::uint8_t sub = 1; sub <= 4; ++sub)
    p.values.push_back({0x6401, sub, "Analogue input", Value::of_signed(DataType::Integer16, sub * 100)});
  canopen::Event ev{0, kT0, p};
  for (auto _ : state) {
    ev.timestamp += 10ms;
    h.on_event(1, ev);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * 4);
}
BENCHMARK(BM_HistoryRecordPdo);

void BM_HistoryRecordSpread(benchmark::State& state) {
  ValueHistory h(std::uint64_t{256} << 20);  // room for all 4064 objects
  const Value v = Value::of_unsigned(DataType::Unsigned8, 7);
  WallTime t = kT0;
  std::uint32_t i = 0;
  for (auto _ : state) {
    const auto node = static_cast<std::uint8_t>(1 + i % 127);
    const auto object = i / 127 % 32;
    h.record(1, node, static_cast<std::uint16_t>(0x6000 + object / 8), static_cast<std::uint8_t>(1 + object % 8), "in",
             v, t);
    t += 1ms;
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["objects"] = static_cast<double>(h.objects());
}
BENCHMARK(BM_HistoryRecordSpread);

void BM_HistoryQuery24h(benchmark::State& state) {
  ValueHistory h;
  WallTime t = kT0;
  for (int s = 0; s < 86400; s += 10, t += 10s)
    for (std::uint8_t sub = 1; sub <= 8; ++sub)
      h.record(1, 10, 0x6401, sub, "Analogue input", Value::of_signed(DataType::Integer16, s % 1000), t);
  for (auto _ : state) {
    auto r = h.query(1, 10, {}, 86400, t);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_HistoryQuery24h);

}  // namespace
