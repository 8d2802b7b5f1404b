// The sans-I/O MQTT codec: exact bytes (the specs' examples where they
// give some), remaining-length boundaries, split and batched input,
// malformed input.
#include "mqtt/mqtt_codec.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace gateway::mqtt::codec;

namespace {

std::string bytes(std::initializer_list<int> b) {
  std::string s;
  for (int v : b) s.push_back(static_cast<char>(v));
  return s;
}

std::string hex(std::string_view s) {
  static const char* d = "0123456789abcdef";
  std::string out;
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    out += d[c >> 4];
    out += d[c & 15];
    out += ' ';
  }
  return out;
}

// Decodes exactly one packet from `wire` (fed in one chunk).
Packet one_packet(Decoder& dec, const std::string& wire) {
  dec.feed(wire);
  Packet p;
  EXPECT_TRUE(dec.next(p)) << to_string(dec.error());
  EXPECT_EQ(dec.buffered(), 0u);
  return p;
}

}  // namespace

TEST(MqttCodec, RemainingLengthBoundariesFromTheSpec) {
  // MQTT 3.1.1 table 2.4 / MQTT 5 table 1-1.
  const std::pair<std::uint32_t, std::string> cases[] = {
      {0, bytes({0x00})},
      {127, bytes({0x7F})},
      {128, bytes({0x80, 0x01})},
      {16383, bytes({0xFF, 0x7F})},
      {16384, bytes({0x80, 0x80, 0x01})},
      {2097151, bytes({0xFF, 0xFF, 0x7F})},
      {2097152, bytes({0x80, 0x80, 0x80, 0x01})},
      {268435455, bytes({0xFF, 0xFF, 0xFF, 0x7F})},
  };
  for (const auto& [v, enc] : cases) {
    std::string out;
    put_varint(out, v);
    EXPECT_EQ(hex(out), hex(enc)) << v;
    EXPECT_EQ(varint_size(v), enc.size()) << v;
  }
}

TEST(MqttCodec, PublishAtRemainingLengthBoundariesRoundTrips) {
  for (std::size_t rl : {127u, 128u, 16383u, 16384u}) {
    // v4 QoS 0: rl = 2 + topic + payload.
    const std::string topic = "t/x";
    const std::string payload(rl - 2 - topic.size(), 'p');
    Publish p;
    p.topic = topic;
    p.payload = payload;
    std::string out;
    ASSERT_EQ(encode_publish(out, kMqtt311, p), Error::None);
    EXPECT_EQ(out.size(), 1 + varint_size(static_cast<std::uint32_t>(rl)) + rl);
    EXPECT_EQ(publish_size(kMqtt311, p), out.size());
    Decoder dec;
    Packet pk = one_packet(dec, out);
    EXPECT_EQ(pk.body.size(), rl);
    Publish in;
    ASSERT_EQ(parse_publish(pk, kMqtt311, in), Error::None);
    EXPECT_EQ(in.topic, topic);
    EXPECT_EQ(in.payload, payload);
  }
}

TEST(MqttCodec, Connect311VariableHeaderAsInTheSpecExample) {
  // 3.1.1 figure 3.6: level 4, flags 0xCE (user, password, will QoS 1, will,
  // clean session), keep alive 10.
  ConnectOptions o;
  o.version = kMqtt311;
  o.keepalive_s = 10;
  o.client_id = "cid";
  o.will = Will{"w/t", "bye", 1, false};
  o.username = "u";
  o.password = "pw";
  std::string out;
  ASSERT_EQ(encode_connect(out, o), Error::None);
  const std::string expect = bytes({0x10, 32, 0x00, 0x04, 'M', 'Q', 'T', 'T', 0x04, 0xCE, 0x00, 0x0A,
                                    0x00, 0x03, 'c', 'i', 'd', 0x00, 0x03, 'w', '/', 't', 0x00, 0x03,
                                    'b', 'y', 'e', 0x00, 0x01, 'u', 0x00, 0x02, 'p', 'w'});
  EXPECT_EQ(hex(out), hex(expect));
}

TEST(MqttCodec, Connect5VariableHeaderAsInTheSpecExample) {
  // MQTT 5 figure 3-6: flags 0xCE, keep alive 10, properties (length 5):
  // Session Expiry Interval 10.
  ConnectOptions o;
  o.version = kMqtt5;
  o.keepalive_s = 10;
  o.client_id = "";
  o.will = Will{"w", "x", 1, false};
  o.username = "u";
  o.password = "p";
  o.session_expiry = 10;
  std::string out;
  ASSERT_EQ(encode_connect(out, o), Error::None);
  const std::string vh = bytes({0x00, 0x04, 'M', 'Q', 'T', 'T', 0x05, 0xCE, 0x00, 0x0A, 0x05, 0x11, 0x00, 0x00,
                                0x00, 0x0A});
  ASSERT_GT(out.size(), 2 + vh.size());
  EXPECT_EQ(hex(out.substr(2, vh.size())), hex(vh));
  // Payload: client id "", will properties (none), will topic, payload, user, password.
  EXPECT_EQ(hex(out.substr(2 + vh.size())),
            hex(bytes({0x00, 0x00, 0x00, 0x00, 0x01, 'w', 0x00, 0x01, 'x', 0x00, 0x01, 'u', 0x00, 0x01, 'p'})));
  EXPECT_EQ(static_cast<unsigned char>(out[1]), out.size() - 2);
  // Receive Maximum and Maximum Packet Size follow, in that order.
  out.clear();
  o.receive_maximum = 20;
  o.maximum_packet_size = 1024;
  ASSERT_EQ(encode_connect(out, o), Error::None);
  EXPECT_EQ(hex(out.substr(12, 14)),
            hex(bytes({0x0D, 0x11, 0x00, 0x00, 0x00, 0x0A, 0x21, 0x00, 0x14, 0x27, 0x00, 0x00, 0x04, 0x00})));
}

TEST(MqttCodec, ConnectMinimalAndRetainedWill) {
  ConnectOptions o;
  o.version = kMqtt311;
  o.keepalive_s = 60;
  o.client_id = "c";
  std::string out;
  ASSERT_EQ(encode_connect(out, o), Error::None);
  EXPECT_EQ(hex(out), hex(bytes({0x10, 0x0D, 0, 4, 'M', 'Q', 'T', 'T', 4, 0x02, 0, 60, 0, 1, 'c'})));
  out.clear();
  o.will = Will{"s", "off", 1, true};
  o.clean_start = false;
  ASSERT_EQ(encode_connect(out, o), Error::None);
  EXPECT_EQ(static_cast<unsigned char>(out[9]), 0x2C);  // will retain, will QoS 1, will flag
}

TEST(MqttCodec, ConnectRefusesWhatTheProtocolForbids) {
  ConnectOptions o;
  o.version = kMqtt311;
  o.client_id = "c";
  o.password = "p";  // 3.1.1: password without user name
  std::string out = "keep";
  EXPECT_EQ(encode_connect(out, o), Error::BadArgument);
  EXPECT_EQ(out, "keep");  // nothing appended
  o.version = kMqtt5;
  EXPECT_EQ(encode_connect(out, o), Error::None);  // allowed in 5
  out.clear();
  o.client_id = std::string_view("a\0b", 3);
  EXPECT_EQ(encode_connect(out, o), Error::BadString);
  o.client_id = "c";
  o.will = Will{"a/#", "x", 0, false};
  EXPECT_EQ(encode_connect(out, o), Error::BadArgument);
  o.will.reset();
  o.version = 3;
  EXPECT_EQ(encode_connect(out, o), Error::BadArgument);
  EXPECT_TRUE(out.empty());
}

TEST(MqttCodec, PublishExactBytes) {
  // 3.1.1 section 3.3.2.3: topic "a/b", packet id 10.
  Publish p;
  p.topic = "a/b";
  p.payload = "hi";
  p.qos = 1;
  p.packet_id = 10;
  std::string out;
  ASSERT_EQ(encode_publish(out, kMqtt311, p), Error::None);
  EXPECT_EQ(hex(out), hex(bytes({0x32, 0x09, 0x00, 0x03, 'a', '/', 'b', 0x00, 0x0A, 'h', 'i'})));
  // v5, QoS 0, retained, no properties: a zero property length.
  out.clear();
  p.qos = 0;
  p.packet_id = 0;
  p.retain = true;
  ASSERT_EQ(encode_publish(out, kMqtt5, p), Error::None);
  EXPECT_EQ(hex(out), hex(bytes({0x31, 0x08, 0x00, 0x03, 'a', '/', 'b', 0x00, 'h', 'i'})));
  // DUP on a QoS 1 resend.
  out.clear();
  p.qos = 1;
  p.packet_id = 0x1234;
  p.retain = false;
  p.dup = true;
  ASSERT_EQ(encode_publish(out, kMqtt311, p), Error::None);
  EXPECT_EQ(static_cast<unsigned char>(out[0]), 0x3A);
}

TEST(MqttCodec, PublishAppendsToTheCallersBuffer) {
  std::string out = "xy";
  Publish p;
  p.topic = "t";
  ASSERT_EQ(encode_publish(out, kMqtt311, p), Error::None);
  ASSERT_EQ(encode_publish(out, kMqtt311, p), Error::None);
  EXPECT_EQ(hex(out), hex(bytes({'x', 'y', 0x30, 0x03, 0x00, 0x01, 't', 0x30, 0x03, 0x00, 0x01, 't'})));
}

TEST(MqttCodec, Publish5PropertiesRoundTrip) {
  Publish p;
  p.topic = "replies/me";
  p.payload = R"({"value":42})";
  p.qos = 1;
  p.packet_id = 7;
  const std::string corr("c\0rr", 4);
  p.props.payload_format = 1;
  p.props.content_type = "application/json";
  p.props.response_topic = "r/t";
  p.props.correlation_data = corr;
  p.props.user = {{"status", "200"}, {"authorization", "Bearer x"}};
  std::string out;
  ASSERT_EQ(encode_publish(out, kMqtt5, p), Error::None);
  EXPECT_EQ(publish_size(kMqtt5, p), out.size());
  // Properties in the order written: 01 01, 03 <ct>, 08 <rt>, 09 <cd>, 26 <k,v> x2.
  const std::size_t props_at = 2 + 2 + p.topic.size() + 2;
  const std::size_t props_len = 2 + (3 + 16) + (3 + 3) + (3 + 4) + (5 + 6 + 3) + (5 + 13 + 8);
  ASSERT_EQ(static_cast<unsigned char>(out[props_at]), props_len);
  EXPECT_EQ(hex(out.substr(props_at + 1, 4)), hex(bytes({0x01, 0x01, 0x03, 0x00})));

  Decoder dec;
  Packet pk = one_packet(dec, out);
  EXPECT_EQ(pk.type, PacketType::Publish);
  Publish in;
  ASSERT_EQ(parse_publish(pk, kMqtt5, in), Error::None);
  EXPECT_EQ(in.topic, "replies/me");
  EXPECT_EQ(in.payload, p.payload);
  EXPECT_EQ(in.qos, 1);
  EXPECT_EQ(in.packet_id, 7);
  ASSERT_TRUE(in.props.payload_format && in.props.content_type && in.props.response_topic &&
              in.props.correlation_data);
  EXPECT_EQ(*in.props.payload_format, 1);
  EXPECT_EQ(*in.props.content_type, "application/json");
  EXPECT_EQ(*in.props.response_topic, "r/t");
  EXPECT_EQ(*in.props.correlation_data, corr);
  ASSERT_EQ(in.props.user.size(), 2u);
  EXPECT_EQ(in.props.user[1].name, "authorization");
  EXPECT_EQ(in.props.user[1].value, "Bearer x");
}

TEST(MqttCodec, PublishRefusesBadTopicsAndArguments) {
  std::string out;
  Publish p;
  p.topic = "";
  EXPECT_EQ(encode_publish(out, kMqtt5, p), Error::BadArgument);
  p.topic = "a/+/b";
  EXPECT_EQ(encode_publish(out, kMqtt5, p), Error::BadArgument);
  p.topic = "a/#";
  EXPECT_EQ(encode_publish(out, kMqtt311, p), Error::BadArgument);
  p.topic = "\xC3\x28";  // invalid UTF-8
  EXPECT_EQ(encode_publish(out, kMqtt311, p), Error::BadString);
  p.topic = std::string_view("a\0b", 3);
  EXPECT_EQ(encode_publish(out, kMqtt311, p), Error::BadString);
  const std::string long_topic(65536, 'a');
  p.topic = long_topic;
  EXPECT_EQ(encode_publish(out, kMqtt311, p), Error::TooLong);
  p.topic = "ok";
  p.qos = 1;  // without a packet id
  EXPECT_EQ(encode_publish(out, kMqtt311, p), Error::BadArgument);
  p.qos = 3;
  p.packet_id = 1;
  EXPECT_EQ(encode_publish(out, kMqtt311, p), Error::BadArgument);
  p.qos = 0;
  p.props.response_topic = "r/+";
  EXPECT_EQ(encode_publish(out, kMqtt5, p), Error::BadArgument);
  EXPECT_EQ(encode_publish(out, kMqtt311, p), Error::None);  // no properties in 3.1.1
  EXPECT_EQ(hex(out), hex(bytes({0x30, 0x04, 0x00, 0x02, 'o', 'k'})));
}

TEST(MqttCodec, PubackSubscribePingDisconnectBytes) {
  std::string out;
  ASSERT_EQ(encode_puback(out, kMqtt311, 10), Error::None);
  ASSERT_EQ(encode_puback(out, kMqtt5, 10), Error::None);        // reason 0: short form
  ASSERT_EQ(encode_puback(out, kMqtt5, 10, 0x87), Error::None);  // not authorized
  EXPECT_EQ(hex(out), hex(bytes({0x40, 0x02, 0x00, 0x0A, 0x40, 0x02, 0x00, 0x0A, 0x40, 0x03, 0x00, 0x0A, 0x87})));
  EXPECT_EQ(encode_puback(out, kMqtt5, 0), Error::BadArgument);

  out.clear();
  const Subscription subs[] = {{"a/b", 1, true}};
  ASSERT_EQ(encode_subscribe(out, kMqtt311, 1, subs), Error::None);
  EXPECT_EQ(hex(out), hex(bytes({0x82, 0x08, 0x00, 0x01, 0x00, 0x03, 'a', '/', 'b', 0x01})));
  out.clear();
  ASSERT_EQ(encode_subscribe(out, kMqtt5, 1, subs), Error::None);  // no local: bit 2
  EXPECT_EQ(hex(out), hex(bytes({0x82, 0x09, 0x00, 0x01, 0x00, 0x00, 0x03, 'a', '/', 'b', 0x05})));

  out.clear();
  encode_pingreq(out);
  encode_disconnect(out, kMqtt311);
  encode_disconnect(out, kMqtt5);
  encode_disconnect(out, kMqtt5, 0x04);  // with Will
  EXPECT_EQ(hex(out), hex(bytes({0xC0, 0x00, 0xE0, 0x00, 0xE0, 0x00, 0xE0, 0x01, 0x04})));
}

TEST(MqttCodec, Connack311And5) {
  Decoder dec;
  Connack ca;
  ASSERT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x02, 0x01, 0x00})), kMqtt311, ca), Error::None);
  EXPECT_TRUE(ca.session_present);
  EXPECT_EQ(ca.code, 0);
  EXPECT_EQ(ca.receive_maximum, 65535);  // the default when absent

  // v5 with the properties the publisher uses.
  const std::string props = bytes({0x21, 0x00, 0x14,                     // Receive Maximum 20
                                   0x27, 0x00, 0x01, 0x00, 0x00,         // Maximum Packet Size 65536
                                   0x24, 0x00,                           // Maximum QoS 0
                                   0x25, 0x00,                           // Retain Available 0
                                   0x22, 0x00, 0x0A,                     // Topic Alias Maximum 10
                                   0x12, 0x00, 0x03, 'a', 'b', 'c',      // Assigned Client Identifier
                                   0x13, 0x00, 0x0F,                     // Server Keep Alive 15
                                   0x26, 0x00, 0x01, 'k', 0x00, 0x01, 'v'});  // User Property
  std::string wire = bytes({0x20, static_cast<int>(3 + props.size()), 0x00, 0x00, static_cast<int>(props.size())});
  wire += props;
  Connack c5;
  ASSERT_EQ(parse_connack(one_packet(dec, wire), kMqtt5, c5), Error::None);
  EXPECT_EQ(c5.receive_maximum, 20);
  ASSERT_TRUE(c5.maximum_packet_size);
  EXPECT_EQ(*c5.maximum_packet_size, 65536u);
  EXPECT_EQ(c5.maximum_qos, 0);
  EXPECT_FALSE(c5.retain_available);
  EXPECT_EQ(c5.topic_alias_maximum, 10);
  ASSERT_TRUE(c5.assigned_client_id);
  EXPECT_EQ(*c5.assigned_client_id, "abc");
  ASSERT_TRUE(c5.server_keepalive);
  EXPECT_EQ(*c5.server_keepalive, 15);

  // A 3.1.1 broker's answer to a v5 CONNECT: 2 bytes, code 1.
  Connack old;
  ASSERT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x02, 0x00, 0x01})), kMqtt5, old), Error::None);
  EXPECT_EQ(old.code, 1);
  // v5 refusal 0x84 (unsupported protocol version), empty properties.
  ASSERT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x03, 0x00, 0x84, 0x00})), kMqtt5, old), Error::None);
  EXPECT_EQ(old.code, 0x84);

  // Malformed: reserved ack flags, receive maximum 0, duplicate, unknown id.
  EXPECT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x02, 0x02, 0x00})), kMqtt311, old), Error::BadFlags);
  EXPECT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x06, 0x00, 0x00, 0x03, 0x21, 0x00, 0x00})), kMqtt5, old),
            Error::BadProperty);
  EXPECT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x07, 0x00, 0x00, 0x04, 0x24, 0x00, 0x24, 0x01})), kMqtt5,
                          old),
            Error::BadProperty);
  EXPECT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x05, 0x00, 0x00, 0x02, 0x7F, 0x00})), kMqtt5, old),
            Error::BadProperty);
  EXPECT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x03, 0x00, 0x00, 0x05})), kMqtt5, old), Error::Truncated);
  EXPECT_EQ(parse_connack(one_packet(dec, bytes({0x20, 0x03, 0x00, 0x00, 0x00})), kMqtt311, old),
            Error::TrailingBytes);
}

TEST(MqttCodec, PubackSubackDisconnectParse) {
  Decoder dec;
  std::uint16_t id = 0;
  std::uint8_t reason = 0xFF;
  ASSERT_EQ(parse_puback(one_packet(dec, bytes({0x40, 0x02, 0x00, 0x0A})), kMqtt5, id, reason), Error::None);
  EXPECT_EQ(id, 10);
  EXPECT_EQ(reason, 0);
  ASSERT_EQ(parse_puback(one_packet(dec, bytes({0x40, 0x03, 0x00, 0x0B, 0x90})), kMqtt5, id, reason), Error::None);
  EXPECT_EQ(reason, 0x90);
  ASSERT_EQ(parse_puback(one_packet(dec, bytes({0x40, 0x08, 0x00, 0x0C, 0x87, 0x04, 0x1F, 0x00, 0x01, 'x'})),
                         kMqtt5, id, reason),
            Error::None);
  EXPECT_EQ(id, 12);
  EXPECT_EQ(parse_puback(one_packet(dec, bytes({0x40, 0x03, 0x00, 0x0B, 0x00})), kMqtt311, id, reason),
            Error::TrailingBytes);
  EXPECT_EQ(parse_puback(one_packet(dec, bytes({0x40, 0x01, 0x00})), kMqtt5, id, reason), Error::Truncated);
  EXPECT_EQ(parse_puback(one_packet(dec, bytes({0x40, 0x02, 0x00, 0x00})), kMqtt5, id, reason), Error::BadArgument);

  std::vector<std::uint8_t> codes;
  ASSERT_EQ(parse_suback(one_packet(dec, bytes({0x90, 0x05, 0x00, 0x01, 0x01, 0x80, 0x00})), kMqtt311, id, codes),
            Error::None);
  EXPECT_EQ(codes, (std::vector<std::uint8_t>{0x01, 0x80, 0x00}));
  codes.clear();
  ASSERT_EQ(parse_suback(one_packet(dec, bytes({0x90, 0x04, 0x00, 0x02, 0x00, 0x01})), kMqtt5, id, codes),
            Error::None);
  EXPECT_EQ(codes, (std::vector<std::uint8_t>{0x01}));

  ASSERT_EQ(parse_disconnect(one_packet(dec, bytes({0xE0, 0x00})), kMqtt5, reason), Error::None);
  EXPECT_EQ(reason, 0);
  ASSERT_EQ(parse_disconnect(one_packet(dec, bytes({0xE0, 0x02, 0x8E, 0x00})), kMqtt5, reason), Error::None);
  EXPECT_EQ(reason, 0x8E);  // session taken over
}

TEST(MqttCodec, DecoderTakesPacketsSplitAnywhereAndManyPerChunk) {
  // A stream of mixed packets, incl. one with a 2-byte remaining length.
  std::string stream;
  Publish p;
  p.topic = "a/b";
  const std::string big(300, 'z');
  for (int i = 0; i < 5; ++i) {
    p.qos = i % 2 == 0 ? 0 : 1;
    p.packet_id = static_cast<std::uint16_t>(p.qos ? i + 1 : 0);
    p.payload = i == 3 ? std::string_view(big) : std::string_view("v");
    ASSERT_EQ(encode_publish(stream, kMqtt5, p), Error::None);
    ASSERT_EQ(encode_puback(stream, kMqtt5, static_cast<std::uint16_t>(100 + i)), Error::None);
  }
  stream += bytes({0xD0, 0x00});  // PINGRESP

  auto decode_all = [&](std::size_t chunk) {
    Decoder dec;
    std::vector<std::pair<PacketType, std::string>> got;
    for (std::size_t at = 0; at < stream.size(); at += chunk) {
      dec.feed(std::string_view(stream).substr(at, chunk));
      Packet pk;
      while (dec.next(pk)) got.emplace_back(pk.type, std::string(pk.body));
      EXPECT_EQ(dec.error(), Error::None);
    }
    EXPECT_EQ(dec.buffered(), 0u);
    return got;
  };
  const auto whole = decode_all(stream.size());
  ASSERT_EQ(whole.size(), 11u);
  EXPECT_EQ(whole.back().first, PacketType::Pingresp);
  EXPECT_EQ(whole[6].second.size(), 2 + 3 + 2 + 1 + 300u);
  for (std::size_t chunk : {1u, 2u, 3u, 7u, 64u}) EXPECT_EQ(decode_all(chunk), whole) << chunk;
}

TEST(MqttCodec, DecoderRejectsMalformedStreams) {
  auto first_error = [](const std::string& wire, std::size_t max = 1u << 20) {
    Decoder dec(max);
    dec.feed(wire);
    Packet p;
    while (dec.next(p)) {
    }
    return dec.error();
  };
  EXPECT_EQ(first_error(bytes({0x30, 0xFF, 0xFF, 0xFF, 0xFF, 0x7F})), Error::MalformedRemainingLength);
  EXPECT_EQ(first_error(bytes({0x30, 0xFF, 0xFF, 0xFF, 0x80})), Error::MalformedRemainingLength);  // 5th byte due
  EXPECT_EQ(first_error(bytes({0xD0, 0x80, 0x00})), Error::MalformedRemainingLength);  // not minimal
  EXPECT_EQ(first_error(bytes({0x00, 0x00})), Error::BadType);
  EXPECT_EQ(first_error(bytes({0x36, 0x00})), Error::BadFlags);  // QoS 3
  EXPECT_EQ(first_error(bytes({0x80, 0x00})), Error::BadFlags);  // SUBSCRIBE needs 0010
  EXPECT_EQ(first_error(bytes({0x41, 0x02, 0x00, 0x01})), Error::BadFlags);
  // Too large is known from the header alone, before the body arrives.
  EXPECT_EQ(first_error(bytes({0x30, 0x80, 0x08}), 1024), Error::PacketTooLarge);
  EXPECT_EQ(first_error(bytes({0x30, 0xFD, 0x07}), 1024), Error::None);  // 1021 + 3 = 1024: fits, incomplete

  // Sticky: nothing more after an error, even valid bytes.
  Decoder dec;
  dec.feed(bytes({0x00, 0x00}));
  Packet p;
  EXPECT_FALSE(dec.next(p));
  dec.feed(bytes({0xD0, 0x00}));
  EXPECT_FALSE(dec.next(p));
  EXPECT_EQ(dec.error(), Error::BadType);
  dec.reset();
  dec.feed(bytes({0xD0, 0x00}));
  EXPECT_TRUE(dec.next(p));
}

TEST(MqttCodec, PublishParseRejectsMalformedBodies) {
  Decoder dec;
  Publish in;
  // Topic length past the end.
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x03, 0x00, 0x05, 'a'})), kMqtt311, in), Error::Truncated);
  // Topic not UTF-8 / wildcard / empty.
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x04, 0x00, 0x02, 0xC0, 0x80})), kMqtt311, in),
            Error::BadString);
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x03, 0x00, 0x01, '#'})), kMqtt311, in), Error::BadArgument);
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x02, 0x00, 0x00})), kMqtt311, in), Error::BadArgument);
  // QoS 1 without its packet id / with id 0.
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x32, 0x03, 0x00, 0x01, 't'})), kMqtt311, in), Error::Truncated);
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x32, 0x05, 0x00, 0x01, 't', 0x00, 0x00})), kMqtt311, in),
            Error::BadArgument);
  // DUP with QoS 0.
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x38, 0x03, 0x00, 0x01, 't'})), kMqtt311, in), Error::BadFlags);
  // v5: property length past the end, a topic alias (never allowed by us),
  // an unknown property, a bad payload format indicator, a duplicate.
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x04, 0x00, 0x01, 't', 0x09})), kMqtt5, in),
            Error::Truncated);
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x07, 0x00, 0x01, 't', 0x03, 0x23, 0x00, 0x01})), kMqtt5, in),
            Error::BadProperty);
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x06, 0x00, 0x01, 't', 0x02, 0x7E, 0x00})), kMqtt5, in),
            Error::BadProperty);
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x06, 0x00, 0x01, 't', 0x02, 0x01, 0x02})), kMqtt5, in),
            Error::BadProperty);
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x08, 0x00, 0x01, 't', 0x04, 0x01, 0x00, 0x01, 0x01})),
                          kMqtt5, in),
            Error::BadProperty);
  // A string property running past the property block.
  EXPECT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x08, 0x00, 0x01, 't', 0x02, 0x08, 0x00, 0x05, 'x'})),
                          kMqtt5, in),
            Error::BadProperty);
  // Empty payload is fine; several user properties with the same name too.
  ASSERT_EQ(parse_publish(one_packet(dec, bytes({0x30, 0x11, 0x00, 0x01, 't', 0x0D, 0x26, 0x00, 0x01, 'k', 0x00,
                                                 0x00, 0x26, 0x00, 0x01, 'k', 0x00, 0x01, 'v'})),
                          kMqtt5, in),
            Error::None);
  EXPECT_EQ(in.props.user.size(), 2u);
  EXPECT_TRUE(in.payload.empty());
}

TEST(MqttCodec, Utf8Validation) {
  EXPECT_TRUE(valid_utf8("canopen/gw1/1/5/tpdo/1"));
  EXPECT_TRUE(valid_utf8("A\xF0\xAA\x9B\x94"));  // "A" U+2A6D4: the spec's example
  EXPECT_TRUE(valid_utf8("\xC3\xA9\xE2\x82\xAC\xF4\x8F\xBF\xBF"));  // é € U+10FFFF
  EXPECT_FALSE(valid_utf8(std::string_view("a\0", 2)));
  EXPECT_FALSE(valid_utf8("\xC0\x80"));          // overlong NUL
  EXPECT_FALSE(valid_utf8("\xE0\x80\xAF"));      // overlong '/'
  EXPECT_FALSE(valid_utf8("\xED\xA0\x80"));      // surrogate
  EXPECT_FALSE(valid_utf8("\xF4\x90\x80\x80"));  // beyond U+10FFFF
  EXPECT_FALSE(valid_utf8("\xE2\x82"));          // truncated
  EXPECT_FALSE(valid_utf8("\x80"));
  EXPECT_FALSE(valid_utf8("\xFF"));
}
