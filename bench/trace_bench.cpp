// The cost of the frame tap (gateway/trace/network_trace) on the bus path:
// a received batch of 64 frames through NetworkTrace::received(), as
// TappedChannel hands it over before the services see it, with nobody
// listening (ring off; ring on), with one trace client (decode + JSON per
// frame, queued), and the decoding alone. items_per_second = frames.
#include <benchmark/benchmark.h>

#include <chrono>
#include <vector>

#include "trace/network_trace.hpp"

namespace {

using namespace std::chrono_literals;
using canopen::can::Frame;
using gateway::trace::NetworkTrace;

// A CANopen-like mix: TPDOs, heartbeats, SDO request/response, SYNC.
std::vector<Frame> batch() {
  std::vector<Frame> out;
  const char* kinds[] = {"185#3706DE0500000000", "28A#55260A1B", "705#05", "605#4018100100000000",
                         "585#4318100178563412", "080#", "38B#0102", "77F#05"};
  for (int i = 0; i < 64; ++i) {
    Frame f = *canopen::can::parse_frame(kinds[i % 8]);
    f.timestamp = std::chrono::system_clock::now();
    out.push_back(f);
  }
  return out;
}

void run(benchmark::State& state, NetworkTrace& trace) {
  const auto frames = batch();
  auto steady = std::chrono::steady_clock::now();
  const auto wall = std::chrono::system_clock::now();
  for (auto _ : state) {
    steady += 1ms;
    trace.received(frames, steady, wall);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * 64);
}

void BM_TapNobodyListensRingOff(benchmark::State& state) {
  NetworkTrace trace({"can0", 127, 500000, {0s, 16u << 20}}, std::chrono::steady_clock::now());
  run(state, trace);
}
BENCHMARK(BM_TapNobodyListensRingOff);

void BM_TapNobodyListensRingOn(benchmark::State& state) {
  NetworkTrace trace({"can0", 127, 500000, {60s, 16u << 20}}, std::chrono::steady_clock::now());
  run(state, trace);
}
BENCHMARK(BM_TapNobodyListensRingOn);

void BM_TapOneTraceClient(benchmark::State& state) {
  NetworkTrace trace({"can0", 127, 500000, {60s, 16u << 20}}, std::chrono::steady_clock::now());
  gateway::trace::TraceQueue queue({4096, 2u << 20});
  trace.add_client({[](std::uint32_t) { return true; },
                    [&](const gateway::trace::Message& m) {
                      if (!queue.push_frame(m))
                        while (!queue.empty()) queue.pop();  // a reader that keeps up in bursts
                    }});
  run(state, trace);
}
BENCHMARK(BM_TapOneTraceClient);

void BM_TapOneFilteredOutClient(benchmark::State& state) {
  NetworkTrace trace({"can0", 127, 500000, {60s, 16u << 20}}, std::chrono::steady_clock::now());
  trace.add_client({[](std::uint32_t id) { return id == 0x123; }, [](const gateway::trace::Message&) {}});
  run(state, trace);
}
BENCHMARK(BM_TapOneFilteredOutClient);

void BM_DecodeFrame(benchmark::State& state) {
  const auto frames = batch();
  gateway::trace::DecodeContext ctx;
  ctx.own_node_id = 127;
  for (auto _ : state)
    for (const auto& f : frames) benchmark::DoNotOptimize(gateway::trace::decode(f, ctx));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * 64);
}
BENCHMARK(BM_DecodeFrame);

}  // namespace
