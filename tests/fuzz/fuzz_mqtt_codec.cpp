// Fuzzes the MQTT decoder and packet parsers with what a broker could send:
// any bytes, split anywhere, either decode to packets or stop the decoder
// with an error; no crash, UB or leak. A PUBLISH that parses is encoded
// again and must decode to the same fields.
// fuzz-libs: gateway_mqtt_codec
// fuzz-seeds: tests/fuzz/corpus/mqtt_codec
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "mqtt/mqtt_codec.hpp"

using namespace gateway::mqtt::codec;

namespace {

void check_publish_round_trip(const Publish& in, std::uint8_t version) {
  std::string wire;
  if (encode_publish(wire, version, in) != Error::None) return;  // e.g. QoS 2 is fine to refuse
  if (publish_size(version, in) != wire.size()) __builtin_trap();
  Decoder dec;
  dec.feed(wire);
  Packet p;
  if (!dec.next(p) || dec.buffered() != 0) __builtin_trap();
  Publish out;
  if (parse_publish(p, version, out) != Error::None) __builtin_trap();
  if (out.topic != in.topic || out.payload != in.payload || out.qos != in.qos || out.retain != in.retain ||
      out.packet_id != in.packet_id || out.dup != in.dup)
    __builtin_trap();
  if (version == kMqtt5 && (out.props.response_topic != in.props.response_topic ||
                            out.props.correlation_data != in.props.correlation_data ||
                            out.props.content_type != in.props.content_type ||
                            out.props.user.size() != in.props.user.size()))
    __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  // First byte: chunk size for feeding and the protocol level.
  const std::size_t chunk = (data[0] & 0x3F) + 1;
  const std::uint8_t version = (data[0] & 0x40) ? kMqtt5 : kMqtt311;
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  Decoder dec(4096);
  std::vector<std::uint8_t> codes;
  for (std::size_t at = 0; at < bytes.size(); at += chunk) {
    dec.feed(bytes.substr(at, chunk));
    Packet p;
    while (dec.next(p)) {
      switch (p.type) {
        case PacketType::Connack: {
          Connack c;
          (void)parse_connack(p, version, c);
          break;
        }
        case PacketType::Publish: {
          Publish pub;
          if (parse_publish(p, version, pub) == Error::None) check_publish_round_trip(pub, version);
          break;
        }
        case PacketType::Puback: case PacketType::Pubrec: case PacketType::Pubrel: case PacketType::Pubcomp: {
          std::uint16_t id;
          std::uint8_t reason;
          (void)parse_puback(p, version, id, reason);
          break;
        }
        case PacketType::Suback: {
          std::uint16_t id;
          codes.clear();
          (void)parse_suback(p, version, id, codes);
          break;
        }
        case PacketType::Disconnect: {
          std::uint8_t reason;
          (void)parse_disconnect(p, version, reason);
          break;
        }
        default:
          break;
      }
    }
    if (dec.error() != Error::None) break;
  }
  return 0;
}
