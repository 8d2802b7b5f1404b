// Decoding: the Decoder and the parse_*() functions (mqtt_codec.hpp).
#include "mqtt/mqtt_codec.hpp"

namespace gateway::mqtt::codec {

namespace {

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

}  // namespace

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
