// Hot-path cost of the metrics registry (issue 14): one counter increment
// and one histogram observation, ours (gateway/metrics/registry.hpp: plain
// uint64 cells read at scrape time) against prometheus-cpp 1.0.1 (Debian's
// prometheus-cpp-dev, when installed), plus rendering /metrics with 100
// series. Results and the decision: bench/README.md, "Metrics registry".
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "metrics/registry.hpp"

#ifdef CANOPEN_HAVE_PROMETHEUS_CPP
#include <prometheus/counter.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>
#include <prometheus/text_serializer.h>
#endif

namespace {

// The SDO latency histogram's bounds (seconds), as the gateway has them.
const std::vector<double> kBounds = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5};

double sample(std::size_t i) { return 0.0003 * static_cast<double>(i % 97); }  // spreads over the buckets

void BM_OurCounterInc(benchmark::State& state) {
  gateway::metrics::Registry r;
  auto& c = r.counter("x_total", "X.", {{"direction", "rx"}});
  for (auto _ : state) {
    c.inc();
    benchmark::ClobberMemory();
  }
  benchmark::DoNotOptimize(c.value());
}
BENCHMARK(BM_OurCounterInc);

void BM_OurHistogramObserve(benchmark::State& state) {
  gateway::metrics::Registry r;
  auto& h = r.histogram("x_seconds", "X.", kBounds);
  std::size_t i = 0;
  for (auto _ : state) {
    h.observe(sample(i++));
    benchmark::ClobberMemory();
  }
  benchmark::DoNotOptimize(h.count());
}
BENCHMARK(BM_OurHistogramObserve);

void BM_OurRender100Series(benchmark::State& state) {
  gateway::metrics::Registry r;
  for (int i = 0; i < 100; ++i) r.counter("x_total", "X.", {{"n", std::to_string(i)}}).inc(static_cast<std::uint64_t>(i));
  for (auto _ : state) benchmark::DoNotOptimize(r.render());
}
BENCHMARK(BM_OurRender100Series);

#ifdef CANOPEN_HAVE_PROMETHEUS_CPP
void BM_PrometheusCppCounterIncrement(benchmark::State& state) {
  prometheus::Registry r;
  auto& c = prometheus::BuildCounter().Name("x_total").Help("X.").Register(r).Add({{"direction", "rx"}});
  for (auto _ : state) {
    c.Increment();
    benchmark::ClobberMemory();
  }
  benchmark::DoNotOptimize(c.Value());
}
BENCHMARK(BM_PrometheusCppCounterIncrement);

void BM_PrometheusCppHistogramObserve(benchmark::State& state) {
  prometheus::Registry r;
  auto& h = prometheus::BuildHistogram().Name("x_seconds").Help("X.").Register(r).Add({}, kBounds);
  std::size_t i = 0;
  for (auto _ : state) {
    h.Observe(sample(i++));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_PrometheusCppHistogramObserve);

void BM_PrometheusCppRender100Series(benchmark::State& state) {
  prometheus::Registry r;
  auto& fam = prometheus::BuildCounter().Name("x_total").Help("X.").Register(r);
  for (int i = 0; i < 100; ++i) fam.Add({{"n", std::to_string(i)}}).Increment(i);
  prometheus::TextSerializer ser;
  for (auto _ : state) benchmark::DoNotOptimize(ser.Serialize(r.Collect()));
}
BENCHMARK(BM_PrometheusCppRender100Series);
#endif

}  // namespace
