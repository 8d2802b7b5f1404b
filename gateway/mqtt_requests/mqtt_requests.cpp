#include "canopen/json_value.hpp"
#include "mqtt_requests/mqtt_requests.hpp"

#include <boost/json/parse.hpp>
#include <boost/json/serialize.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>

#include "core/format.hpp"
#include "mqtt/topic_filter.hpp"

namespace gateway::mqtt {

namespace {

namespace json = boost::json;

// "Bearer abc" -> "abc"; a bare token stays as it is.
std::string_view strip_bearer(std::string_view v) {
  constexpr std::string_view kBearer = "Bearer ";
  if (v.size() >= kBearer.size() && std::equal(kBearer.begin(), kBearer.end(), v.begin(), [](char a, char b) {
        return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
      }))
    v.remove_prefix(kBearer.size());
  return v;
}

// The body's command, or what the core answers 400 with.
core::Command decode_command(core::Operation op, std::uint8_t node, std::string_view body, bool protobuf,
                             const canopen::Result<json::object>* object, ReplyOptions& opts) {
  auto bad = [&](const canopen::Error& e) -> core::Command { return core::Undecodable{op, node, e.detail, false}; };
  switch (op) {
    case core::Operation::sdo_read: {
      auto p = protobuf ? parse_sdo_read(body, true) : *object ? parse_sdo_read(**object) : object->error();
      if (!p) return bad(p.error());
      opts.correlation_id = p->correlation_id;
      return core::SdoRead{node, *p->index, *p->sub, p->type};
    }
    case core::Operation::sdo_write: {
      auto p = protobuf ? parse_sdo_write(body, true) : *object ? parse_sdo_write(**object) : object->error();
      if (!p) return bad(p.error());
      opts.correlation_id = p->correlation_id;
      return core::SdoWrite{node, *p->index, *p->sub, p->type, canopen::literal_from_json(p->value)};
    }
    default: {
      auto p = protobuf ? parse_nmt(body, true) : *object ? parse_nmt(**object) : object->error();
      if (!p) return bad(p.error());
      opts.correlation_id = p->correlation_id;
      return core::Nmt{node, p->command};
    }
  }
}

// A warning that a flood of bad requests could repeat endlessly: the
// first, then at most one per interval, saying how many were left out.
struct LogThrottle {
  static constexpr std::chrono::seconds kInterval{10};
  std::chrono::steady_clock::time_point last{};
  bool logged = false;
  std::uint64_t left_out = 0;
  void warn(Logger& log, std::string line) {
    const auto now = std::chrono::steady_clock::now();
    if (logged && now - last < kInterval) {
      ++left_out;
      return;
    }
    if (left_out > 0) line += " (and " + std::to_string(left_out) + " more like it since the last such line)";
    logged = true;
    last = now;
    left_out = 0;
    log.warn(line);
  }
};

}  // namespace

DecodedRequest decode_request(const codec::Publish& msg, std::string_view gateway_id) {
  DecodedRequest d;
  core::Caller& caller = d.request.caller;
  caller.transport = core::Transport::mqtt;
  const auto& props = msg.props;
  if (props.response_topic) {
    d.reply.topic = std::string(*props.response_topic);
    d.reply.v5 = true;
    if (props.correlation_data) d.reply.correlation = std::string(*props.correlation_data);
  }
  // MQTT 5 user property "authorization": "Bearer <token>" (or the token).
  for (const auto& u : props.user)
    if (u.name == "authorization") caller.token = std::string(strip_bearer(u.value));
  d.options.protobuf = props.content_type && *props.content_type == "application/x-protobuf";
  // A JSON body is parsed once: the reply address and token come out of it
  // (3.1.1; allowed over 5 too) before the command is decoded from the rest.
  std::optional<canopen::Result<json::object>> object;
  if (!d.options.protobuf) {
    object = parse_json_body(msg.payload);
    if (*object) {
      auto& o = **object;
      if (auto* r = o.if_contains("replyTo")) {
        if (r->is_string() && d.reply.topic.empty()) d.reply.topic = std::string(r->as_string());
        o.erase("replyTo");
      }
      if (auto* c = o.if_contains("correlationId")) {
        if (!d.reply.v5) d.reply.corr_id = *c;
        o.erase("correlationId");
      }
      if (auto* t = o.if_contains("token")) {
        if (t->is_string() && caller.token.empty()) caller.token = std::string(strip_bearer(t->as_string()));
        o.erase("token");
      }
    }
  }

  // canopen/<gw>/<net>/<node>/sdo/read|write or canopen/<gw>/<net>/<node>/nmt
  const std::string prefix = "canopen/" + std::string(gateway_id) + "/";
  if (msg.topic.substr(0, prefix.size()) != prefix) {
    d.error = "not this gateway's request topic";
    return d;
  }
  const auto parts = topic_levels(msg.topic.substr(prefix.size()));
  core::Operation op{};
  if (parts.size() == 4 && parts[2] == "sdo" && parts[3] == "read") {
    op = core::Operation::sdo_read;
  } else if (parts.size() == 4 && parts[2] == "sdo" && parts[3] == "write") {
    op = core::Operation::sdo_write;
  } else if (parts.size() == 3 && parts[2] == "nmt") {
    op = core::Operation::nmt;
  } else {
    d.error = "unknown request topic";
    return d;
  }
  const auto network = core::parse_decimal(parts[0]);
  if (!network || *network == 0) {
    d.error = "network must be a number from 1";
    return d;
  }
  const auto node = core::parse_decimal(parts[1]);
  if (!node || *node > 127 || (*node == 0 && op != core::Operation::nmt)) {
    d.error = "node must be 1..127 (0 = all nodes, NMT only)";
    return d;
  }
  d.request.network = *network;
  d.request.command = decode_command(op, static_cast<std::uint8_t>(*node), msg.payload, d.options.protobuf,
                                     object ? &*object : nullptr, d.options);
  // The 3.1.1 correlationId is what the reply echoes; one inside the body
  // under another spelling does not compete with it.
  if (d.reply.corr_id) d.options.correlation_id.clear();
  return d;
}

std::string reply_body(const Reply& r, const ReplyAddress& addr) {
  if (!addr.corr_id || r.content_type.find("json") == std::string::npos) return r.body;
  // The encoder wrote one JSON object: the correlationId goes in as its last member.
  const auto close = r.body.rfind('}');
  if (close == std::string::npos) return r.body;
  const bool empty = r.body.find_first_not_of(" \t\r\n", r.body.find('{') + 1) == close;
  std::string out = r.body.substr(0, close);
  out += empty ? "\"correlationId\":" : ",\"correlationId\":";
  out += json::serialize(*addr.corr_id);
  out += r.body.substr(close);
  return out;
}

struct MqttRequests::State {
  std::string gateway_id;
  std::vector<std::string> reply_topics;
  Logger& log;
  Execute execute;
  ReplySender sender;
  Counters counters;
  LogThrottle refused_log;      // reply address refused
  LogThrottle bad_request_log;  // bad topic (answered 400)

  // Why the reply address is refused ("" = it is not).
  std::string reply_refusal(const ReplyAddress& addr) const {
    if (addr.correlation.size() > kMaxCorrelation)
      return "correlation data of " + std::to_string(addr.correlation.size()) + " bytes (at most " +
             std::to_string(kMaxCorrelation) + ")";
    if (addr.corr_id) {
      const std::size_t n = json::serialize(*addr.corr_id).size();
      if (n > kMaxCorrelation)
        return "correlationId of " + std::to_string(n) + " bytes (at most " + std::to_string(kMaxCorrelation) + ")";
    }
    if (addr.topic.empty()) return {};
    if (auto why = reply_topic_refusal(addr.topic, gateway_id, reply_topics); !why.empty())
      return "reply topic '" + addr.topic.substr(0, 200) + "': " + std::string(why);
    return {};
  }

  void send_reply(const ReplyAddress& addr, const std::string& request_topic, const Reply& r) {
    if (addr.topic.empty()) {
      log.info("mqtt: request on " + request_topic + " without reply address: status " + std::to_string(r.status));
      return;
    }
    const std::string body = reply_body(r, addr);
    const std::string status = std::to_string(r.status);
    codec::PublishProperties props;
    if (!addr.correlation.empty()) props.correlation_data = addr.correlation;
    props.user.push_back({"status", status});
    // As HTTP's Retry-After (429/503): a requester need not parse the body.
    const std::string retry = r.retry_after > 0 ? std::to_string(r.retry_after) : std::string();
    if (!retry.empty()) props.user.push_back({"retry-after", retry});
    if (!r.content_type.empty()) props.content_type = r.content_type;
    switch (sender ? sender(addr.topic, body, props) : ReplyOutcome::gone) {
      case ReplyOutcome::sent:
        ++counters.replies;
        break;
      case ReplyOutcome::not_connected:
        ++counters.replies_dropped;
        log.warn("mqtt: reply to " + addr.topic + " dropped: not connected");
        break;
      case ReplyOutcome::not_encodable:
        ++counters.replies_dropped;
        log.warn("mqtt: reply to " + addr.topic + " failed: cannot be encoded");
        break;
      case ReplyOutcome::gone:
        break;
    }
  }
};

MqttRequests::MqttRequests(std::string gateway_id, std::vector<std::string> reply_topics, Logger& log,
                           Execute execute)
    : state_(std::make_shared<State>(State{std::move(gateway_id), std::move(reply_topics), log, std::move(execute),
                                           {}, {}, {}, {}})) {}

MqttRequests::~MqttRequests() = default;

void MqttRequests::set_reply_sender(ReplySender sender) { state_->sender = std::move(sender); }

const MqttRequests::Counters& MqttRequests::counters() const { return state_->counters; }

void MqttRequests::on_publish(const codec::Publish& msg) {
  State& s = *state_;
  ++s.counters.requests;
  const std::string topic(msg.topic);
  DecodedRequest d = decode_request(msg, s.gateway_id);
  // A refused address gets nothing: a reply there is what must not
  // happen, and a request nobody may hear the answer to is not executed.
  if (auto why = s.reply_refusal(d.reply); !why.empty()) {
    ++s.counters.bad_requests;
    ++s.counters.replies_refused;
    s.refused_log.warn(s.log, "mqtt: request on " + topic.substr(0, 200) + " dropped unanswered: " + why);
    return;
  }
  if (d.error.empty() && !s.execute) d.error = "requests are not served";
  if (!d.error.empty()) {
    ++s.counters.bad_requests;
    s.bad_request_log.warn(s.log, "mqtt: request on " + topic.substr(0, 200) + ": " + d.error);
    s.send_reply(d.reply, topic, problem(400, d.error, d.options));
    return;
  }
  // Exactly once, whatever the core does; dropped once this unit is gone.
  auto done = [weak = std::weak_ptr<State>(state_), addr = std::move(d.reply), opts = std::move(d.options), topic,
               answered = std::make_shared<bool>(false)](core::Result result) {
    if (*answered) return;
    *answered = true;
    if (auto self = weak.lock()) self->send_reply(addr, topic, encode_result(result, opts));
  };
  s.execute(std::move(d.request), std::move(done));
}

}  // namespace gateway::mqtt
