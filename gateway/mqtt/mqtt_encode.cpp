// Encoding: the encode_*() functions and publish_size() (mqtt_codec.hpp).
#include <cstring>

#include "mqtt/mqtt_codec.hpp"

namespace gateway::mqtt::codec {

namespace {

// Writes into memory already sized by the caller (no bounds checks: the
// sizes are computed first).
struct Writer {
  char* p;
  void u8(std::uint8_t v) { *p++ = static_cast<char>(v); }
  void u16(std::uint16_t v) {
    u8(static_cast<std::uint8_t>(v >> 8));
    u8(static_cast<std::uint8_t>(v));
  }
  void u32(std::uint32_t v) {
    u16(static_cast<std::uint16_t>(v >> 16));
    u16(static_cast<std::uint16_t>(v));
  }
  void varint(std::uint32_t v) {
    do {
      auto b = static_cast<std::uint8_t>(v & 0x7F);
      v >>= 7;
      if (v > 0) b |= 0x80;
      u8(b);
    } while (v > 0);
  }
  void raw(std::string_view s) {
    if (!s.empty()) std::memcpy(p, s.data(), s.size());
    p += s.size();
  }
  void str(std::string_view s) {  // UTF-8 string or binary data: u16 length + bytes
    u16(static_cast<std::uint16_t>(s.size()));
    raw(s);
  }
};

// Appends `size` bytes to out and returns a Writer over them.
Writer grow(std::string& out, std::size_t size) {
  const std::size_t at = out.size();
  out.resize(at + size);
  return Writer{out.data() + at};
}

constexpr std::size_t kMaxString = 65535;

std::size_t publish_props_size(const PublishProperties& pp) {
  std::size_t n = 0;
  if (pp.payload_format) n += 2;
  if (pp.content_type) n += 3 + pp.content_type->size();
  if (pp.response_topic) n += 3 + pp.response_topic->size();
  if (pp.correlation_data) n += 3 + pp.correlation_data->size();
  for (const auto& u : pp.user) n += 5 + u.name.size() + u.value.size();
  return n;
}

Error check_publish_props(const PublishProperties& pp) {
  auto ok_str = [](std::string_view s) { return s.size() <= kMaxString; };
  if (pp.payload_format && *pp.payload_format > 1) return Error::BadArgument;
  if (pp.content_type && (!ok_str(*pp.content_type) || !valid_utf8(*pp.content_type))) return Error::BadString;
  if (pp.response_topic) {
    if (!ok_str(*pp.response_topic) || !valid_utf8(*pp.response_topic)) return Error::BadString;
    if (pp.response_topic->empty() || pp.response_topic->find_first_of("+#") != std::string_view::npos)
      return Error::BadArgument;
  }
  if (pp.correlation_data && !ok_str(*pp.correlation_data)) return Error::TooLong;
  for (const auto& u : pp.user)
    if (!ok_str(u.name) || !ok_str(u.value) || !valid_utf8(u.name) || !valid_utf8(u.value)) return Error::BadString;
  return Error::None;
}

void write_publish_props(Writer& w, const PublishProperties& pp) {
  if (pp.payload_format) {
    w.u8(prop::PayloadFormatIndicator);
    w.u8(*pp.payload_format);
  }
  if (pp.content_type) {
    w.u8(prop::ContentType);
    w.str(*pp.content_type);
  }
  if (pp.response_topic) {
    w.u8(prop::ResponseTopic);
    w.str(*pp.response_topic);
  }
  if (pp.correlation_data) {
    w.u8(prop::CorrelationData);
    w.str(*pp.correlation_data);
  }
  for (const auto& u : pp.user) {
    w.u8(prop::UserProperty);
    w.str(u.name);
    w.str(u.value);
  }
}

Error check_string(std::string_view s) {
  if (s.size() > kMaxString) return Error::TooLong;
  return valid_utf8(s) ? Error::None : Error::BadString;
}

void append_str(std::string& out, std::string_view s) {
  out.push_back(static_cast<char>(s.size() >> 8));
  out.push_back(static_cast<char>(s.size() & 0xFF));
  out.append(s);
}

void append_u16(std::string& out, std::uint16_t v) {
  out.push_back(static_cast<char>(v >> 8));
  out.push_back(static_cast<char>(v & 0xFF));
}

void append_u32(std::string& out, std::uint32_t v) {
  append_u16(out, static_cast<std::uint16_t>(v >> 16));
  append_u16(out, static_cast<std::uint16_t>(v & 0xFFFF));
}

}  // namespace

Error encode_connect(std::string& out, const ConnectOptions& o) {
  if (o.version != kMqtt311 && o.version != kMqtt5) return Error::BadArgument;
  const bool v5 = o.version == kMqtt5;
  if (Error e = check_string(o.client_id); e != Error::None) return e;
  if (o.will) {
    if (o.will->qos > 2 || o.will->topic.empty() || o.will->topic.find_first_of("+#") != std::string_view::npos)
      return Error::BadArgument;
    if (Error e = check_string(o.will->topic); e != Error::None) return e;
    if (o.will->payload.size() > kMaxString) return Error::TooLong;
  }
  if (o.username)
    if (Error e = check_string(*o.username); e != Error::None) return e;
  if (o.password && o.password->size() > kMaxString) return Error::TooLong;
  // 3.1.1 (3.1.2.9): a password needs a user name.
  if (!v5 && o.password && !o.username) return Error::BadArgument;
  if (o.receive_maximum && *o.receive_maximum == 0) return Error::BadArgument;
  if (o.maximum_packet_size && *o.maximum_packet_size == 0) return Error::BadArgument;

  // Not on the hot path: built in a local body, then header + body.
  std::string body;
  body.reserve(64 + o.client_id.size() + (o.will ? o.will->topic.size() + o.will->payload.size() : 0));
  append_str(body, "MQTT");
  body.push_back(static_cast<char>(o.version));
  std::uint8_t flags = 0;
  if (o.username) flags |= 0x80;
  if (o.password) flags |= 0x40;
  if (o.will) {
    flags |= 0x04;
    flags = static_cast<std::uint8_t>(flags | o.will->qos << 3);
    if (o.will->retain) flags |= 0x20;
  }
  if (o.clean_start) flags |= 0x02;
  body.push_back(static_cast<char>(flags));
  append_u16(body, o.keepalive_s);
  if (v5) {
    std::string props;
    if (o.session_expiry) {
      props.push_back(static_cast<char>(prop::SessionExpiryInterval));
      append_u32(props, *o.session_expiry);
    }
    if (o.receive_maximum) {
      props.push_back(static_cast<char>(prop::ReceiveMaximum));
      append_u16(props, *o.receive_maximum);
    }
    if (o.maximum_packet_size) {
      props.push_back(static_cast<char>(prop::MaximumPacketSize));
      append_u32(props, *o.maximum_packet_size);
    }
    put_varint(body, static_cast<std::uint32_t>(props.size()));
    body += props;
  }
  append_str(body, o.client_id);
  if (o.will) {
    if (v5) body.push_back(0);  // no will properties
    append_str(body, o.will->topic);
    append_str(body, o.will->payload);
  }
  if (o.username) append_str(body, *o.username);
  if (o.password) append_str(body, *o.password);
  if (body.size() > kMaxRemainingLength) return Error::TooLong;
  out.push_back(static_cast<char>(0x10));
  put_varint(out, static_cast<std::uint32_t>(body.size()));
  out += body;
  return Error::None;
}

namespace {
// Remaining length of a PUBLISH, or 0 when it cannot be encoded.
std::size_t publish_remaining(std::uint8_t version, const Publish& p, std::size_t& props_len) {
  props_len = version == kMqtt5 ? publish_props_size(p.props) : 0;
  std::size_t rl = 2 + p.topic.size() + (p.qos > 0 ? 2 : 0) + p.payload.size();
  if (version == kMqtt5) rl += varint_size(static_cast<std::uint32_t>(props_len)) + props_len;
  return rl;
}
}  // namespace

std::size_t publish_size(std::uint8_t version, const Publish& p) {
  std::size_t props_len;
  const std::size_t rl = publish_remaining(version, p, props_len);
  if (rl > kMaxRemainingLength) return 0;
  return 1 + varint_size(static_cast<std::uint32_t>(rl)) + rl;
}

Error encode_publish(std::string& out, std::uint8_t version, const Publish& p) {
  if (version != kMqtt311 && version != kMqtt5) return Error::BadArgument;
  if (p.qos > 2 || (p.qos > 0 && p.packet_id == 0) || (p.qos == 0 && p.dup)) return Error::BadArgument;
  // No topic aliases: a topic name is needed, and wildcards are for filters.
  if (p.topic.empty() || p.topic.find_first_of("+#") != std::string_view::npos) return Error::BadArgument;
  if (Error e = check_string(p.topic); e != Error::None) return e;
  if (version == kMqtt5 && !p.props.empty())
    if (Error e = check_publish_props(p.props); e != Error::None) return e;
  std::size_t props_len;
  const std::size_t rl = publish_remaining(version, p, props_len);
  if (rl > kMaxRemainingLength) return Error::TooLong;
  const auto rl32 = static_cast<std::uint32_t>(rl);
  Writer w = grow(out, 1 + varint_size(rl32) + rl);
  w.u8(static_cast<std::uint8_t>(0x30 | (p.dup ? 0x08 : 0) | p.qos << 1 | (p.retain ? 1 : 0)));
  w.varint(rl32);
  w.str(p.topic);
  if (p.qos > 0) w.u16(p.packet_id);
  if (version == kMqtt5) {
    w.varint(static_cast<std::uint32_t>(props_len));
    if (props_len > 0) write_publish_props(w, p.props);
  }
  w.raw(p.payload);
  return Error::None;
}

Error encode_puback(std::string& out, std::uint8_t version, std::uint16_t packet_id, std::uint8_t reason) {
  if (packet_id == 0) return Error::BadArgument;
  const bool with_reason = version == kMqtt5 && reason != 0;
  Writer w = grow(out, with_reason ? 5 : 4);
  w.u8(0x40);
  w.u8(with_reason ? 3 : 2);
  w.u16(packet_id);
  if (with_reason) w.u8(reason);
  return Error::None;
}

Error encode_subscribe(std::string& out, std::uint8_t version, std::uint16_t packet_id,
                       std::span<const Subscription> subs) {
  if (packet_id == 0 || subs.empty()) return Error::BadArgument;
  std::size_t rl = 2 + (version == kMqtt5 ? 1 : 0);
  for (const auto& s : subs) {
    if (s.filter.empty() || s.qos > 2) return Error::BadArgument;
    if (Error e = check_string(s.filter); e != Error::None) return e;
    rl += 3 + s.filter.size();
  }
  if (rl > kMaxRemainingLength) return Error::TooLong;
  const auto rl32 = static_cast<std::uint32_t>(rl);
  Writer w = grow(out, 1 + varint_size(rl32) + rl);
  w.u8(0x82);  // SUBSCRIBE's fixed-header flags are 0010
  w.varint(rl32);
  w.u16(packet_id);
  if (version == kMqtt5) w.u8(0);  // no properties
  for (const auto& s : subs) {
    w.str(s.filter);
    w.u8(static_cast<std::uint8_t>(s.qos | (version == kMqtt5 && s.no_local ? 0x04 : 0)));
  }
  return Error::None;
}

void encode_pingreq(std::string& out) { out.append("\xC0\x00", 2); }

void encode_disconnect(std::string& out, std::uint8_t version, std::uint8_t reason) {
  if (version == kMqtt5 && reason != 0) {
    out.append("\xE0\x01", 2);
    out.push_back(static_cast<char>(reason));
  } else {
    out.append("\xE0\x00", 2);
  }
}

}  // namespace gateway::mqtt::codec
