// MQTT topic filters (MQTT 3.1.1 and 5, 4.7): their syntax and matching,
// and the rule for the topics the gateway publishes request replies to
// (../shared/api-contract.md, "MQTT topics"). A requester chooses the reply
// topic, so without this rule anyone allowed to publish a request could make
// the gateway publish into its own topics (status, node states), another
// gateway's or another system's (Sparkplug, $SYS).
//
// Pure functions; thread-safe.
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace gateway::mqtt {

// The levels of a topic name or filter ("a//b" -> "a", "", "b").
std::vector<std::string_view> topic_levels(std::string_view topic);

// The filters the gateway `gateway_id` subscribes to for requests:
// canopen/<gw>/+/+/sdo/read, canopen/<gw>/+/+/sdo/write, canopen/<gw>/+/+/nmt.
std::array<std::string, 3> request_filters(std::string_view gateway_id);

// Why `filter` is not a valid topic filter: empty, not UTF-8 (or U+0000),
// over 65535 bytes, '#' not alone in the last level, '+' not alone in its
// level. "" when it is valid.
std::string_view topic_filter_problem(std::string_view filter);

// Whether topic name `topic` matches the valid filter `filter`: '+' one
// level, '#' the parent level and everything below it. Filters starting
// with a wildcard do not match topics starting with '$' (MQTT 4.7.2).
bool topic_matches(std::string_view filter, std::string_view topic);

// Why the gateway `gateway_id` does not publish a reply to `topic`; "" when
// it does. Never: an empty topic, one with wildcards, not UTF-8 or too long,
// or one of the gateway's own request topics (canopen/<gw>/+/+/sdo/read,
// .../sdo/write, canopen/<gw>/+/+/nmt: a loop). Then, without `filters`
// (mqtt.reply-topics), the default: a level named "reply" or "replies", not
// under "$" or "spBv1.0/", and not under "canopen/" except under
// "canopen/<gw>/reply/". With `filters`, instead of the default: a topic one
// of them matches.
std::string_view reply_topic_refusal(std::string_view topic, std::string_view gateway_id,
                                     std::span<const std::string> filters);

}  // namespace gateway::mqtt
