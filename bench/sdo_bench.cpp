// SDO client <-> server in one process over the in-memory bus: expedited
// round trips per second, and segmented/block transfer throughput. These
// measure the protocol code alone (no kernel), the upper bound of what the
// gateway can do per core.
#include <benchmark/benchmark.h>

#include "canopen/can/memory_bus.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/sdo/server.hpp"

namespace {

using namespace canopen;

struct Rig {
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> client_ep = bus.attach("client");
  std::unique_ptr<can::MemoryEndpoint> server_ep = bus.attach("server");
  od::ObjectDictionary od;
  sdo::SdoServer server;
  sdo::SdoClient client;
  TimePoint now{};

  explicit Rig(std::size_t domain_size)
      : server(od, server_config(), [this](const can::Frame& f) { server_ep->send(f); }),
        client({}, [this](const can::Frame& f) { client_ep->send(f); }) {
    od.insert(od::make_var(0x2000, "domain", DataType::Domain, od::Access::ReadWrite,
                           Value::of_bytes(DataType::Domain, Bytes(domain_size, 0x5A))));
    od.insert(od::make_var(0x2002, "u32", DataType::Unsigned32, od::Access::ReadWrite,
                           Value::of_unsigned(DataType::Unsigned32, 42)));
    server_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) server.on_frame(f, now);
    });
    client_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) client.on_frame(f, now);
    });
  }
  static sdo::ServerConfig server_config() {
    sdo::ServerConfig c;
    c.node_id = 5;
    return c;
  }
  // Runs one upload to completion; returns the bytes received.
  std::size_t upload(std::uint16_t index, sdo::Mode mode) {
    std::size_t got = 0;
    sdo::Request r;
    r.node = 5;
    r.index = index;
    r.mode = mode;
    r.on_done = [&got](sdo::TransferResult&& res) { got = res.ok() ? res.data.size() : 0; };
    (void)client.upload(std::move(r), now);
    bus.deliver();
    return got;
  }
};

void BM_SdoExpeditedUploadRoundTrip(benchmark::State& state) {
  Rig rig(16);
  for (auto _ : state) {
    if (rig.upload(0x2002, sdo::Mode::Expedited) != 4) state.SkipWithError("upload failed");
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_SdoExpeditedUploadRoundTrip);

void BM_SdoUploadThroughput(benchmark::State& state) {
  const auto size = static_cast<std::size_t>(state.range(0));
  const auto mode = static_cast<sdo::Mode>(state.range(1));
  Rig rig(size);
  for (auto _ : state) {
    if (rig.upload(0x2000, mode) != size) state.SkipWithError("upload failed");
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * size));
}
BENCHMARK(BM_SdoUploadThroughput)
    ->ArgNames({"bytes", "mode"})
    ->Args({1 << 20, static_cast<int>(sdo::Mode::Segmented)})
    ->Args({1 << 20, static_cast<int>(sdo::Mode::Block)})
    ->Unit(benchmark::kMillisecond);

}  // namespace
