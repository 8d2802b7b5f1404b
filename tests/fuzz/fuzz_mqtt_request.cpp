// Fuzzes the MQTT request front end with what any client allowed to publish
// to canopen/<gw>/... sends (issue 27 item 11): the input is split into a
// topic, MQTT 5 properties (response topic, correlation data, a user
// property) and the body, decoded by decode_request and served by
// MqttRequests::on_publish against a stand-in core that answers a value.
// Invariants: nothing crashes or throws; a request is either refused with
// its error or reaches the core once; at most one reply per request, only
// to a topic the default rule allows (no wildcard, a `reply`/`replies`
// level, not under $, spBv1.0/ or another system's canopen/), never with
// correlation data over kMaxCorrelation.
// fuzz-libs: gateway_mqtt_requests
// fuzz-seeds: tests/fuzz/corpus/mqtt_request
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "log.hpp"
#include "mqtt_requests/mqtt_requests.hpp"

namespace mq = gateway::mqtt;

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "invariant broken: %s\n", what);
    std::abort();
  }
}

// The next field: up to a 0 byte (or the end).
std::string_view field(std::string_view& in) {
  const auto at = in.find('\0');
  const std::string_view f = in.substr(0, at);
  in = at == std::string_view::npos ? std::string_view{} : in.substr(at + 1);
  return f;
}

bool has_level(std::string_view topic, std::string_view level) {
  std::size_t from = 0;
  for (;;) {
    const auto slash = topic.find('/', from);
    if (topic.substr(from, slash == std::string_view::npos ? std::string_view::npos : slash - from) == level)
      return true;
    if (slash == std::string_view::npos) return false;
    from = slash + 1;
  }
}

bool allowed_reply(std::string_view t) {
  if (t.empty() || t.find_first_of("+#") != std::string_view::npos) return false;
  if (t.starts_with("$") || t.starts_with("spBv1.0/")) return false;
  if (t.starts_with("canopen/") && !t.starts_with("canopen/gw1/reply/")) return false;
  return has_level(t, "reply") || has_level(t, "replies");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::string_view in(reinterpret_cast<const char*>(data), size);
  const std::uint8_t flags = static_cast<std::uint8_t>(in[0]);
  in.remove_prefix(1);
  // A topic of gateway gw1 (the request levels come from the input).
  const std::string topic = "canopen/gw1/" + std::string(field(in));
  const std::string response_topic(field(in));
  const std::string correlation(field(in));
  const std::string user_value(field(in));
  const std::string body(in);

  mq::codec::Publish p;
  p.topic = topic;
  p.payload = body;
  p.qos = flags & 1;
  if (flags & 2) p.props.response_topic = response_topic;
  if (flags & 4) p.props.correlation_data = correlation;
  if (flags & 8) p.props.user.push_back({"authorization", user_value});
  if (flags & 16) p.props.content_type = "application/x-protobuf";

  static std::FILE* null = std::fopen("/dev/null", "w");
  static gateway::Logger log(gateway::LogLevel::Error, null);
  try {
    const auto d = mq::decode_request(p, "gw1");
    check(mq::decode_request(p, "gw1").error == d.error, "decoding is a function of the PUBLISH");

    int executed = 0, replies = 0;
    mq::MqttRequests unit("gw1", {}, log, [&](gateway::core::Request, mq::MqttRequests::Done done) {
      ++executed;
      done(gateway::core::SdoValue{canopen::Value::of_unsigned(canopen::DataType::Unsigned8, 42)});
    });
    unit.set_reply_sender([&](std::string_view t, std::string_view, const mq::codec::PublishProperties& props) {
      ++replies;
      check(allowed_reply(t), "a reply only to an allowed reply topic");
      check(!props.correlation_data || props.correlation_data->size() <= mq::kMaxCorrelation,
            "correlation data within its bound");
      return mq::ReplyOutcome::sent;
    });
    unit.on_publish(p);
    check(executed <= 1, "one request reaches the core at most once");
    check(replies <= 1, "at most one reply per request");
    const auto& c = unit.counters();
    check(c.requests == 1, "every PUBLISH counted");
    check(executed == 0 || d.error.empty(), "a request refused by its topic never reaches the core");
  } catch (...) {
    check(false, "no exception");
  }
  return 0;
}
