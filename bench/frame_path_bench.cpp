// Benchmarks for the frame path: the in-memory bus used by tests and
// simulations, the SocketCAN receive/transmit codec, and the can-utils text
// form used for debug logging.
//
// The numbers are for people comparing changes on one machine; nothing
// asserts on them (bench.smoke only checks that the code still runs).
#include <benchmark/benchmark.h>

#include <linux/can.h>
#include <sys/socket.h>
#include <sys/uio.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/can/memory_bus.hpp"
#include "canopen/socketcan/codec.hpp"

namespace {

using canopen::can::Frame;
using canopen::can::FrameFlag;
namespace sc = canopen::socketcan;

// Frames per batch: SocketCanChannel's default rx_batch (frames per recvmmsg()).
constexpr std::size_t kBatch = 64;

std::vector<std::uint8_t> payload(std::size_t n, std::uint8_t seed) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(seed + i * 7U);
  return v;
}

// A realistic mix for a CANopen bus with some FD traffic: standard-id
// classic (PDO/SDO), extended-id classic, FD with BRS, extended FD.
Frame mixed_frame(std::size_t i) {
  const auto seed = static_cast<std::uint8_t>(i);
  const auto idx = static_cast<std::uint32_t>(i);
  switch (i % 4) {
    case 0: return Frame::standard(0x180U + (idx & 0x7FU), payload(8, seed));
    case 1: return Frame::extended_id(0x18FF0000U | idx, payload(6, seed));
    case 2: {
      Frame f = Frame::standard(0x200U + (idx & 0x7FU), payload(64, seed));
      f.set(FrameFlag::BitRateSwitch);
      return f;
    }
    default: return Frame::extended_id(0x1CEB0000U | idx, payload(12, seed));
  }
}

std::vector<Frame> mixed_frames() {
  std::vector<Frame> v;
  v.reserve(kBatch);
  for (std::size_t i = 0; i < kBatch; ++i) v.push_back(mixed_frame(i));
  return v;
}

// ---- MemoryBus ---------------------------------------------------------------

// One sender queues kBatch frames, deliver() fans them out to the other
// endpoints. Args: payload bytes (8 = classic, 64 = FD), endpoints on the bus.
// items_per_second counts frames put on the bus; deliveries_per_second counts
// frames handed to receivers (frames x receivers).
void BM_MemoryBusThroughput(benchmark::State& state) {
  const auto bytes = static_cast<std::size_t>(state.range(0));
  const auto endpoints = static_cast<std::size_t>(state.range(1));

  canopen::can::MemoryBus bus;
  auto sender = bus.attach("tx");
  std::vector<std::unique_ptr<canopen::can::MemoryEndpoint>> receivers;
  std::uint64_t received = 0;
  for (std::size_t r = 1; r < endpoints; ++r) {
    receivers.push_back(bus.attach("rx" + std::to_string(r)));
    receivers.back()->on_frames([&received](std::span<const Frame> frames) {
      received += frames.size();
      benchmark::DoNotOptimize(frames.data());
    });
  }
  const Frame frame = Frame::standard(0x181, payload(bytes, 0x11));
  if (!frame.valid()) {
    state.SkipWithError("invalid benchmark frame");
    return;
  }

  for (auto _ : state) {
    for (std::size_t i = 0; i < kBatch; ++i) {
      benchmark::DoNotOptimize(sender->send(frame));
    }
    benchmark::DoNotOptimize(bus.deliver());
    benchmark::DoNotOptimize(received);
  }

  const auto frames = static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBatch);
  state.SetItemsProcessed(frames);
  state.counters["deliveries_per_second"] =
      benchmark::Counter(static_cast<double>(received), benchmark::Counter::kIsRate);
  if (received != static_cast<std::uint64_t>(frames) * (endpoints - 1)) {
    state.SkipWithError("receivers did not get every frame");
  }
}
BENCHMARK(BM_MemoryBusThroughput)
    ->ArgNames({"bytes", "endpoints"})
    ->Args({8, 2})
    ->Args({64, 2})
    ->Args({8, 4})
    ->Args({64, 4});

// ---- SocketCAN decode ----------------------------------------------------------

// What one recvmmsg() call leaves behind for kBatch messages: the frames,
// their mmsghdr (msg_len = bytes read) and per-message control buffers
// holding SCM_TIMESTAMPNS followed by SO_RXQ_OVFL, in the kernel's order.
struct RxBatch {
  struct alignas(cmsghdr) Control {
    std::array<unsigned char, sc::kControlBufferSize> bytes{};
  };

  std::array<canfd_frame, kBatch> raw{};
  std::array<iovec, kBatch> iov{};
  std::array<Control, kBatch> control{};
  std::array<mmsghdr, kBatch> msgs{};

  RxBatch(const RxBatch&) = delete;
  RxBatch& operator=(const RxBatch&) = delete;
  RxBatch() = default;

  // Returns false if the control messages did not fit (cannot happen with
  // kControlBufferSize, unless someone shrinks it).
  bool fill();
};

// CMSG_* are C macros with C casts.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wcast-align"
#pragma GCC diagnostic ignored "-Wsign-conversion"
bool RxBatch::fill() {
  const std::uint32_t drops = 3;  // SO_RXQ_OVFL is cumulative; usually unchanged
  for (std::size_t i = 0; i < kBatch; ++i) {
    // The frame as the kernel writes it: classic frames are a can_frame
    // (CAN_MTU bytes), FD frames a canfd_frame with CANFD_FDF set.
    const Frame f = mixed_frame(i);
    canfd_frame& r = raw[i];
    r.can_id = f.id | (f.extended() ? CAN_EFF_FLAG : 0U);
    r.len = f.len;
    if (f.fd()) {
      r.flags = static_cast<std::uint8_t>(CANFD_FDF | (f.has(FrameFlag::BitRateSwitch) ? CANFD_BRS : 0));
    }
    std::memcpy(r.data, f.data.data(), f.len);

    iov[i].iov_base = &r;
    iov[i].iov_len = sizeof r;

    msghdr& h = msgs[i].msg_hdr;
    h = msghdr{};
    h.msg_iov = &iov[i];
    h.msg_iovlen = 1;
    h.msg_control = control[i].bytes.data();
    h.msg_controllen = sc::kControlBufferSize;

    cmsghdr* c = CMSG_FIRSTHDR(&h);
    if (c == nullptr) return false;
    const timespec ts{1'700'000'000 + static_cast<std::time_t>(i), static_cast<long>(i) * 1000};
    c->cmsg_level = SOL_SOCKET;
    c->cmsg_type = SCM_TIMESTAMPNS;
    c->cmsg_len = CMSG_LEN(sizeof ts);
    std::memcpy(CMSG_DATA(c), &ts, sizeof ts);

    c = CMSG_NXTHDR(&h, c);
    if (c == nullptr) return false;
    c->cmsg_level = SOL_SOCKET;
    c->cmsg_type = SO_RXQ_OVFL;
    c->cmsg_len = CMSG_LEN(sizeof drops);
    std::memcpy(CMSG_DATA(c), &drops, sizeof drops);

    // The kernel reports the space it used, as put_cmsg() advances it.
    h.msg_controllen = CMSG_SPACE(sizeof ts) + CMSG_SPACE(sizeof drops);
    msgs[i].msg_len = f.fd() ? static_cast<unsigned>(CANFD_MTU) : static_cast<unsigned>(CAN_MTU);
  }
  return true;
}
#pragma GCC diagnostic pop

// The body of SocketCanChannel::on_readable() after recvmmsg() returned a
// full batch: parse_control + decode per message into a reserved vector.
void BM_SocketCanDecode(benchmark::State& state) {
  auto batch = std::make_unique<RxBatch>();
  if (!batch->fill()) {
    state.SkipWithError("control messages do not fit kControlBufferSize");
    return;
  }
  std::vector<Frame> out;
  out.reserve(kBatch);
  std::uint32_t last_drops = 0;

  for (auto _ : state) {
    out.clear();
    for (std::size_t i = 0; i < kBatch; ++i) {
      const sc::RxMeta meta = sc::parse_control(batch->msgs[i].msg_hdr);
      if (meta.drop_count) last_drops = *meta.drop_count;
      const sc::Decoded d = sc::decode(batch->raw[i], batch->msgs[i].msg_len);
      if (d.kind == sc::RawKind::Data) {
        out.push_back(d.frame);
        out.back().timestamp = meta.timestamp.value_or(Frame::Clock::time_point{});
      }
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::DoNotOptimize(last_drops);
    benchmark::ClobberMemory();
  }

  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBatch));
  if (out.size() != kBatch || last_drops != 3 || out[1].timestamp == Frame::Clock::time_point{}) {
    state.SkipWithError("decode produced unexpected frames");
  }
}
BENCHMARK(BM_SocketCanDecode);

// ---- SocketCAN encode ----------------------------------------------------------

// encode() of the same mix into one canfd_frame each, as the transmit path
// does before write().
void BM_SocketCanEncode(benchmark::State& state) {
  const std::vector<Frame> frames = mixed_frames();
  std::array<canfd_frame, kBatch> raw{};
  std::size_t bytes = 0;

  for (auto _ : state) {
    for (std::size_t i = 0; i < kBatch; ++i) {
      bytes += sc::encode(frames[i], raw[i]);
    }
    benchmark::DoNotOptimize(raw.data());
    benchmark::DoNotOptimize(bytes);
    benchmark::ClobberMemory();
  }

  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBatch));
}
BENCHMARK(BM_SocketCanEncode);

// ---- text codec ------------------------------------------------------------------

// Arg: payload bytes (8 = classic "181#..." , 64 = FD "181##1...").
Frame text_frame(std::size_t bytes) {
  Frame f = Frame::standard(0x181, payload(bytes, 0xA5));
  if (f.fd()) f.set(FrameFlag::BitRateSwitch);
  return f;
}

void BM_FrameToString(benchmark::State& state) {
  const Frame f = text_frame(static_cast<std::size_t>(state.range(0)));
  std::size_t chars = 0;
  for (auto _ : state) {
    std::string s = canopen::can::to_string(f);
    chars += s.size();
    benchmark::DoNotOptimize(s.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.SetBytesProcessed(static_cast<std::int64_t>(chars));
}
BENCHMARK(BM_FrameToString)->ArgName("bytes")->Arg(8)->Arg(64);

void BM_ParseFrame(benchmark::State& state) {
  const Frame f = text_frame(static_cast<std::size_t>(state.range(0)));
  const std::string text = canopen::can::to_string(f);
  if (canopen::can::parse_frame(text) != f) {
    state.SkipWithError("text form does not round-trip");
    return;
  }
  for (auto _ : state) {
    std::optional<Frame> parsed = canopen::can::parse_frame(text);
    benchmark::DoNotOptimize(parsed);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(text.size()));
}
BENCHMARK(BM_ParseFrame)->ArgName("bytes")->Arg(8)->Arg(64);

}  // namespace
