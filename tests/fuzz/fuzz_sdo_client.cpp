// Fuzzes the SDO client with arbitrary server responses and time steps
// while several requests in every mode are queued on one node.
// Invariants: every frame it sends is an 8-byte request on 600h+node-ID;
// every request completes exactly once; after enough time nothing is left
// pending (a misbehaving server can never make the client hang).
// fuzz-libs: canopen_sdo
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "canopen/sdo/client.hpp"

namespace {
constexpr std::uint8_t kNode = 5;
}

// Input: byte 0 picks the requests (bit i: request i of the table below);
// then records of 9 bytes as in fuzz_sdo_server.cpp, the frames coming from
// 580h+node-ID (or another COB-ID when bits 0-1 are 2).
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  bool bad = false;
  canopen::sdo::ClientConfig cfg;
  cfg.max_upload_size = 64 * 1024;
  canopen::sdo::SdoClient client(cfg, [&](const canopen::can::Frame& f) {
    if (f.id != 0x600U + kNode || f.len != 8 || f.remote() || f.extended() || f.fd()) bad = true;
  });
  using canopen::sdo::Mode;
  struct Spec {
    bool upload;
    Mode mode;
    std::size_t size;
  };
  const Spec table[] = {{true, Mode::Auto, 0},       {true, Mode::Segmented, 0}, {true, Mode::Block, 0},
                        {false, Mode::Expedited, 4}, {false, Mode::Segmented, 20}, {false, Mode::Block, 1000},
                        {false, Mode::Auto, 300},    {true, Mode::Expedited, 0}};
  canopen::TimePoint now{};
  std::vector<int> completions;
  for (unsigned i = 0; i < 8; ++i) {
    if (!(data[0] & (1U << i))) continue;
    canopen::sdo::Request r;
    r.node = kNode;
    r.index = static_cast<std::uint16_t>(0x2000 + i);
    r.sub = 0;
    r.mode = table[i].mode;
    const std::size_t slot = completions.size();
    completions.push_back(0);
    r.on_done = [&completions, slot](canopen::sdo::TransferResult&&) { ++completions[slot]; };
    auto id = table[i].upload ? client.upload(std::move(r), now)
                              : client.download(std::move(r), canopen::Bytes(table[i].size, 0xA5), now);
    if (!id) completions[slot] = 1;  // refused at submit: no completion owed
  }
  for (std::size_t i = 1; i + 9 <= size; i += 9) {
    const std::uint8_t sel = data[i];
    if ((sel & 3) == 3) {
      now += std::chrono::milliseconds((sel >> 2) * 37);
      if (now >= client.next_deadline()) client.on_time(now);
      continue;
    }
    canopen::can::Frame f;
    f.id = (sel & 3) == 2 ? 0x580U + kNode + 1 : 0x580U + kNode;
    f.len = (sel & 0x80) ? static_cast<std::uint8_t>(data[i + 1] & 7) : 8;
    std::memcpy(f.data.data(), data + i + 1, 8);
    client.on_frame(f, now);
  }
  // Each remaining transfer times out in turn.
  for (int step = 0; step < 64 && client.pending(kNode) > 0; ++step) {
    now += std::chrono::seconds(2);
    client.on_time(now);
  }
  if (bad || client.pending(kNode) != 0) __builtin_trap();
  for (int c : completions) {
    if (c != 1) __builtin_trap();
  }
  return 0;
}
