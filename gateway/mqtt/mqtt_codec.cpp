// The codec's shared pieces (mqtt_codec.hpp): error texts, the UTF-8 rule
// and the Variable Byte Integer. Packets are encoded in mqtt_encode.cpp and
// decoded in mqtt_decode.cpp.
#include "mqtt/mqtt_codec.hpp"

namespace gateway::mqtt::codec {

const char* to_string(Error e) {
  switch (e) {
    case Error::None: return "no error";
    case Error::MalformedRemainingLength: return "malformed remaining length";
    case Error::BadFlags: return "reserved fixed-header flags or QoS 3";
    case Error::BadType: return "invalid packet type";
    case Error::PacketTooLarge: return "packet too large";
    case Error::Truncated: return "packet shorter than its fields";
    case Error::TrailingBytes: return "bytes after the last field";
    case Error::BadProperty: return "malformed or unexpected property";
    case Error::BadString: return "string not well-formed UTF-8";
    case Error::TooLong: return "string or packet too long";
    case Error::BadArgument: return "value not allowed by the protocol";
  }
  return "unknown error";
}

bool valid_utf8(std::string_view s) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const auto* end = p + s.size();
  while (p < end) {
    const unsigned c = *p;
    if (c < 0x80) {
      if (c == 0) return false;  // U+0000 is forbidden in MQTT strings
      ++p;
      continue;
    }
    std::size_t n;
    std::uint32_t cp;
    if ((c & 0xE0) == 0xC0) { n = 1; cp = c & 0x1F; }
    else if ((c & 0xF0) == 0xE0) { n = 2; cp = c & 0x0F; }
    else if ((c & 0xF8) == 0xF0) { n = 3; cp = c & 0x07; }
    else return false;
    if (static_cast<std::size_t>(end - p) <= n) return false;
    for (std::size_t i = 1; i <= n; ++i) {
      if ((p[i] & 0xC0) != 0x80) return false;
      cp = cp << 6 | (p[i] & 0x3Fu);
    }
    // Overlong forms, surrogates and beyond U+10FFFF are not UTF-8.
    static constexpr std::uint32_t kMin[] = {0, 0x80, 0x800, 0x10000};
    if (cp < kMin[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    p += n + 1;
  }
  return true;
}

std::size_t varint_size(std::uint32_t v) { return v < 128 ? 1 : v < 16384 ? 2 : v < 2'097'152 ? 3 : 4; }

void put_varint(std::string& out, std::uint32_t v) {
  do {
    auto b = static_cast<std::uint8_t>(v & 0x7F);
    v >>= 7;
    if (v > 0) b |= 0x80;
    out.push_back(static_cast<char>(b));
  } while (v > 0);
}

}  // namespace gateway::mqtt::codec
