// Decoded PDO events per second through the stack: PdoReceiver with the
// mapping of a node's EDS (the shipped CiA 402 drive), one TPDO frame in,
// one PdoEvent with typed, named values out. Issue goal: >= 5 M/s per core.
#include <benchmark/benchmark.h>

#include "canopen/eds/eds.hpp"
#include "canopen/pdo/receiver.hpp"

namespace {

using namespace canopen;

void BM_PdoDecodeWithEdsMapping(benchmark::State& state) {
  const auto desc = eds::load_device_description(CANOPEN_SOURCE_DIR "/deploy/eds/cia402-drive.eds", 5);
  std::size_t values = 0;
  pdo::PdoReceiver rx([](const can::Frame&) {}, [&values](PdoEvent e) { values += e.values.size(); });
  (void)rx.add_node(5, desc.od);
  // Arg 1: TPDO1 (185h: statusword, 2 bytes). Arg 3: TPDO3 (385h:
  // statusword + position actual value, 6 bytes). Lengths match the mapping.
  const bool tpdo3 = state.range(0) == 3;
  can::Frame f = can::Frame::standard(tpdo3 ? 0x385 : 0x185, {0x37, 0x06, 0x10, 0x27, 0x00, 0x00});
  f.len = tpdo3 ? 6 : 2;
  const TimePoint now{};
  for (auto _ : state) {
    f.data[0] = static_cast<std::uint8_t>(f.data[0] + 1);
    benchmark::DoNotOptimize(rx.on_frame(f, now));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["values_per_event"] =
      static_cast<double>(values) / static_cast<double>(std::max<std::int64_t>(state.iterations(), 1));
}
BENCHMARK(BM_PdoDecodeWithEdsMapping)->ArgName("tpdo")->Arg(1)->Arg(3);

}  // namespace
