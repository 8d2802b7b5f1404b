// How a request front end (mqtt_requests/) sends a reply over the
// publisher's session: MqttPublisher::reply_sender() gives one; the front
// end calls it with the reply topic, body and MQTT 5 properties. It may be
// kept and called after the publisher is gone (ReplyOutcome::gone).
//
// Thread safety: call on the publisher's io thread only.
#pragma once

#include <cstdint>
#include <functional>
#include <string_view>

#include "mqtt/mqtt_codec.hpp"

namespace gateway::mqtt {

// How the publisher took a reply.
enum class ReplyOutcome : std::uint8_t { sent, not_connected, not_encodable, gone };
using ReplySender =
    std::function<ReplyOutcome(std::string_view topic, std::string_view body, const codec::PublishProperties& props)>;

}  // namespace gateway::mqtt
