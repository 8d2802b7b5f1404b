// Helpers shared by the SDO unit tests: frames written as hex, a test
// object dictionary, and deterministic test data.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "canopen/od/object_dictionary.hpp"
#include "canopen/sdo/protocol.hpp"
#include "canopen/types.hpp"

namespace canopen::sdo::test {

// "2B 17 10 00 E8 03 00 00" -> the 8 bytes; missing bytes are 0.
inline Payload hex(std::string_view text) {
  Payload p{};
  std::size_t n = 0;
  int hi = -1;
  for (const char c : text) {
    int v = -1;
    if (c >= '0' && c <= '9') v = c - '0';
    if (c >= 'a' && c <= 'f') v = c - 'a' + 10;
    if (c >= 'A' && c <= 'F') v = c - 'A' + 10;
    if (v < 0) continue;
    if (hi < 0) {
      hi = v;
    } else if (n < p.size()) {
      p[n++] = static_cast<std::uint8_t>((hi << 4) | v);
      hi = -1;
    }
  }
  return p;
}

inline std::string to_hex(const Payload& p) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  std::string s;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (i > 0) s += ' ';
    s += kDigits[p[i] >> 4];
    s += kDigits[p[i] & 0xF];
  }
  return s;
}

inline Payload payload(const can::Frame& f) {
  Payload p{};
  for (std::size_t i = 0; i < p.size() && i < f.len; ++i) p[i] = f.data[i];
  return p;
}

// Deterministic, non-repeating-looking bytes (so a shifted or duplicated
// segment never compares equal by accident).
inline Bytes pattern(std::size_t n, std::uint32_t seed = 1) {
  Bytes b(n);
  std::uint32_t x = seed * 2654435761U + 12345U;
  for (auto& v : b) {
    x = x * 1664525U + 1013904223U;
    v = static_cast<std::uint8_t>(x >> 24);
  }
  return b;
}

// Objects of the test dictionary.
inline constexpr std::uint16_t kDeviceType = 0x1000;  // u32 ro 00020192h
inline constexpr std::uint16_t kHeartbeat = 0x1017;   // u16 rw 0
inline constexpr std::uint16_t kDomain = 0x2000;      // DOMAIN rw, empty
inline constexpr std::uint16_t kString = 0x2001;      // VISIBLE_STRING rw "hello world!"
inline constexpr std::uint16_t kLimited = 0x2002;     // u8 rw, 10..20, value 15
inline constexpr std::uint16_t kWriteOnly = 0x2003;   // u32 wo
inline constexpr std::uint16_t kArray = 0x2004;       // ARRAY of 2 u8 rw
inline constexpr std::uint16_t kBigDomain = 0x2005;   // DOMAIN rw, preset by tests
inline constexpr std::uint16_t kFailingRead = 0x2006; // DOMAIN whose read hook fails (08000024h)

inline od::ObjectDictionary make_test_dictionary() {
  using od::Access;
  od::ObjectDictionary d;
  d.insert(od::make_var(kDeviceType, "Device type", DataType::Unsigned32, Access::ReadOnly,
                        Value::of_unsigned(DataType::Unsigned32, 0x00020192)));
  d.insert(od::make_var(kHeartbeat, "Producer heartbeat time", DataType::Unsigned16, Access::ReadWrite,
                        Value::of_unsigned(DataType::Unsigned16, 0)));
  d.insert(od::make_var(kDomain, "Domain", DataType::Domain, Access::ReadWrite, Value::of_bytes(DataType::Domain, {})));
  d.insert(od::make_var(kString, "String", DataType::VisibleString, Access::ReadWrite,
                        Value::of_string("hello world!")));
  od::Object limited = od::make_var(kLimited, "Limited", DataType::Unsigned8, Access::ReadWrite,
                                    Value::of_unsigned(DataType::Unsigned8, 15));
  limited.subs[0].low = Value::of_unsigned(DataType::Unsigned8, 10);
  limited.subs[0].high = Value::of_unsigned(DataType::Unsigned8, 20);
  d.insert(std::move(limited));
  d.insert(od::make_var(kWriteOnly, "Write only", DataType::Unsigned32, Access::WriteOnly,
                        Value::of_unsigned(DataType::Unsigned32, 0)));
  d.insert(od::make_array(kArray, "Array", DataType::Unsigned8, Access::ReadWrite, 2));
  d.insert(od::make_var(kBigDomain, "Big domain", DataType::Domain, Access::ReadWrite,
                        Value::of_bytes(DataType::Domain, {})));
  d.insert(od::make_var(kFailingRead, "Failing read", DataType::Domain, Access::ReadWrite,
                        Value::of_bytes(DataType::Domain, {})));
  d.on_read(kFailingRead, [](const od::SubEntry&) -> Result<Bytes> { return Error{SdoAbort::NoDataAvailable, {}}; });
  return d;
}

inline Bytes domain_bytes(const od::ObjectDictionary& d, std::uint16_t index, std::uint8_t sub = 0) {
  auto v = d.get(index, sub);
  if (!v) return {};
  if (const auto* b = std::get_if<Bytes>(&v->data)) return *b;
  return {};
}

}  // namespace canopen::sdo::test
