// EDS/DCF loading: real vendor files are large (a drive controller's EDS of
// 486 KiB with 2,855 objects), and the gateway loads one per node at start
// and `canopen-eds check` loads many. Target: well under 100 ms per such
// file (results in bench/README.md).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "canopen/eds/eds.hpp"

namespace {

// A file of the same shape as the large vendor file, made here so the
// benchmark runs without ../shared: `objects` RECORDs of 1 + 4 sub-objects
// with limits, defaults and names.
std::string synthetic_eds(int objects) {
  std::string s =
      "[FileInfo]\nFileName=big.eds\nEDSVersion=4.0\n[DeviceInfo]\nVendorName=Bench\n"
      "[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n"
      "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x191\n";
  s += "[ManufacturerObjects]\nSupportedObjects=" + std::to_string(objects) + "\n";
  for (int i = 0; i < objects; ++i) s += std::to_string(i + 1) + "=0x" + std::to_string(2000 + i) + "\n";
  for (int i = 0; i < objects; ++i) {
    const auto idx = std::to_string(2000 + i);
    s += "[" + idx + "]\nParameterName=Parameter block " + idx + "\nObjectType=0x9\nSubNumber=5\n";
    s += "[" + idx + "sub0]\nParameterName=Highest sub-index supported\nObjectType=0x7\nDataType=0x0005\n"
         "AccessType=ro\nDefaultValue=4\nPDOMapping=0\n";
    for (int sub = 1; sub <= 4; ++sub) {
      s += "[" + idx + "sub" + std::to_string(sub) + "]\nParameterName=Value " + std::to_string(sub) +
           "\nObjectType=0x7\nDataType=0x0004\nAccessType=rw\nDefaultValue=0x" + std::to_string(100 * sub) +
           "\nLowLimit=-100000\nHighLimit=100000\nPDOMapping=1\n";
    }
  }
  return s;
}

void BM_EdsParseSynthetic(benchmark::State& state) {
  const auto text = synthetic_eds(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    auto d = canopen::eds::parse_device_description(text, "big.eds", 5);
    benchmark::DoNotOptimize(d.od.objects().size());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
  state.counters["KiB"] = static_cast<double>(text.size()) / 1024.0;
}
BENCHMARK(BM_EdsParseSynthetic)->Arg(100)->Arg(2855)->Unit(benchmark::kMillisecond);

// The largest file of the public corpus (../shared, beside the checkout),
// from disk as the gateway loads it; skipped where the corpus is absent.
void BM_EdsLoadLargestVendorFile(benchmark::State& state) {
  const std::filesystem::path path = std::filesystem::path(CANOPEN_SOURCE_DIR) /
                                     "../shared/eds-corpus/b-robotized+diff_canopen_system/config/"
                                     "custom_mapping_canopen_system/sample.eds";
  if (!std::filesystem::is_regular_file(path)) {
    state.SkipWithError("../shared/eds-corpus not found");
    return;
  }
  std::size_t objects = 0;
  for (auto _ : state) {
    auto d = canopen::eds::load_device_description(path, 5);
    objects = d.od.objects().size();
    benchmark::DoNotOptimize(objects);
  }
  state.counters["objects"] = static_cast<double>(objects);
  state.counters["KiB"] = static_cast<double>(std::filesystem::file_size(path)) / 1024.0;
}
BENCHMARK(BM_EdsLoadLargestVendorFile)->Unit(benchmark::kMillisecond);

}  // namespace
