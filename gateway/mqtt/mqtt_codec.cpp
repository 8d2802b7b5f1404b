#include "mqtt/mqtt_codec.hpp"

#include <cstring>

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

// Reads the fields of a packet body; every read checks the bounds.
struct Reader {
  std::string_view s;
  std::size_t p = 0;
  std::size_t left() const { return s.size() - p; }
  bool u8(std::uint8_t& v) {
    if (left() < 1) return false;
    v = static_cast<std::uint8_t>(s[p++]);
    return true;
  }
  bool u16(std::uint16_t& v) {
    if (left() < 2) return false;
    v = static_cast<std::uint16_t>(static_cast<unsigned>(static_cast<std::uint8_t>(s[p])) << 8 |
                                   static_cast<std::uint8_t>(s[p + 1]));
    p += 2;
    return true;
  }
  bool u32(std::uint32_t& v) {
    std::uint16_t hi = 0, lo = 0;
    if (left() < 4) return false;
    u16(hi);
    u16(lo);
    v = static_cast<std::uint32_t>(hi) << 16 | lo;
    return true;
  }
  // Error::None, Truncated or MalformedRemainingLength (over 4 bytes / not minimal).
  Error varint(std::uint32_t& v) {
    v = 0;
    for (unsigned i = 0; i < 4; ++i) {
      std::uint8_t b;
      if (!u8(b)) return Error::Truncated;
      v |= static_cast<std::uint32_t>(b & 0x7F) << (7 * i);
      if ((b & 0x80) == 0) return (b == 0 && i > 0) ? Error::MalformedRemainingLength : Error::None;
    }
    return Error::MalformedRemainingLength;
  }
  bool bin(std::string_view& out) {
    std::uint16_t n;
    if (!u16(n) || left() < n) return false;
    out = s.substr(p, n);
    p += n;
    return true;
  }
  Error str(std::string_view& out) {
    if (!bin(out)) return Error::Truncated;
    return valid_utf8(out) ? Error::None : Error::BadString;
  }
};

enum class PropType : std::uint8_t { None, Byte, U16, U32, Varint, String, Binary, Pair };

PropType prop_type(std::uint32_t id) {
  switch (id) {
    case prop::PayloadFormatIndicator: case prop::RequestProblemInformation: case prop::RequestResponseInformation:
    case prop::MaximumQoS: case prop::RetainAvailable: case prop::WildcardSubscriptionAvailable:
    case prop::SubscriptionIdentifierAvailable: case prop::SharedSubscriptionAvailable:
      return PropType::Byte;
    case prop::ServerKeepAlive: case prop::ReceiveMaximum: case prop::TopicAliasMaximum: case prop::TopicAlias:
      return PropType::U16;
    case prop::MessageExpiryInterval: case prop::SessionExpiryInterval: case prop::WillDelayInterval:
    case prop::MaximumPacketSize:
      return PropType::U32;
    case prop::SubscriptionIdentifier:
      return PropType::Varint;
    case prop::ContentType: case prop::ResponseTopic: case prop::AssignedClientIdentifier:
    case prop::AuthenticationMethod: case prop::ResponseInformation: case prop::ServerReference:
    case prop::ReasonString:
      return PropType::String;
    case prop::CorrelationData: case prop::AuthenticationData:
      return PropType::Binary;
    case prop::UserProperty:
      return PropType::Pair;
    default:
      return PropType::None;
  }
}

struct PropValue {
  std::uint32_t num = 0;
  std::string_view a, b;
};

// Reads a property block (length + properties) and calls
// on(id, value) -> Error for each; only User Property and Subscription
// Identifier may repeat.
template <class F>
Error read_properties(Reader& r, F&& on) {
  std::uint32_t len;
  if (Error e = r.varint(len); e != Error::None) return e == Error::Truncated ? e : Error::BadProperty;
  if (len > r.left()) return Error::Truncated;
  Reader pr{r.s.substr(r.p, len)};
  r.p += len;
  std::uint64_t seen = 0;
  while (pr.left() > 0) {
    std::uint32_t id;
    if (pr.varint(id) != Error::None) return Error::BadProperty;
    const PropType t = prop_type(id);
    if (t == PropType::None) return Error::BadProperty;
    if (id != prop::UserProperty && id != prop::SubscriptionIdentifier) {
      const std::uint64_t bit = std::uint64_t{1} << id;
      if (seen & bit) return Error::BadProperty;
      seen |= bit;
    }
    PropValue v;
    bool ok = true;
    switch (t) {
      case PropType::Byte: {
        std::uint8_t b;
        ok = pr.u8(b);
        v.num = b;
        break;
      }
      case PropType::U16: {
        std::uint16_t x;
        ok = pr.u16(x);
        v.num = x;
        break;
      }
      case PropType::U32: ok = pr.u32(v.num); break;
      case PropType::Varint:
        if (pr.varint(v.num) != Error::None) return Error::BadProperty;
        break;
      case PropType::String:
        if (Error e = pr.str(v.a); e != Error::None) return e == Error::Truncated ? Error::BadProperty : e;
        break;
      case PropType::Binary: ok = pr.bin(v.a); break;
      case PropType::Pair:
        if (Error e = pr.str(v.a); e != Error::None) return e == Error::Truncated ? Error::BadProperty : e;
        if (Error e = pr.str(v.b); e != Error::None) return e == Error::Truncated ? Error::BadProperty : e;
        break;
      case PropType::None: return Error::BadProperty;
    }
    if (!ok) return Error::BadProperty;
    if (Error e = on(static_cast<std::uint8_t>(id), v); e != Error::None) return e;
  }
  return Error::None;
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

// --- Decoder -----------------------------------------------------------

void Decoder::reset() {
  buf_.clear();
  pos_ = 0;
  error_ = Error::None;
}

void Decoder::feed(std::string_view chunk) {
  if (pos_ == buf_.size()) {
    buf_.clear();
    pos_ = 0;
  } else if (pos_ > 0) {
    buf_.erase(0, pos_);
    pos_ = 0;
  }
  buf_.append(chunk);
}

namespace {
Error check_flags(PacketType t, std::uint8_t flags) {
  switch (t) {
    case PacketType::Publish: return ((flags >> 1) & 3) == 3 ? Error::BadFlags : Error::None;
    case PacketType::Pubrel: case PacketType::Subscribe: case PacketType::Unsubscribe:
      return flags == 0x2 ? Error::None : Error::BadFlags;
    default: return flags == 0 ? Error::None : Error::BadFlags;
  }
}
}  // namespace

bool Decoder::next(Packet& out) {
  if (error_ != Error::None) return false;
  const std::size_t avail = buf_.size() - pos_;
  if (avail < 1) return false;
  const auto* d = reinterpret_cast<const std::uint8_t*>(buf_.data() + pos_);
  const std::uint8_t type = d[0] >> 4;
  const auto flags = static_cast<std::uint8_t>(d[0] & 0x0F);
  if (type == 0) {
    error_ = Error::BadType;
    return false;
  }
  if (Error e = check_flags(static_cast<PacketType>(type), flags); e != Error::None) {
    error_ = e;
    return false;
  }
  std::uint32_t rl = 0;
  std::size_t i = 1;
  for (;;) {
    if (i >= avail) return false;  // the length is not complete yet
    const std::uint8_t b = d[i];
    rl |= static_cast<std::uint32_t>(b & 0x7F) << (7 * (i - 1));
    ++i;
    if ((b & 0x80) == 0) {
      if (b == 0 && i > 2) {  // not the minimal encoding
        error_ = Error::MalformedRemainingLength;
        return false;
      }
      break;
    }
    if (i == 5) {
      error_ = Error::MalformedRemainingLength;
      return false;
    }
  }
  const std::size_t total = i + rl;
  if (total > max_) {
    error_ = Error::PacketTooLarge;
    return false;
  }
  if (avail < total) return false;
  out.type = static_cast<PacketType>(type);
  out.flags = flags;
  out.body = std::string_view(buf_).substr(pos_ + i, rl);
  pos_ += total;
  return true;
}

// --- packet bodies -----------------------------------------------------

Error parse_connack(const Packet& p, std::uint8_t version, Connack& out) {
  if (p.type != PacketType::Connack) return Error::BadType;
  Reader r{p.body};
  std::uint8_t flags;
  if (!r.u8(flags) || !r.u8(out.code)) return Error::Truncated;
  if (flags & 0xFE) return Error::BadFlags;
  out.session_present = (flags & 1) != 0;
  // A 3.1.1 broker answers a v5 CONNECT with a 2-byte CONNACK (code 1).
  if (version != kMqtt5 || r.left() == 0) return r.left() == 0 ? Error::None : Error::TrailingBytes;
  Error e = read_properties(r, [&](std::uint8_t id, const PropValue& v) -> Error {
    switch (id) {
      case prop::ReceiveMaximum:
        if (v.num == 0) return Error::BadProperty;
        out.receive_maximum = static_cast<std::uint16_t>(v.num);
        break;
      case prop::MaximumPacketSize:
        if (v.num == 0) return Error::BadProperty;
        out.maximum_packet_size = v.num;
        break;
      case prop::MaximumQoS:
        if (v.num > 1) return Error::BadProperty;
        out.maximum_qos = static_cast<std::uint8_t>(v.num);
        break;
      case prop::RetainAvailable:
        if (v.num > 1) return Error::BadProperty;
        out.retain_available = v.num == 1;
        break;
      case prop::TopicAliasMaximum: out.topic_alias_maximum = static_cast<std::uint16_t>(v.num); break;
      case prop::AssignedClientIdentifier: out.assigned_client_id = v.a; break;
      case prop::ServerKeepAlive: out.server_keepalive = static_cast<std::uint16_t>(v.num); break;
      case prop::ReasonString: out.reason_string = v.a; break;
      case prop::SessionExpiryInterval: case prop::WildcardSubscriptionAvailable:
      case prop::SubscriptionIdentifierAvailable: case prop::SharedSubscriptionAvailable:
      case prop::ResponseInformation: case prop::ServerReference: case prop::AuthenticationMethod:
      case prop::AuthenticationData: case prop::UserProperty:
        break;  // allowed, not used
      default: return Error::BadProperty;
    }
    return Error::None;
  });
  if (e != Error::None) return e;
  return r.left() == 0 ? Error::None : Error::TrailingBytes;
}

Error parse_publish(const Packet& p, std::uint8_t version, Publish& out) {
  if (p.type != PacketType::Publish) return Error::BadType;
  out.qos = static_cast<std::uint8_t>((p.flags >> 1) & 3);
  out.dup = (p.flags & 0x08) != 0;
  out.retain = (p.flags & 0x01) != 0;
  out.packet_id = 0;
  out.props = PublishProperties{};
  if (out.qos == 0 && out.dup) return Error::BadFlags;
  Reader r{p.body};
  if (Error e = r.str(out.topic); e != Error::None) return e;
  // The client never allows topic aliases, so a topic name is required.
  if (out.topic.empty() || out.topic.find_first_of("+#") != std::string_view::npos) return Error::BadArgument;
  if (out.qos > 0) {
    if (!r.u16(out.packet_id)) return Error::Truncated;
    if (out.packet_id == 0) return Error::BadArgument;
  }
  if (version == kMqtt5) {
    Error e = read_properties(r, [&](std::uint8_t id, const PropValue& v) -> Error {
      switch (id) {
        case prop::PayloadFormatIndicator:
          if (v.num > 1) return Error::BadProperty;
          out.props.payload_format = static_cast<std::uint8_t>(v.num);
          break;
        case prop::ContentType: out.props.content_type = v.a; break;
        case prop::ResponseTopic: out.props.response_topic = v.a; break;
        case prop::CorrelationData: out.props.correlation_data = v.a; break;
        case prop::UserProperty: out.props.user.push_back({v.a, v.b}); break;
        case prop::MessageExpiryInterval: case prop::SubscriptionIdentifier: break;
        default: return Error::BadProperty;  // incl. Topic Alias: never allowed by this client
      }
      return Error::None;
    });
    if (e != Error::None) return e;
  }
  out.payload = p.body.substr(r.p);
  return Error::None;
}

namespace {
// v5 reason-string / user-property blocks of acks: checked, not used.
Error skip_ack_properties(Reader& r) {
  return read_properties(r, [](std::uint8_t id, const PropValue&) -> Error {
    return id == prop::ReasonString || id == prop::UserProperty ? Error::None : Error::BadProperty;
  });
}
}  // namespace

Error parse_puback(const Packet& p, std::uint8_t version, std::uint16_t& packet_id, std::uint8_t& reason) {
  if (p.type != PacketType::Puback && p.type != PacketType::Pubrec && p.type != PacketType::Pubrel &&
      p.type != PacketType::Pubcomp)
    return Error::BadType;
  Reader r{p.body};
  reason = 0;
  if (!r.u16(packet_id)) return Error::Truncated;
  if (packet_id == 0) return Error::BadArgument;
  if (version == kMqtt5) {
    if (r.left() > 0) r.u8(reason);
    if (r.left() > 0)
      if (Error e = skip_ack_properties(r); e != Error::None) return e;
  }
  return r.left() == 0 ? Error::None : Error::TrailingBytes;
}

Error parse_suback(const Packet& p, std::uint8_t version, std::uint16_t& packet_id, std::vector<std::uint8_t>& codes) {
  if (p.type != PacketType::Suback) return Error::BadType;
  Reader r{p.body};
  if (!r.u16(packet_id)) return Error::Truncated;
  if (version == kMqtt5)
    if (Error e = skip_ack_properties(r); e != Error::None) return e;
  if (r.left() == 0) return Error::Truncated;  // at least one code
  while (r.left() > 0) {
    std::uint8_t c;
    r.u8(c);
    codes.push_back(c);
  }
  return Error::None;
}

Error parse_disconnect(const Packet& p, std::uint8_t version, std::uint8_t& reason) {
  if (p.type != PacketType::Disconnect) return Error::BadType;
  reason = 0;
  Reader r{p.body};
  if (version != kMqtt5) return r.left() == 0 ? Error::None : Error::TrailingBytes;
  if (r.left() > 0) r.u8(reason);
  if (r.left() > 0) {
    Error e = read_properties(r, [](std::uint8_t id, const PropValue&) -> Error {
      return id == prop::ReasonString || id == prop::UserProperty || id == prop::ServerReference ||
                     id == prop::SessionExpiryInterval
                 ? Error::None
                 : Error::BadProperty;
    });
    if (e != Error::None) return e;
  }
  return r.left() == 0 ? Error::None : Error::TrailingBytes;
}

}  // namespace gateway::mqtt::codec
