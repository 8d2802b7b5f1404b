#include "mqtt/session.hpp"

#include <algorithm>

namespace gateway::mqtt {
namespace {

// pid_slot_ values besides a token.
constexpr std::uint64_t kFreePid = 0;
constexpr std::uint64_t kControlPid = ~std::uint64_t{0};  // status, replies, SUBSCRIBE
// The window never needs more packet ids than there are.
constexpr std::size_t kMaxWindow = 65535 - 1024;

}  // namespace

Session::Session(Options opts, SessionEvents& events)
    : opts_(std::move(opts)), ev_(events), version_(opts_.mqtt_version >= 5 ? codec::kMqtt5 : codec::kMqtt311),
      decoder_(opts_.maximum_packet_size), pid_slot_(65536, kFreePid) {
  if (opts_.inflight_window == 0) opts_.inflight_window = 1;
}

std::size_t Session::window() const {
  std::size_t w = std::min(opts_.inflight_window, kMaxWindow);
  if (limits_.receive_maximum == 0) return w;
  const std::size_t r = limits_.receive_maximum;
  const std::size_t cap = r > 2 * kReceiveMaximumReserve ? r - kReceiveMaximumReserve : r;
  return std::min(cap, w);
}

std::chrono::milliseconds Session::ping_period() const {
  return std::max<std::chrono::milliseconds>(limits_.keepalive / 2, std::chrono::milliseconds(500));
}

void Session::set_deadline(std::optional<canopen::TimePoint> d) {
  if (d == deadline_) return;
  deadline_ = d;
  ev_.on_deadline_changed();
}

codec::Error Session::open(canopen::TimePoint now) {
  codec::ConnectOptions o;
  o.version = version_;
  o.clean_start = true;  // the owner's queue, not the broker, holds the backlog
  o.keepalive_s = static_cast<std::uint16_t>(std::clamp<long long>(opts_.keepalive.count(), 0, 65535));
  o.client_id = opts_.client_id;
  if (!opts_.will_topic.empty())
    o.will = codec::Will{opts_.will_topic, opts_.will_payload, opts_.will_qos, opts_.will_retain};
  if (!opts_.username.empty()) o.username = opts_.username;
  if (!opts_.password.empty()) o.password = opts_.password;
  if (version_ == codec::kMqtt5) {
    o.session_expiry = 0;
    o.receive_maximum = opts_.receive_maximum;
    o.maximum_packet_size = opts_.maximum_packet_size;
  }
  std::string packet;
  if (auto e = codec::encode_connect(packet, o); e != codec::Error::None) return e;
  close();
  connect_packet_ = std::move(packet);
  decoder_.reset();
  state_ = State::Connecting;
  set_deadline(now + opts_.connect_timeout);
  return codec::Error::None;
}

void Session::set_will(std::string topic, std::string payload) {
  opts_.will_topic = std::move(topic);
  opts_.will_payload = std::move(payload);
}

void Session::transport_connected(std::string& out, canopen::TimePoint now) {
  if (state_ != State::Connecting) return;
  out.append(connect_packet_);
  state_ = State::AwaitConnack;
  last_read_ = last_write_ = now;
}

void Session::received(std::string& out, std::string_view bytes, canopen::TimePoint now) {
  if (state_ != State::AwaitConnack && state_ != State::Up) return;
  last_read_ = now;
  ping_outstanding_ = false;  // anything from the broker shows it is alive
  decoder_.feed(bytes);
  codec::Packet p;
  bool any = false;
  acked_in_batch_ = false;
  while (decoder_.next(p)) {
    handle(out, p, now);
    if (state_ != State::Up && state_ != State::AwaitConnack) return;  // lost, refused or closed
    any = true;
  }
  if (decoder_.error() != codec::Error::None) {
    lost(std::string("malformed data from the broker: ") + codec::to_string(decoder_.error()));
    return;
  }
  if (any && state_ == State::Up) ev_.on_batch_end(acked_in_batch_);
}

std::size_t Session::wrote(canopen::TimePoint now) {
  last_write_ = now;
  const std::size_t n = unwritten_q0_.size();
  if (n == 0) return 0;
  for (auto token : unwritten_q0_) ev_.on_acked(token);
  unwritten_q0_.clear();
  return n;
}

void Session::transport_closed(const std::string& why) {
  if (state_ == State::Idle) return;
  lost(why, state_ == State::AwaitConnack);
}

void Session::on_timer(std::string& out, canopen::TimePoint now) {
  if (!deadline_ || now < *deadline_) return;
  if (state_ == State::Connecting || state_ == State::AwaitConnack) {
    lost("connect timeout");
    return;
  }
  if (state_ != State::Up) {
    set_deadline(std::nullopt);
    return;
  }
  // Checked every half keepalive, so no deadline moves per packet.
  const auto period = ping_period();
  if (now - last_read_ > std::chrono::milliseconds(limits_.keepalive) * 3 / 2) {
    lost("no answer from the broker within 1.5 keepalive intervals");
    return;
  }
  if (!ping_outstanding_ && (now - last_read_ >= period || now - last_write_ >= period)) {
    codec::encode_pingreq(out);
    ping_outstanding_ = true;
  }
  set_deadline(now + period);
}

void Session::close() {
  if (state_ == State::Idle) return;
  forget_window(true);
  state_ = State::Idle;
  set_deadline(std::nullopt);
}

void Session::reset_version() {
  if (state_ != State::Idle) return;
  version_ = opts_.mqtt_version >= 5 ? codec::kMqtt5 : codec::kMqtt311;
  fell_back_ = false;
}

void Session::lost(const std::string& why, bool closed_awaiting_connack) {
  const bool was_up = state_ == State::Up;
  bool fall_back = false;
  if (!was_up && opts_.mqtt_version >= 5) {
    if (version_ == codec::kMqtt5 && closed_awaiting_connack) {
      // RabbitMQ's MQTT plugin (3.1.1 only) closes at an MQTT 5 CONNECT.
      version_ = codec::kMqtt311;
      fell_back_ = fall_back = true;
    } else if (version_ == codec::kMqtt311 && fell_back_) {
      // The 3.1.1 attempt failed as well: the broker was maybe restarting
      // rather than refusing 5; the next attempt is 5 again.
      version_ = codec::kMqtt5;
      fell_back_ = false;
    }
  }
  close();
  ev_.on_lost(why, was_up, fall_back);
}

void Session::handle(std::string& out, const codec::Packet& p, canopen::TimePoint now) {
  if (state_ == State::AwaitConnack) {
    if (p.type != codec::PacketType::Connack) {
      lost("expected CONNACK");
      return;
    }
    handle_connack(p, now);
    return;
  }
  switch (p.type) {
    case codec::PacketType::Pingresp: return;
    case codec::PacketType::Connack: lost("second CONNACK"); return;
    case codec::PacketType::Puback: {
      std::uint16_t pid;
      std::uint8_t reason;
      if (auto e = codec::parse_puback(p, version_, pid, reason); e != codec::Error::None) {
        lost(std::string("bad PUBACK: ") + codec::to_string(e));
        return;
      }
      on_puback(pid, reason);
      return;
    }
    case codec::PacketType::Publish: {
      codec::Publish in;
      if (auto e = codec::parse_publish(p, version_, in); e != codec::Error::None) {
        lost(std::string("bad PUBLISH from the broker: ") + codec::to_string(e));
        return;
      }
      if (in.qos > 0) codec::encode_puback(out, version_, in.packet_id);
      ev_.on_publish(in);
      return;
    }
    case codec::PacketType::Suback: {
      std::uint16_t pid;
      suback_codes_.clear();
      if (auto e = codec::parse_suback(p, version_, pid, suback_codes_); e != codec::Error::None) {
        lost(std::string("bad SUBACK: ") + codec::to_string(e));
        return;
      }
      if (pid_slot_[pid] == kControlPid) pid_slot_[pid] = kFreePid;
      for (auto c : suback_codes_)
        if (c >= 0x80) ev_.on_subscribe_refused(c);
      return;
    }
    case codec::PacketType::Disconnect: {
      std::uint8_t reason = 0;
      (void)codec::parse_disconnect(p, version_, reason);
      lost("broker disconnected, reason " + std::to_string(reason));
      return;
    }
    default:
      // PUBREC etc. cannot come (QoS <= 1 both ways): a broker bug.
      lost("unexpected packet type " + std::to_string(static_cast<int>(p.type)));
      return;
  }
}

void Session::handle_connack(const codec::Packet& p, canopen::TimePoint now) {
  codec::Connack ca;
  if (auto e = codec::parse_connack(p, version_, ca); e != codec::Error::None) {
    lost(std::string("bad CONNACK: ") + codec::to_string(e));
    return;
  }
  if (ca.code != 0) {
    // The broker refuses MQTT 5: v5 reason 0x84, or a 3.1.1 broker's
    // CONNACK code 1 (unacceptable protocol version).
    const bool fall_back = version_ == codec::kMqtt5 && opts_.mqtt_version >= 5 && (ca.code == 0x84 || ca.code == 1);
    if (fall_back) version_ = codec::kMqtt311;  // refused 5 in so many words: no going back
    fell_back_ = false;
    close();
    ev_.on_refused(ca.code, fall_back);
    return;
  }
  const bool v5 = version_ == codec::kMqtt5;
  limits_ = BrokerLimits{};
  limits_.version = version_;
  limits_.receive_maximum = v5 ? ca.receive_maximum : 0;
  limits_.maximum_qos = v5 ? std::min<std::uint8_t>(ca.maximum_qos, 1) : 1;
  limits_.retain_available = v5 ? ca.retain_available : true;
  limits_.maximum_packet_size = v5 && ca.maximum_packet_size ? *ca.maximum_packet_size : 0;
  limits_.keepalive = ca.server_keepalive ? std::chrono::seconds(*ca.server_keepalive) : opts_.keepalive;
  forget_window(true);
  state_ = State::Up;
  set_deadline(limits_.keepalive.count() > 0 ? std::optional(now + ping_period()) : std::nullopt);
  ev_.on_connected(limits_);
}

void Session::on_puback(std::uint16_t pid, std::uint8_t reason) {
  const std::uint64_t slot = pid_slot_[pid];
  if (slot == kFreePid) return;  // forgotten by a restart: a late PUBACK
  pid_slot_[pid] = kFreePid;
  if (slot == kControlPid) return;
  --inflight_q1_;
  acked_in_batch_ = true;
  if (reason >= 0x80)
    ev_.on_rejected(slot, reason);
  else
    ev_.on_acked(slot);
}

// What was in flight goes to the front of the resend list, oldest first.
// Packet ids count up (skipping busy ones), so the oldest is the first busy
// one after next_pid_. Ids keep counting after a restart, so a late PUBACK
// for a forgotten one finds a free slot and is ignored.
void Session::forget_window(bool control_too) {
  std::vector<std::uint64_t> unacked;
  unacked.reserve(inflight_q1_ + resend_.size() - resend_pos_);
  for (std::size_t i = 1; i <= 65535; ++i) {
    const auto pid = static_cast<std::uint16_t>((next_pid_ + i - 1) % 65535 + 1);
    auto& s = pid_slot_[pid];
    if (s == kFreePid) continue;
    if (s != kControlPid) {
      unacked.push_back(s);
      s = kFreePid;
    } else if (control_too) {
      s = kFreePid;
    }
  }
  if (!unacked.empty()) {
    unacked.insert(unacked.end(), resend_.begin() + static_cast<std::ptrdiff_t>(resend_pos_), resend_.end());
    resend_ = std::move(unacked);
    resend_pos_ = 0;
  }
  inflight_q1_ = 0;
  unwritten_q0_.clear();
}

std::span<const std::uint64_t> Session::resend_list() const {
  return std::span<const std::uint64_t>(resend_).subspan(resend_pos_);
}

// True when token was in flight at the last loss (and is now sent again).
// The queue hands them out oldest first, so a QoS 1 message that is not on
// the list means the rest will not come again (moved within the queue):
// the list is dropped.
bool Session::take_resend(std::uint64_t token) {
  if (resend_pos_ == resend_.size()) return false;
  if (resend_[resend_pos_] == token) {
    ++resend_pos_;
  } else {
    auto it = std::find(resend_.begin() + static_cast<std::ptrdiff_t>(resend_pos_), resend_.end(), token);
    if (it == resend_.end()) {
      resend_.clear();
      resend_pos_ = 0;
      return false;
    }
    resend_.erase(it);
  }
  if (resend_pos_ == resend_.size()) {
    resend_.clear();
    resend_pos_ = 0;
  }
  return true;
}

std::uint16_t Session::alloc_pid() {
  for (int i = 0; i < 65535; ++i) {
    if (++next_pid_ == 0) next_pid_ = 1;
    if (pid_slot_[next_pid_] == kFreePid) return next_pid_;
  }
  return 0;
}

// One PUBLISH as the broker allows it: `qos` as from out_qos() (with `pid`
// when it is 1), the retain flag only where Retain Available, properties
// only under MQTT 5, PacketTooLarge above the broker's Maximum Packet Size.
codec::Error Session::encode_out(std::string& out, std::string_view topic, std::string_view payload,
                                 std::uint8_t qos, bool retain, std::uint16_t pid, bool dup,
                                 const codec::PublishProperties* props) const {
  codec::Publish p;
  p.topic = topic;
  p.payload = payload;
  p.qos = qos;
  p.retain = retain && limits_.retain_available;
  p.dup = dup && qos > 0;
  p.packet_id = qos > 0 ? pid : 0;
  if (props && version_ == codec::kMqtt5) p.props = *props;
  if (limits_.maximum_packet_size > 0 && codec::publish_size(version_, p) > limits_.maximum_packet_size)
    return codec::Error::PacketTooLarge;
  return codec::encode_publish(out, version_, p);
}

Session::SendResult Session::publish(std::string& out, std::uint64_t token, std::string_view topic,
                                     std::string_view payload, std::uint8_t qos, bool retain) {
  SendResult r;
  const std::uint8_t q = out_qos(qos);
  std::uint16_t pid = 0;
  if (q > 0 && (pid = alloc_pid()) == 0) {
    r.busy = true;
    return r;
  }
  // Looked up only after a loss, and only for QoS 1 (QoS 0 has no DUP).
  const bool dup = q > 0 && resend_pos_ < resend_.size() && take_resend(token);
  r.error = encode_out(out, topic, payload, q, retain, pid, dup, nullptr);
  if (r.error != codec::Error::None) return r;
  if (q > 0) {
    pid_slot_[pid] = token;
    ++inflight_q1_;
  } else {
    unwritten_q0_.push_back(token);
  }
  return r;
}

bool Session::publish_control(std::string& out, std::string_view topic, std::string_view payload, bool retain,
                              const codec::PublishProperties* props) {
  const std::uint16_t pid = alloc_pid();
  if (pid == 0) return false;
  const std::uint8_t q = out_qos(1);
  if (encode_out(out, topic, payload, q, retain, pid, false, props) != codec::Error::None) return false;
  if (q > 0) pid_slot_[pid] = kControlPid;
  return true;
}

void Session::publish_final(std::string& out, std::string_view topic, std::string_view payload, std::uint8_t qos,
                            bool retain) {
  const std::uint8_t q = out_qos(qos);
  const std::uint16_t pid = q > 0 ? alloc_pid() : 0;
  (void)encode_out(out, topic, payload, q, retain, pid == 0 ? 1 : pid, false, nullptr);
}

Session::SendResult Session::subscribe(std::string& out, std::span<const codec::Subscription> subs) {
  SendResult r;
  const std::uint16_t pid = alloc_pid();
  if (pid == 0) {
    r.busy = true;
    return r;
  }
  r.error = codec::encode_subscribe(out, version_, pid, subs);
  if (r.error == codec::Error::None) pid_slot_[pid] = kControlPid;
  return r;
}

void Session::disconnect(std::string& out, std::uint8_t reason) { codec::encode_disconnect(out, version_, reason); }

void Session::restart_window() { forget_window(false); }

}  // namespace gateway::mqtt
