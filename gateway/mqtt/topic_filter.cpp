#include "mqtt/topic_filter.hpp"

#include <vector>

#include "mqtt/mqtt_codec.hpp"

namespace gateway::mqtt {

namespace {

constexpr std::size_t kMaxTopic = 65535;  // an MQTT UTF-8 string

bool starts_with(std::string_view s, std::string_view prefix) { return s.substr(0, prefix.size()) == prefix; }

}  // namespace

std::vector<std::string_view> topic_levels(std::string_view s) {
  std::vector<std::string_view> out;
  for (;;) {
    const auto pos = s.find('/');
    out.push_back(s.substr(0, pos));
    if (pos == std::string_view::npos) return out;
    s.remove_prefix(pos + 1);
  }
}

std::array<std::string, 3> request_filters(std::string_view gateway_id) {
  const std::string base = "canopen/" + std::string(gateway_id);
  return {base + "/+/+/sdo/read", base + "/+/+/sdo/write", base + "/+/+/nmt"};
}

std::string_view topic_filter_problem(std::string_view filter) {
  if (filter.empty()) return "an empty topic filter";
  if (filter.size() > kMaxTopic) return "longer than 65535 bytes";
  if (!codec::valid_utf8(filter)) return "not UTF-8 (or contains U+0000)";
  const auto l = topic_levels(filter);
  for (std::size_t i = 0; i < l.size(); ++i) {
    if (l[i].find('#') != std::string_view::npos && (l[i] != "#" || i + 1 != l.size()))
      return "'#' must be a whole level and the last one (e.g. a/reply/#)";
    if (l[i].find('+') != std::string_view::npos && l[i] != "+")
      return "'+' must be a whole level (e.g. a/+/reply)";
  }
  return {};
}

bool topic_matches(std::string_view filter, std::string_view topic) {
  if (!topic.empty() && topic.front() == '$' && !filter.empty() && (filter.front() == '+' || filter.front() == '#'))
    return false;
  const auto f = topic_levels(filter);
  const auto t = topic_levels(topic);
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f[i] == "#") return true;  // this level and below, the parent included ("a/#" matches "a")
    if (i >= t.size()) return false;
    if (f[i] != "+" && f[i] != t[i]) return false;
  }
  return f.size() == t.size();
}

std::string_view reply_topic_refusal(std::string_view topic, std::string_view gateway_id,
                                     std::span<const std::string> filters) {
  if (topic.empty()) return "an empty topic";
  if (topic.find_first_of("+#") != std::string_view::npos) return "wildcards are for subscriptions, not replies";
  if (topic.size() > kMaxTopic || !codec::valid_utf8(topic)) return "not an MQTT topic name";
  for (const auto& f : request_filters(gateway_id))
    if (topic_matches(f, topic)) return "one of this gateway's request topics (a loop)";
  if (!filters.empty()) {
    for (const auto& f : filters)
      if (topic_matches(f, topic)) return {};
    return "no mqtt.reply-topics filter matches it";
  }
  if (topic.front() == '$') return "under '$' (broker topics)";
  if (starts_with(topic, "spBv1.0/")) return "under 'spBv1.0/' (Sparkplug)";
  if (starts_with(topic, "canopen/") && !starts_with(topic, "canopen/" + std::string(gateway_id) + "/reply/"))
    return "under 'canopen/' but not under this gateway's canopen/<gateway id>/reply/";
  for (auto level : topic_levels(topic))
    if (level == "reply" || level == "replies") return {};
  return "it has no level named 'reply' or 'replies' (e.g. myapp/reply/42)";
}

}  // namespace gateway::mqtt
