// Fuzzes the SDO server with arbitrary frame sequences and time steps.
// Invariants: every frame it sends is an 8-byte response on 580h+node-ID;
// it never answers a frame that is not for it; after the input and enough
// time it is idle again (no transfer can hang).
// fuzz-libs: canopen_sdo
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "canopen/od/object_dictionary.hpp"
#include "canopen/sdo/server.hpp"

namespace {

constexpr std::uint8_t kNode = 5;

// Small on purpose (rebuilt for every input): one object of each kind the
// server treats differently.
canopen::od::ObjectDictionary make_dictionary() {
  using canopen::DataType;
  using canopen::Value;
  using canopen::od::Access;
  canopen::od::ObjectDictionary od;
  od.insert(canopen::od::make_var(0x1000, "device type", DataType::Unsigned32, Access::ReadOnly,
                                  Value::of_unsigned(DataType::Unsigned32, 0x191)));
  od.insert(canopen::od::make_array(0x1016, "consumer heartbeat", DataType::Unsigned32, Access::ReadWrite, 3));
  od.insert(canopen::od::make_var(0x2000, "domain", DataType::Domain, Access::ReadWrite,
                                  Value::of_bytes(DataType::Domain, canopen::Bytes(3000, 0x5A))));
  od.insert(canopen::od::make_var(0x2001, "text", DataType::VisibleString, Access::ReadWrite,
                                  Value::of_string("hello")));
  od.insert(canopen::od::make_var(0x2002, "write only", DataType::Integer16, Access::WriteOnly,
                                  Value::of_signed(DataType::Integer16, 0)));
  auto& limited = od.insert(canopen::od::make_var(0x2003, "limited", DataType::Unsigned8, Access::ReadWrite,
                                                  Value::of_unsigned(DataType::Unsigned8, 5)));
  limited.subs[0].low = Value::of_unsigned(DataType::Unsigned8, 1);
  limited.subs[0].high = Value::of_unsigned(DataType::Unsigned8, 10);
  return od;
}

}  // namespace

// Input: records of 9 bytes. Byte 0 selects: bits 0-1 = 0/1 frame to the
// server, 2 frame on another COB-ID, 3 time step of (byte0 >> 2) * 37 ms;
// bit 7 set = short frame of (byte 1 & 7) bytes. Bytes 1-8 are the data.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto od = make_dictionary();
  std::size_t sent = 0;
  bool bad = false;
  canopen::sdo::ServerConfig cfg;
  cfg.node_id = kNode;
  cfg.max_download_size = 64 * 1024;
  canopen::sdo::SdoServer server(od, cfg, [&](const canopen::can::Frame& f) {
    ++sent;
    if (f.id != 0x580U + kNode || f.len != 8 || f.remote() || f.extended() || f.fd()) bad = true;
  });
  canopen::TimePoint now{};
  for (std::size_t i = 0; i + 9 <= size; i += 9) {
    const std::uint8_t sel = data[i];
    if ((sel & 3) == 3) {
      now += std::chrono::milliseconds((sel >> 2) * 37);
      if (now >= server.next_deadline()) server.on_time(now);
      continue;
    }
    canopen::can::Frame f;
    f.id = (sel & 3) == 2 ? 0x600U + kNode + 1 : 0x600U + kNode;
    f.len = (sel & 0x80) ? static_cast<std::uint8_t>(data[i + 1] & 7) : 8;
    std::memcpy(f.data.data(), data + i + 1, 8);
    const std::size_t before = sent;
    server.on_frame(f, now);
    if ((sel & 3) == 2 && sent != before) bad = true;  // answered a frame for another node
  }
  now += std::chrono::seconds(5);
  server.on_time(now);
  if (bad || server.state() != canopen::sdo::SdoServer::State::Idle) __builtin_trap();
  return 0;
}
