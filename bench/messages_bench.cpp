// Encoding cost of one event as it leaves the gateway (topic, JSON and
// protobuf binary, once per event). Budget: the whole gateway spends < 3 µs
// of CPU per PDO event, so this should stay well under 1 µs.
#include <benchmark/benchmark.h>
#include <google/protobuf/util/json_util.h>

#include "canopen_gateway.pb.h"
#include "messages/event_encoder.hpp"

namespace {

canopen::Event two_value_tpdo() {
  canopen::PdoEvent p;
  p.node = 5;
  p.number = 3;
  p.cob_id = 0x385;
  p.raw = {0x37, 0x06, 0xB8, 0x0B, 0x00, 0x00};
  p.values.push_back(
      {0x6041, 0, "Statusword", canopen::Value::of_unsigned(canopen::DataType::Unsigned16, 1591)});
  p.values.push_back(
      {0x6064, 0, "Position actual value", canopen::Value::of_signed(canopen::DataType::Integer32, 3000)});
  canopen::Event ev;
  ev.seq = 123456;
  ev.timestamp = canopen::can::Frame::Clock::now();
  ev.body = std::move(p);
  return ev;
}

// protobuf false: JSON only, what the gateway does while nobody wants protobuf.
void BM_EncodeTpdo2Values(benchmark::State& state, bool protobuf) {
  gateway::EncodeContext ctx{"gw1"};
  ctx.protobuf = protobuf;
  canopen::Event ev = two_value_tpdo();
  for (auto _ : state) {
    ++ev.seq;
    auto e = gateway::encode_event(ev, 1, ctx);
    benchmark::DoNotOptimize(e);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_EncodeTpdo2Values, json_and_protobuf, true);
BENCHMARK_CAPTURE(BM_EncodeTpdo2Values, json_only, false);

// For comparison: protobuf's own JSON printer on the same message (what
// the direct writer avoids).
void BM_ProtobufJsonPrinterTpdo2Values(benchmark::State& state) {
  const gateway::EncodeContext ctx{"gw1"};
  const auto e = gateway::encode_event(two_value_tpdo(), 1, ctx);
  canopen::gateway::v1::PdoEvent m;
  m.ParseFromString(e->binary);
  google::protobuf::util::JsonPrintOptions po;
  po.always_print_primitive_fields = true;
  for (auto _ : state) {
    std::string out;
    (void)google::protobuf::util::MessageToJsonString(m, &out, po);
    benchmark::DoNotOptimize(out);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ProtobufJsonPrinterTpdo2Values);

void BM_EncodeHeartbeat(benchmark::State& state) {
  const gateway::EncodeContext ctx{"gw1"};
  canopen::Event ev;
  ev.timestamp = canopen::can::Frame::Clock::now();
  ev.body = canopen::HeartbeatEvent{5, canopen::NmtState::Operational};
  for (auto _ : state) {
    ++ev.seq;
    auto e = gateway::encode_event(ev, 1, ctx);
    benchmark::DoNotOptimize(e);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EncodeHeartbeat);

}  // namespace
