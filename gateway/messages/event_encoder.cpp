#include "messages/event_encoder.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <type_traits>
#include <variant>

#include "canopen/sdo/abort.hpp"
#include "canopen_gateway.pb.h"
#include "messages/json_text.hpp"
#include "messages/proto_value.hpp"

namespace gateway {

namespace pb = ::canopen::gateway::v1;
using detail::append_hex;
using detail::append_json_string;
using detail::append_timestamp;
using detail::append_uint;
using detail::UnixTime;

namespace {

std::string_view cause_name(canopen::NodeStateEvent::Cause c) {
  using C = canopen::NodeStateEvent::Cause;
  switch (c) {
    case C::BootUp: return "boot-up";
    case C::Heartbeat: return "heartbeat";
    case C::NodeGuarding: return "node-guarding";
    case C::Lost: return "lost";
    case C::Recovered: return "recovered";
  }
  return "unknown";
}

std::string_view step_name(canopen::BootConfigEvent::Step s) {
  using S = canopen::BootConfigEvent::Step;
  switch (s) {
    case S::Identify: return "identify";
    case S::CheckIdentity: return "check-identity";
    case S::Configure: return "configure";
    case S::Start: return "start";
    case S::Done: return "done";
    case S::Failed: return "failed";
  }
  return "unknown";
}

std::string_view transfer_operation_name(canopen::TransferEvent::Operation o) {
  using O = canopen::TransferEvent::Operation;
  switch (o) {
    case O::ProgramDownload: return "program-download";
    case O::DcfRead: return "dcf-read";
    case O::DcfApply: return "dcf-apply";
  }
  return "unknown";
}

std::string_view transfer_status_name(canopen::TransferEvent::Status s) {
  using S = canopen::TransferEvent::Status;
  switch (s) {
    case S::Running: return "running";
    case S::Done: return "done";
    case S::Failed: return "failed";
  }
  return "unknown";
}

// Text that goes into a protobuf string field and JSON: always UTF-8.
std::string utf8(std::string_view s) { return detail::to_utf8(s); }

// Fields every event starts with: seq, timestamp, network, node.
struct Header {
  std::uint64_t seq = 0;
  UnixTime time;
  std::uint32_t network = 0;
  std::uint8_t node = 0;

  template <typename M>
  void set(M& m) const {
    m.set_seq(seq);
    auto* ts = m.mutable_timestamp();
    ts->set_seconds(time.seconds);
    ts->set_nanos(time.nanos);
    m.set_network(network);
    m.set_node(node);
  }
  // Opens the object and writes the four fields.
  void json(std::string& out) const {
    out += "{\"seq\":\"";
    append_uint(out, seq);
    out += "\",\"timestamp\":";
    append_timestamp(out, time);
    out += ",\"network\":";
    append_uint(out, network);
    out += ",\"node\":";
    append_uint(out, node);
  }
};

// ,"k": in one append (k is one of our short field names).
void key(std::string& out, std::string_view k) {
  std::array<char, 40> buf{};
  if (k.size() + 4 > buf.size()) {
    out += ",\"";
    out += k;
    out += "\":";
    return;
  }
  buf[0] = ',';
  buf[1] = '"';
  std::copy(k.begin(), k.end(), buf.begin() + 2);
  buf[k.size() + 2] = '"';
  buf[k.size() + 3] = ':';
  out.append(buf.data(), k.size() + 4);
}
void field(std::string& out, std::string_view k, std::string_view utf8_text) {
  key(out, k);
  append_json_string(out, utf8_text);
}
void field(std::string& out, std::string_view k, std::uint64_t v) {
  key(out, k);
  append_uint(out, v);
}
void field_u64(std::string& out, std::string_view k, std::uint64_t v) {
  key(out, k);
  out += '"';
  append_uint(out, v);
  out += '"';
}

std::shared_ptr<EncodedEvent> make(EventKind kind, const Header& h, std::string topic, bool retained) {
  auto e = std::make_shared<EncodedEvent>();
  e->kind = kind;
  e->network = h.network;
  e->node = h.node;
  e->seq = h.seq;
  e->topic = std::move(topic);
  e->retained = retained;
  return e;
}

template <typename M>
void finish(EncodedEvent& e, const M& m) {
  m.SerializeToString(&e.binary);
  // The WebSocket frames, built once here from the payloads (no re-encoding).
  e.ws_json = envelope_json(e);
  e.ws_binary = envelope_binary(e);
}

class Encoder {
 public:
  Encoder(const canopen::Event& ev, std::uint32_t network, const EncodeContext& ctx) : ctx_(ctx) {
    h_.seq = ev.seq;
    h_.time = detail::to_unix_time(ev.timestamp);
    h_.network = network;
  }

  EncodedEventPtr operator()(const canopen::PdoEvent& p) {
    h_.node = p.node;
    if (p.node == 0 || p.number == 0) return unclaimed(p);
    auto e = make(EventKind::Tpdo, h_, node_topic(ctx_, h_.network, p.node, "tpdo/" + std::to_string(p.number)),
                  false);
    // Sub-messages and strings on an arena whose first block is on the
    // stack: no heap allocation for a typical PDO. No message at all when
    // nobody wants protobuf (most of the encoding's cost).
    alignas(std::max_align_t) std::array<char, 2048> block;
    google::protobuf::ArenaOptions opts;
    opts.initial_block = block.data();
    opts.initial_block_size = block.size();
    google::protobuf::Arena arena(opts);
    pb::PdoEvent* m = ctx_.protobuf ? google::protobuf::Arena::CreateMessage<pb::PdoEvent>(&arena) : nullptr;
    if (m != nullptr) {
      h_.set(*m);
      m->set_tpdo(p.number);
      m->set_cob_id(p.cob_id);
      m->mutable_values()->Reserve(static_cast<int>(p.values.size()));
    }
    std::string& j = e->json;
    j.reserve(160 + p.values.size() * 96 + p.raw.size() * 2);
    h_.json(j);
    field(j, "tpdo", p.number);
    field(j, "cobId", p.cob_id);
    j += ",\"values\":[";
    bool first = true;
    for (const auto& v : p.values) {
      auto* mv = m != nullptr ? m->add_values() : nullptr;
      const std::string_view type = canopen::cia309_name(v.value.type);
      if (!first) j += ',';
      first = false;
      j += "{\"index\":";
      append_uint(j, v.index);
      j += ",\"subIndex\":";
      append_uint(j, v.sub);
      if (detail::is_utf8(v.name)) {
        field(j, "name", v.name);
        if (mv != nullptr) mv->set_name(v.name);
      } else {
        std::string name = utf8(v.name);
        field(j, "name", name);
        if (mv != nullptr) mv->set_name(std::move(name));
      }
      field(j, "type", type);
      key(j, "value");
      const bool typed = canopen::holds_its_type(v.value);
      if (typed) {
        detail::append_value_json(j, v.value);
      } else {
        j += "null";  // a stack bug, not a reason to crash the gateway
      }
      j += '}';
      if (mv != nullptr) {
        mv->set_index(v.index);
        mv->set_sub_index(v.sub);
        mv->set_type(std::string(type));
        if (typed)
          detail::set_proto_value(*mv->mutable_value(), v.value);
        else
          mv->mutable_value()->set_null_value(google::protobuf::NULL_VALUE);
      }
    }
    j += ']';
    std::string raw;
    raw.reserve(p.raw.size() * 2);
    append_hex(raw, p.raw);
    field(j, "raw", raw);
    if (m != nullptr) m->set_raw(std::move(raw));
    if (p.error) {
      std::string err = utf8(*p.error);
      field(j, "error", err);
      if (m != nullptr) m->set_error(std::move(err));
    }
    if (p.mpdo) {
      const auto& mp = *p.mpdo;
      const char* mode = mp.destination_mode ? "dam" : "sam";
      j += ",\"mpdo\":{\"mode\":";
      append_json_string(j, mode);
      field(j, "address", mp.address);
      field(j, "index", mp.index);
      field(j, "subIndex", mp.sub);
      if (mp.local_index) field(j, "localIndex", *mp.local_index);
      if (mp.local_sub) field(j, "localSubIndex", *mp.local_sub);
      j += '}';
      if (m != nullptr) {
        auto* mi = m->mutable_mpdo();
        mi->set_mode(mode);
        mi->set_address(mp.address);
        mi->set_index(mp.index);
        mi->set_sub_index(mp.sub);
        if (mp.local_index) mi->set_local_index(*mp.local_index);
        if (mp.local_sub) mi->set_local_sub_index(*mp.local_sub);
      }
    }
    j += '}';
    if (m != nullptr)
      finish(*e, *m);
    else
      e->ws_json = envelope_json(*e);  // binary and ws_binary stay empty
    return e;
  }

  EncodedEventPtr operator()(const canopen::NodeStateEvent& s) {
    h_.node = s.node;
    auto e = make(EventKind::State, h_, node_topic(ctx_, h_.network, s.node, "state"), true);
    pb::NodeStateEvent m;
    h_.set(m);
    // A lost node has no NMT state; the contract's state for it is "lost".
    const bool lost = s.cause == canopen::NodeStateEvent::Cause::Lost || !s.state;
    m.set_state(lost ? "lost" : std::string(canopen::to_string(*s.state)));
    if (s.previous) m.set_previous(std::string(canopen::to_string(*s.previous)));
    m.set_cause(std::string(cause_name(s.cause)));
    h_.json(e->json);
    field(e->json, "state", m.state());
    if (m.has_previous()) field(e->json, "previous", m.previous());
    field(e->json, "cause", m.cause());
    e->json += '}';
    finish(*e, m);
    return e;
  }

  EncodedEventPtr operator()(const canopen::HeartbeatEvent& hb) {
    h_.node = hb.node;
    auto e = make(EventKind::Heartbeat, h_, node_topic(ctx_, h_.network, hb.node, "heartbeat"), false);
    pb::HeartbeatEvent m;
    h_.set(m);
    m.set_state(std::string(canopen::to_string(hb.state)));
    h_.json(e->json);
    field(e->json, "state", m.state());
    e->json += '}';
    finish(*e, m);
    return e;
  }

  EncodedEventPtr operator()(const canopen::EmcyEvent& em) {
    h_.node = em.node;
    auto e = make(EventKind::Emcy, h_, node_topic(ctx_, h_.network, em.node, "emcy"), false);
    pb::EmcyEvent m;
    h_.set(m);
    m.set_error_code(em.error_code);
    m.set_error_register(em.error_register);
    m.set_manufacturer_data(detail::to_hex(em.manufacturer));
    m.set_description(utf8(em.description));
    std::string& j = e->json;
    h_.json(j);
    field(j, "errorCode", em.error_code);
    field(j, "errorRegister", em.error_register);
    field(j, "manufacturerData", m.manufacturer_data());
    field(j, "description", m.description());
    j += '}';
    finish(*e, m);
    return e;
  }

  EncodedEventPtr operator()(const canopen::SyncEvent& s) {
    auto e = make(EventKind::Sync, h_, network_topic(ctx_, h_.network, "sync"), false);
    pb::SyncEvent m;
    h_.set(m);
    h_.json(e->json);
    if (s.counter) {
      m.set_counter(*s.counter);
      field(e->json, "counter", *s.counter);
    }
    e->json += '}';
    finish(*e, m);
    return e;
  }

  EncodedEventPtr operator()(const canopen::TimeEvent& t) {
    auto e = make(EventKind::Time, h_, network_topic(ctx_, h_.network, "time"), false);
    pb::TimeEvent m;
    h_.set(m);
    const std::int64_t ms = canopen::unix_ms_from_time_of_day(t.time);
    const std::int64_t s = ms >= 0 ? ms / 1000 : (ms - 999) / 1000;
    const UnixTime ut{s, static_cast<std::int32_t>((ms - s * 1000) * 1'000'000)};
    m.mutable_time()->set_seconds(ut.seconds);
    m.mutable_time()->set_nanos(ut.nanos);
    h_.json(e->json);
    key(e->json, "time");
    append_timestamp(e->json, ut);
    e->json += '}';
    finish(*e, m);
    return e;
  }

  EncodedEventPtr operator()(const canopen::BootConfigEvent& b) {
    h_.node = b.node;
    auto e = make(EventKind::BootConfig, h_, node_topic(ctx_, h_.network, b.node, "boot"), false);
    pb::BootConfigEvent m;
    h_.set(m);
    m.set_step(std::string(step_name(b.step)));
    if (b.error) {
      m.set_error(utf8(b.error.message()));
      if (b.error.category() == canopen::sdo_abort_category()) {
        m.set_abort_code(detail::abort_code_text(static_cast<std::uint32_t>(b.error.value())));
      }
    }
    m.set_detail(utf8(b.detail));
    std::string& j = e->json;
    h_.json(j);
    field(j, "step", m.step());
    if (m.has_error()) field(j, "error", m.error());
    if (m.has_abort_code()) field(j, "abortCode", m.abort_code());
    field(j, "detail", m.detail());
    j += '}';
    finish(*e, m);
    return e;
  }

  EncodedEventPtr operator()(const canopen::TransferEvent& t) {
    h_.node = t.node;
    auto e = make(EventKind::Transfer, h_, node_topic(ctx_, h_.network, t.node, "transfer"), false);
    pb::TransferEvent m;
    h_.set(m);
    m.set_operation(std::string(transfer_operation_name(t.operation)));
    m.set_status(std::string(transfer_status_name(t.status)));
    m.set_done(t.done);
    m.set_total(t.total);
    m.set_unit(t.operation == canopen::TransferEvent::Operation::ProgramDownload ? "bytes" : "objects");
    if (t.error) {
      m.set_error(utf8(t.error.message()));
      if (t.error.category() == canopen::sdo_abort_category()) {
        m.set_abort_code(detail::abort_code_text(static_cast<std::uint32_t>(t.error.value())));
      }
    }
    m.set_detail(utf8(t.detail));
    std::string& j = e->json;
    h_.json(j);
    field(j, "operation", m.operation());
    field(j, "status", m.status());
    field_u64(j, "done", t.done);  // proto3 JSON: uint64 as a string
    field_u64(j, "total", t.total);
    field(j, "unit", m.unit());
    if (m.has_error()) field(j, "error", m.error());
    if (m.has_abort_code()) field(j, "abortCode", m.abort_code());
    field(j, "detail", m.detail());
    j += '}';
    finish(*e, m);
    return e;
  }

  EncodedEventPtr operator()(const canopen::can::BusEvent& b) {
    auto e = make(EventKind::Bus, h_, network_topic(ctx_, h_.network, "bus"), true);
    pb::BusStateEvent m;
    h_.set(m);
    m.set_state(std::string(canopen::can::to_string(b.state)));
    m.set_previous(std::string(canopen::can::to_string(b.previous)));
    m.set_cause(std::string(canopen::can::to_string(b.cause)));
    m.set_tec(b.tx_error_counter);
    m.set_rec(b.rx_error_counter);
    m.set_dropped(b.dropped);
    std::string& j = e->json;
    h_.json(j);
    field(j, "state", m.state());
    field(j, "previous", m.previous());
    field(j, "cause", m.cause());
    field(j, "tec", b.tx_error_counter);
    field(j, "rec", b.rx_error_counter);
    field_u64(j, "dropped", b.dropped);
    j += '}';
    finish(*e, m);
    return e;
  }

 private:
  EncodedEventPtr unclaimed(const canopen::PdoEvent& p) {
    h_.node = 0;
    auto e = make(EventKind::UnclaimedPdo, h_, network_topic(ctx_, h_.network, "pdo/" + cob_id_topic_level(p.cob_id)),
                  false);
    pb::UnclaimedPdo m;
    h_.set(m);
    m.set_cob_id(p.cob_id);
    append_hex(*m.mutable_raw(), p.raw);
    h_.json(e->json);
    field(e->json, "cobId", p.cob_id);
    field(e->json, "raw", m.raw());
    e->json += '}';
    finish(*e, m);
    return e;
  }

  const EncodeContext& ctx_;
  Header h_;
};

void append_topic_prefix(std::string& t, const EncodeContext& ctx, std::uint32_t network) {
  t += "canopen/";
  t += ctx.gateway_id;
  t += '/';
  append_uint(t, network);
  t += '/';
}

// Protobuf wire format: varint and a length-delimited field.
void append_varint(std::string& out, std::uint64_t v) {
  while (v >= 0x80) {
    out += static_cast<char>((v & 0x7F) | 0x80);
    v >>= 7;
  }
  out += static_cast<char>(v);
}
void append_bytes_field(std::string& out, std::uint32_t number, std::string_view bytes) {
  append_varint(out, (std::uint64_t{number} << 3) | 2);
  append_varint(out, bytes.size());
  out += bytes;
}

}  // namespace

bool valid_gateway_id(std::string_view id) {
  if (id.empty() || !detail::is_utf8(id)) return false;
  for (char c : id) {
    if (c == '/' || c == '+' || c == '#' || c == '\0') return false;
  }
  return true;
}

std::string node_topic(const EncodeContext& ctx, std::uint32_t network, std::uint8_t node, std::string_view leaf) {
  std::string t;
  t.reserve(24 + ctx.gateway_id.size() + leaf.size());
  append_topic_prefix(t, ctx, network);
  append_uint(t, node);
  t += '/';
  t += leaf;
  return t;
}

std::string status_topic(std::string_view gateway_id) { return "canopen/" + std::string(gateway_id) + "/status"; }

std::string network_topic(const EncodeContext& ctx, std::uint32_t network, std::string_view leaf) {
  std::string t;
  t.reserve(20 + ctx.gateway_id.size() + leaf.size());
  append_topic_prefix(t, ctx, network);
  t += leaf;
  return t;
}

std::string cob_id_topic_level(std::uint32_t cob_id) {
  constexpr char kUpper[] = "0123456789ABCDEF";
  const std::uint32_t id = cob_id & 0x1FFFFFFFu;
  const int digits = id > 0x7FF ? 8 : 3;
  std::string s;
  for (int i = digits - 1; i >= 0; --i) s += kUpper[(id >> (4 * i)) & 0x0F];
  return s;
}

EncodedEventPtr encode_event(const canopen::Event& ev, std::uint32_t network, const EncodeContext& ctx) {
  Encoder enc(ev, network, ctx);
  return std::visit(enc, ev.body);
}

EncodedEventPtr encode_status(const GatewayStatusInfo& s, const EncodeContext& ctx) {
  Header h;
  h.time = detail::to_unix_time(s.timestamp);
  auto e = make(EventKind::Status, h, status_topic(ctx.gateway_id), true);
  pb::GatewayStatus m;
  h.set(m);
  m.set_state(s.online ? "online" : "offline");
  m.set_version(utf8(s.version));
  m.set_gateway_id(utf8(ctx.gateway_id));
  m.set_uptime_ms(s.uptime_ms);
  m.set_node_id(s.node_id);
  for (auto n : s.networks) m.add_networks(n);
  std::string& j = e->json;
  h.json(j);
  field(j, "state", m.state());
  field(j, "version", m.version());
  field(j, "gatewayId", m.gateway_id());
  field_u64(j, "uptimeMs", s.uptime_ms);
  field(j, "nodeId", s.node_id);
  j += ",\"networks\":[";
  for (std::size_t i = 0; i < s.networks.size(); ++i) {
    if (i) j += ',';
    append_uint(j, s.networks[i]);
  }
  j += "]}";
  finish(*e, m);
  return e;
}

std::string envelope_json(const EncodedEvent& ev) {
  std::string j;
  j.reserve(ev.json.size() + ev.topic.size() + 48);
  j += "{\"kind\":";
  append_json_string(j, to_string(ev.kind));
  field(j, "topic", detail::to_utf8(ev.topic));
  key(j, to_string(ev.kind));
  j += ev.json;
  j += '}';
  return j;
}

std::string envelope_binary(const EncodedEvent& ev) {
  std::string b;
  b.reserve(ev.binary.size() + ev.topic.size() + 24);
  append_bytes_field(b, 1, to_string(ev.kind));
  append_bytes_field(b, 2, detail::to_utf8(ev.topic));
  // EventEnvelope's oneof numbers follow EventKind: status = 10 ... boot = 19.
  append_bytes_field(b, 10 + static_cast<std::uint32_t>(ev.kind), ev.binary);
  return b;
}

}  // namespace gateway
