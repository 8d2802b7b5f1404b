// The MQTT request front end (../shared/api-contract.md): made by the
// composition root (app/front_ends.hpp: serve_mqtt_requests) from the
// request core alone and handed to the App, whose publisher then subscribes
// (QoS 1) to request_filters() (topic_filter.hpp: canopen/<gw>/+/+/sdo/read,
// .../sdo/write and .../nmt) and hands every PUBLISH it receives on them to
// MqttRequests::on_publish. This unit decodes topic and body once into a
// core::Request, has it executed (the request core: identity, roles, limits,
// audit) and encodes the core::Result as the reply, which goes out through
// the publisher's ReplySender.
//
// Decoding: the network and node come from the topic (decimal; node 0 only
// for nmt); a bad topic is answered 400 here. Reply address: MQTT 5
// response topic + correlation data (copied to the reply, which also
// carries a user property "status" with the HTTP-style code, and
// "retry-after" in seconds when the core said when to try again, as HTTP's
// Retry-After with 429/503); otherwise, or
// over 3.1.1, the JSON body's "replyTo" (string) and "correlationId" (any
// JSON value): both are taken out of the body before it is decoded, and a
// JSON reply gets "correlationId" added. The bearer token: MQTT 5 user
// property "authorization" ("Bearer <t>" or the token), else "token" in a
// JSON body (taken out too); the core checks it. A body with MQTT 5 content
// type "application/x-protobuf" is protobuf (SdoReadRequest, ...). A body
// that does not decode still goes to the core (core::Undecodable), which
// answers 400 after identifying and rate-limiting the caller. A request
// without a reply address is still executed, its reply only logged.
//
// A reply topic must pass reply_topic_refusal (topic_filter.hpp: the
// contract's default rule, or the configured reply topics) and correlation
// data (or the serialized correlationId) must be at most kMaxCorrelation
// bytes; otherwise the request is dropped: not executed, not answered,
// counted in bad_requests and replies_refused, logged at most once per 10 s.
//
// Thread safety: the io thread only (the publisher's). The execute function
// and logger MUST outlive this object; replies that complete after it is
// gone are dropped.
#pragma once

#include <boost/json/value.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/request.hpp"
#include "log.hpp"
#include "mqtt/mqtt_codec.hpp"
#include "mqtt/reply_sender.hpp"
#include "messages/request_codec.hpp"

namespace gateway::mqtt {

// Largest MQTT 5 correlation data, or 3.1.1 correlationId as JSON text, a
// request may carry (the reply echoes it).
constexpr std::size_t kMaxCorrelation = 1024;

// Where a request's reply goes, as decoded from it.
struct ReplyAddress {
  std::string topic;                          // "" = none: the reply is only logged
  std::string correlation;                    // MQTT 5 correlation data
  std::optional<boost::json::value> corr_id;  // 3.1.1 correlationId (added to a JSON reply)
  bool v5 = false;                            // the address came as MQTT 5 properties
};

// One request PUBLISH decoded: the request for the core (unless `error`),
// where its reply goes and how it is encoded.
struct DecodedRequest {
  core::Request request;
  ReplyAddress reply;
  ReplyOptions options;  // protobuf, and the correlation id from inside the body
  std::string error;     // a bad topic: answered 400 without the core
};

// Decodes a PUBLISH on a request topic of gateway `gateway_id`. Never throws.
DecodedRequest decode_request(const codec::Publish& msg, std::string_view gateway_id);

// The reply body for `r`: as the request was encoded (JSON or protobuf),
// with a 3.1.1 correlationId added to a JSON object.
std::string reply_body(const Reply& r, const ReplyAddress& addr);

class MqttRequests {
 public:
  using Done = std::function<void(core::Result)>;
  using Execute = std::function<void(core::Request, Done)>;
  struct Counters {
    std::uint64_t requests = 0;
    std::uint64_t bad_requests = 0;     // bad topic or reply address
    std::uint64_t replies_refused = 0;  // requests dropped for their reply address
    std::uint64_t replies = 0;
    std::uint64_t replies_dropped = 0;  // not connected when the reply was ready, or not encodable
  };

  // reply_topics: filters a reply topic must match instead of the default
  // rule (mqtt.reply-topics); each MUST be valid (topic_filter_problem).
  // Without `execute` every request is answered 400 "requests are not served".
  MqttRequests(std::string gateway_id, std::vector<std::string> reply_topics, Logger& log, Execute execute);
  ~MqttRequests();
  MqttRequests(const MqttRequests&) = delete;
  MqttRequests& operator=(const MqttRequests&) = delete;

  // Where replies go (the publisher's reply_sender()); set before requests come.
  void set_reply_sender(ReplySender sender);
  // The publisher's hand-off: one PUBLISH received on a request topic.
  void on_publish(const codec::Publish& msg);
  const Counters& counters() const;

  struct State;

 private:
  std::shared_ptr<State> state_;
};

}  // namespace gateway::mqtt
