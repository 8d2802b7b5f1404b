// Sans-I/O MQTT packet encoding and decoding, protocol levels 4 (3.1.1)
// and 5, for the client side of the packets the gateway uses: CONNECT,
// CONNACK, PUBLISH (QoS 0/1), PUBACK, SUBSCRIBE/SUBACK, PINGREQ/PINGRESP,
// DISCONNECT. No sockets, no threads, no exceptions: every function returns
// an Error.
//
// Encoding: encode_*() append one packet to the caller's std::string (the
// caller keeps and reuses it, so the hot path does not allocate once its
// capacity has grown). On error nothing is appended.
//
// Decoding: a Decoder is fed byte chunks as they come from the socket (a
// packet may be split anywhere, a chunk may hold many packets); next()
// hands out one complete packet at a time as views into the decoder's
// buffer, valid until the next feed(). The parse_*() functions turn a
// Packet into the fields of its type. A malformed stream (bad remaining
// length, reserved flags, a packet over the maximum size) makes the
// decoder fail for good: the connection must be closed.
//
// Thread safety: none; a Decoder belongs to one connection.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace gateway::mqtt::codec {

enum class Error : std::uint8_t {
  None = 0,
  MalformedRemainingLength,  // more than 4 bytes, or not minimal
  BadFlags,                  // reserved fixed-header flags, QoS 3
  BadType,                   // packet type 0, or one a client never receives
  PacketTooLarge,            // over the decoder's / broker's maximum
  Truncated,                 // a field runs past the packet's end
  TrailingBytes,             // bytes left after the last field
  BadProperty,               // unknown id, wrong type, duplicate where forbidden
  BadString,                 // not UTF-8, or holds U+0000
  TooLong,                   // a string over 65,535 bytes, a packet over 256 MB
  BadArgument,               // QoS > 2, packet id 0 with QoS > 0, empty topic ...
};
const char* to_string(Error e);

enum class PacketType : std::uint8_t {
  Connect = 1, Connack, Publish, Puback, Pubrec, Pubrel, Pubcomp,
  Subscribe, Suback, Unsubscribe, Unsuback, Pingreq, Pingresp, Disconnect, Auth,
};

constexpr std::uint8_t kMqtt311 = 4;
constexpr std::uint8_t kMqtt5 = 5;
constexpr std::size_t kMaxRemainingLength = 268'435'455;

// v5 property identifiers used here (MQTT 5.0, 2.2.2.2).
namespace prop {
constexpr std::uint8_t PayloadFormatIndicator = 0x01, MessageExpiryInterval = 0x02, ContentType = 0x03,
                       ResponseTopic = 0x08, CorrelationData = 0x09, SubscriptionIdentifier = 0x0B,
                       SessionExpiryInterval = 0x11, AssignedClientIdentifier = 0x12, ServerKeepAlive = 0x13,
                       AuthenticationMethod = 0x15, AuthenticationData = 0x16, RequestProblemInformation = 0x17,
                       WillDelayInterval = 0x18, RequestResponseInformation = 0x19, ResponseInformation = 0x1A,
                       ServerReference = 0x1C, ReasonString = 0x1F, ReceiveMaximum = 0x21,
                       TopicAliasMaximum = 0x22, TopicAlias = 0x23, MaximumQoS = 0x24, RetainAvailable = 0x25,
                       UserProperty = 0x26, MaximumPacketSize = 0x27, WildcardSubscriptionAvailable = 0x28,
                       SubscriptionIdentifierAvailable = 0x29, SharedSubscriptionAvailable = 0x2A;
}

struct UserProperty {
  std::string_view name, value;
};

// PUBLISH properties (v5) the gateway sends or reads; views, the caller
// keeps the bytes alive while encoding.
struct PublishProperties {
  std::optional<std::uint8_t> payload_format;  // 0 bytes, 1 UTF-8
  std::optional<std::string_view> content_type;
  std::optional<std::string_view> response_topic;
  std::optional<std::string_view> correlation_data;
  std::vector<UserProperty> user;  // decode: filled only when present
  bool empty() const {
    return !payload_format && !content_type && !response_topic && !correlation_data && user.empty();
  }
};

struct Will {
  std::string_view topic, payload;
  std::uint8_t qos = 0;
  bool retain = false;
};

struct ConnectOptions {
  std::uint8_t version = kMqtt5;  // 4 or 5
  bool clean_start = true;
  std::uint16_t keepalive_s = 0;
  std::string_view client_id;
  std::optional<Will> will;
  std::optional<std::string_view> username, password;
  // v5 only (absent = not sent).
  std::optional<std::uint32_t> session_expiry;
  std::optional<std::uint16_t> receive_maximum;
  std::optional<std::uint32_t> maximum_packet_size;
};

struct Connack {
  bool session_present = false;
  std::uint8_t code = 0;  // v5 reason code / 3.1.1 return code
  // v5 properties (defaults as the spec says when absent).
  std::uint16_t receive_maximum = 65535;
  std::optional<std::uint32_t> maximum_packet_size;
  std::uint8_t maximum_qos = 2;
  bool retain_available = true;
  std::uint16_t topic_alias_maximum = 0;
  std::optional<std::string_view> assigned_client_id;
  std::optional<std::uint16_t> server_keepalive;
  std::optional<std::string_view> reason_string;
};

struct Publish {
  std::string_view topic;
  std::string_view payload;
  std::uint8_t qos = 0;
  bool retain = false;
  bool dup = false;
  std::uint16_t packet_id = 0;  // QoS > 0 only
  PublishProperties props;      // v5
};

struct Subscription {
  std::string_view filter;
  std::uint8_t qos = 0;
  bool no_local = false;  // v5 only
};

// One complete packet: type, the fixed header's low 4 bits, and the body
// (variable header + payload). Views into the Decoder.
struct Packet {
  PacketType type{};
  std::uint8_t flags = 0;
  std::string_view body;
};

// --- encoding ----------------------------------------------------------
Error encode_connect(std::string& out, const ConnectOptions& o);
// The exact size encode_publish() would append (0 on error): lets a caller
// check a broker's Maximum Packet Size first.
std::size_t publish_size(std::uint8_t version, const Publish& p);
Error encode_publish(std::string& out, std::uint8_t version, const Publish& p);
// v5: reason 0 with no properties is sent in the short form (2 bytes).
Error encode_puback(std::string& out, std::uint8_t version, std::uint16_t packet_id, std::uint8_t reason = 0);
Error encode_subscribe(std::string& out, std::uint8_t version, std::uint16_t packet_id,
                       std::span<const Subscription> subs);
void encode_pingreq(std::string& out);
void encode_disconnect(std::string& out, std::uint8_t version, std::uint8_t reason = 0);

// Appends the Variable Byte Integer (1..4 bytes) for v <= 268,435,455.
void put_varint(std::string& out, std::uint32_t v);
std::size_t varint_size(std::uint32_t v);

// --- decoding ----------------------------------------------------------
class Decoder {
 public:
  explicit Decoder(std::size_t max_packet_size = kMaxRemainingLength + 5) : max_(max_packet_size) {}
  void set_max_packet_size(std::size_t n) { max_ = n; }
  // Appends a chunk. Views from earlier next() calls become invalid.
  void feed(std::string_view chunk);
  // True and a packet when one is complete; false when more bytes are
  // needed or on error (error() != None; sticky).
  bool next(Packet& out);
  Error error() const { return error_; }
  std::size_t buffered() const { return buf_.size() - pos_; }
  void reset();

 private:
  std::string buf_;
  std::size_t pos_ = 0;
  std::size_t max_;
  Error error_ = Error::None;
};

// Fixed-header flags of each type are checked by the Decoder; these check
// the body. version: the connection's protocol level.
Error parse_connack(const Packet& p, std::uint8_t version, Connack& out);
Error parse_publish(const Packet& p, std::uint8_t version, Publish& out);
// PUBACK (also PUBREC/PUBREL/PUBCOMP's shape): id and v5 reason code.
Error parse_puback(const Packet& p, std::uint8_t version, std::uint16_t& packet_id, std::uint8_t& reason);
// SUBACK: id and one return/reason code per filter (appended to codes).
Error parse_suback(const Packet& p, std::uint8_t version, std::uint16_t& packet_id,
                   std::vector<std::uint8_t>& codes);
Error parse_disconnect(const Packet& p, std::uint8_t version, std::uint8_t& reason);

// True when s is well-formed UTF-8 without U+0000 (MQTT 1.5.4).
bool valid_utf8(std::string_view s);

}  // namespace gateway::mqtt::codec
