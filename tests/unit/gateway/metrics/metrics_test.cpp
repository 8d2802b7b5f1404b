#include "metrics/metrics.hpp"

#include "metrics/registry.hpp"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace gateway::metrics {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// What the gateway's components report, as fixed values: each field feeds
// the register_* function of the component that owns it.
struct Values {
  std::string version;  // build_info version label; empty = no build_info family
  std::vector<NetworkMetrics> networks;
  std::uint64_t sdo_requests = 0, sdo_aborts = 0, sdo_timeouts = 0;
  std::uint64_t nmt_commands = 0;
  // SDO transfer latency (submit to result, seconds): counts per upper bound,
  // not cumulative, the last for slower ones (TextWriter::histogram). Empty
  // bounds = no histogram family.
  std::vector<double> sdo_latency_bounds;
  std::vector<std::uint64_t> sdo_latency_counts;
  double sdo_latency_sum = 0.0;
  // Requests refused with 401/403 by the request handler (MQTT requests,
  // NMT resets); the HTTP authorizer's refusals are in http_responses_by_status.
  // nullopt = no such family.
  std::optional<std::uint64_t> request_auth_failures;
  // Requests the request handler answered 429 for their caller: over its
  // share of a node's SDO queue, over the MQTT rate limit. nullopt = no such family.
  std::optional<std::uint64_t> requests_over_sdo_share, mqtt_requests_rate_limited;
  std::map<std::string, std::uint64_t> events_by_kind;  // "tpdo" -> n
  bool mqtt_enabled = false;  // false: only canopen_gateway_mqtt_enabled 0 is written
  bool mqtt_connected = false;
  std::uint64_t mqtt_published = 0, mqtt_acked = 0, mqtt_dropped = 0;
  std::uint64_t mqtt_queue_depth = 0, mqtt_queue_bytes = 0;
  std::uint64_t mqtt_reconnects = 0;
  std::uint64_t mqtt_requests_refused = 0;  // dropped unanswered for their reply address
  // The MQTT queue's storage (mqtt/outbound_queue.hpp, disk_queue.hpp).
  std::map<std::string, std::uint64_t> mqtt_dropped_by_reason;  // "storage_full" -> n
  std::uint64_t mqtt_memory_depth = 0;
  std::uint64_t mqtt_spilled = 0;
  std::uint64_t mqtt_storage_bytes = 0, mqtt_storage_syncs = 0, mqtt_storage_errors = 0;
  bool mqtt_storage_failing = false;
  std::uint64_t mqtt_corrupt_records = 0, mqtt_corrupt_bytes = 0;
  std::uint64_t mqtt_stalls = 0;
  std::uint64_t ws_clients = 0, ws_messages_sent = 0, ws_messages_dropped = 0;
  std::map<int, std::uint64_t> http_responses_by_status;  // 200 -> n
  std::optional<HttpConnectionMetrics> http_connections;   // nullopt = no such families
  double uptime_seconds = 0.0;
};

// The /metrics text for `s`: the families registered per component in the
// order the gateway registers them (app.cpp, api_routes.cpp), reading `s`.
std::string render(const Values& s) {
  Registry r;
  if (!s.version.empty()) register_build_info(r, s.version);
  register_network_families(r);
  for (const auto& n : s.networks) register_network(r, [&n] { return n; });
  register_requests(
      r,
      [&s] {
        return RequestMetrics{s.sdo_requests,        s.sdo_aborts,           s.sdo_timeouts, s.nmt_commands,
                              s.request_auth_failures, s.requests_over_sdo_share, s.mqtt_requests_rate_limited};
      },
      s.sdo_latency_bounds,
      s.sdo_latency_bounds.empty() ? std::function<HistogramValues()>{}
                                   : [&s] { return HistogramValues{s.sdo_latency_counts, s.sdo_latency_sum}; });
  register_events_by_kind(r, [&s] { return s.events_by_kind; });
  if (s.mqtt_enabled)
    register_mqtt(r, [&s] {
      return MqttMetrics{s.mqtt_connected,       s.mqtt_published,      s.mqtt_acked,         s.mqtt_dropped,
                         s.mqtt_queue_depth,     s.mqtt_queue_bytes,    s.mqtt_reconnects,    s.mqtt_requests_refused,
                         s.mqtt_dropped_by_reason, s.mqtt_memory_depth, s.mqtt_spilled,       s.mqtt_storage_bytes,
                         s.mqtt_storage_syncs,   s.mqtt_storage_errors, s.mqtt_storage_failing, s.mqtt_corrupt_records,
                         s.mqtt_corrupt_bytes,   s.mqtt_stalls,            {}};
    });
  else
    register_mqtt(r, {});
  register_http_server(
      r,
      [&s] {
        HttpServerMetrics m{s.ws_clients, s.ws_messages_sent, s.ws_messages_dropped, s.http_responses_by_status, {}};
        if (s.http_connections) m.connections = *s.http_connections;
        return m;
      },
      s.http_connections.has_value());
  register_uptime(r, [&s] { return s.uptime_seconds; });
  return r.render();
}

Values full_snapshot() {
  Values s;
  s.version = "1.2.3";
  NetworkMetrics a;
  a.network = 1;
  a.interface = "can0";
  a.bus_state = "error-active";
  a.rx_frames = 1000;
  a.tx_frames = 20;
  a.rx_dropped = 1;
  a.error_frames = 3;
  a.reopens = 2;
  a.events = 40;
  NetworkMetrics b = a;
  b.network = 2;
  b.interface = "vcan\"x\\y\nz";
  b.bus_state = "bus-off";
  s.networks = {a, b};
  s.sdo_requests = 10;
  s.sdo_aborts = 1;
  s.sdo_timeouts = 2;
  s.nmt_commands = 4;
  s.events_by_kind = {{"tpdo", 30}, {"emcy", 2}, {"heartbeat", 8}};
  s.mqtt_enabled = true;
  s.mqtt_connected = true;
  s.mqtt_published = 40;
  s.mqtt_acked = 39;
  s.mqtt_queue_depth = 1;
  s.mqtt_queue_bytes = 128;
  s.ws_clients = 2;
  s.ws_messages_sent = 80;
  s.http_responses_by_status = {{200, 5}, {404, 1}, {503, 2}};
  s.uptime_seconds = 12.5;
  return s;
}

TEST(MetricsValue, IntegersExactDoublesLikePercent17g) {
  EXPECT_EQ(Value(std::uint64_t{18446744073709551615ULL}).to_string(), "18446744073709551615");
  EXPECT_EQ(Value(std::int64_t{-9223372036854775807LL - 1}).to_string(), "-9223372036854775808");
  EXPECT_EQ(Value(0).to_string(), "0");
  EXPECT_EQ(Value(true).to_string(), "1");
  EXPECT_EQ(Value(false).to_string(), "0");
  EXPECT_EQ(Value(12.5).to_string(), "12.5");
  EXPECT_EQ(Value(3.0).to_string(), "3");
  EXPECT_EQ(Value(0.1).to_string(), "0.10000000000000001");
  EXPECT_EQ(Value(1e20).to_string(), "1e+20");
  EXPECT_EQ(Value(std::numeric_limits<double>::infinity()).to_string(), "+Inf");
  EXPECT_EQ(Value(-std::numeric_limits<double>::infinity()).to_string(), "-Inf");
  EXPECT_EQ(Value(std::nan("")).to_string(), "NaN");
}

TEST(MetricsNames, ValidityRules) {
  EXPECT_TRUE(valid_metric_name("canopen_gateway_x_total"));
  EXPECT_TRUE(valid_metric_name(":a:b_9"));
  EXPECT_FALSE(valid_metric_name(""));
  EXPECT_FALSE(valid_metric_name("9abc"));
  EXPECT_FALSE(valid_metric_name("a-b"));
  EXPECT_FALSE(valid_metric_name("a b"));
  EXPECT_TRUE(valid_label_name("network"));
  EXPECT_TRUE(valid_label_name("_x1"));
  EXPECT_FALSE(valid_label_name("a:b"));
  EXPECT_FALSE(valid_label_name("__name__"));
  EXPECT_FALSE(valid_label_name("1a"));
  EXPECT_FALSE(valid_label_name(""));
}

TEST(MetricsEscape, LabelValuesAndHelp) {
  EXPECT_EQ(escape_label_value("plain"), "plain");
  EXPECT_EQ(escape_label_value("a\\b"), "a\\\\b");
  EXPECT_EQ(escape_label_value("say \"hi\""), "say \\\"hi\\\"");
  EXPECT_EQ(escape_label_value("l1\nl2"), "l1\\nl2");
  EXPECT_EQ(escape_help("a\\b \"q\"\nc"), "a\\\\b \"q\"\\nc");

  TextWriter w;
  w.family("m", "Help with \\ and\nnewline.", MetricType::Gauge);
  w.sample("m", {{"v", "x\"y\\z\nw"}}, 1);
  EXPECT_EQ(w.str(),
            "# HELP m Help with \\\\ and\\nnewline.\n"
            "# TYPE m gauge\n"
            "m{v=\"x\\\"y\\\\z\\nw\"} 1\n");
}

TEST(MetricsWriter, FamilyWrittenOnceWithAllSamples) {
  TextWriter w;
  w.family("a_total", "A.", MetricType::Counter);
  w.family("b", "B.", MetricType::Gauge);
  w.sample("a_total", {{"k", "1"}}, 1);
  w.sample("b", {}, 2.5);
  w.family("a_total", "A.", MetricType::Counter);  // same again: no-op
  w.sample("a_total", {{"k", "2"}}, 2);
  w.family("empty", "No samples.", MetricType::Gauge);
  EXPECT_EQ(w.str(),
            "# HELP a_total A.\n"
            "# TYPE a_total counter\n"
            "a_total{k=\"1\"} 1\n"
            "a_total{k=\"2\"} 2\n"
            "# HELP b B.\n"
            "# TYPE b gauge\n"
            "b 2.5\n"
            "# HELP empty No samples.\n"
            "# TYPE empty gauge\n");
}

TEST(MetricsWriter, MisuseThrows) {
  TextWriter w;
  EXPECT_THROW(w.family("bad-name", "x", MetricType::Gauge), std::invalid_argument);
  w.family("m", "M.", MetricType::Gauge);
  EXPECT_THROW(w.family("m", "M.", MetricType::Counter), std::invalid_argument);
  EXPECT_THROW(w.family("m", "Other help.", MetricType::Gauge), std::invalid_argument);
  EXPECT_THROW(w.sample("undeclared", {}, 1), std::invalid_argument);
  EXPECT_THROW(w.sample("m", {{"bad-label", "x"}}, 1), std::invalid_argument);
  EXPECT_THROW(w.sample("m", {{"__reserved", "x"}}, 1), std::invalid_argument);
  w.sample("m", {{"a", "1"}}, 1);
  EXPECT_THROW(w.sample("m", {{"a", "1"}}, 2), std::invalid_argument);
  w.sample("m", {{"a", "2"}}, 1);
  w.sample("m", {}, 1);
  EXPECT_THROW(w.sample("m", {}, 1), std::invalid_argument);
}

TEST(RenderMetrics, GoldenSmallSnapshot) {
  Values s;
  NetworkMetrics n;
  n.network = 1;
  n.interface = "can0";
  n.bus_state = "error-passive";
  n.rx_frames = 7;
  n.tx_frames = 3;
  n.rx_dropped = 1;
  n.error_frames = 2;
  n.events = 5;
  s.networks.push_back(n);
  s.sdo_requests = 4;
  s.sdo_aborts = 1;
  s.nmt_commands = 2;
  s.events_by_kind = {{"tpdo", 5}};
  s.mqtt_enabled = false;
  s.ws_clients = 1;
  s.ws_messages_sent = 9;
  s.http_responses_by_status = {{200, 3}, {404, 1}};
  s.uptime_seconds = 1.25;
  const std::string expected =
      "# HELP canopen_gateway_can_frames_total CAN frames received (rx) and sent (tx) per network.\n"
      "# TYPE canopen_gateway_can_frames_total counter\n"
      "canopen_gateway_can_frames_total{network=\"1\",interface=\"can0\",direction=\"rx\"} 7\n"
      "canopen_gateway_can_frames_total{network=\"1\",interface=\"can0\",direction=\"tx\"} 3\n"
      "# HELP canopen_gateway_can_frames_dropped_total CAN frames lost per network: rx overflow in kernel or "
      "controller, tx queue full.\n"
      "# TYPE canopen_gateway_can_frames_dropped_total counter\n"
      "canopen_gateway_can_frames_dropped_total{network=\"1\",interface=\"can0\",direction=\"rx\"} 1\n"
      "canopen_gateway_can_frames_dropped_total{network=\"1\",interface=\"can0\",direction=\"tx\"} 0\n"
      "# HELP canopen_gateway_can_error_frames_total CAN error frames received per network.\n"
      "# TYPE canopen_gateway_can_error_frames_total counter\n"
      "canopen_gateway_can_error_frames_total{network=\"1\",interface=\"can0\"} 2\n"
      "# HELP canopen_gateway_can_reopens_total Times the CAN socket of a network was reopened after the link "
      "came back.\n"
      "# TYPE canopen_gateway_can_reopens_total counter\n"
      "canopen_gateway_can_reopens_total{network=\"1\",interface=\"can0\"} 0\n"
      "# HELP canopen_gateway_bus_state CAN controller state per network: 1 for the current state, 0 for the "
      "others.\n"
      "# TYPE canopen_gateway_bus_state gauge\n"
      "canopen_gateway_bus_state{network=\"1\",interface=\"can0\",state=\"error-active\"} 0\n"
      "canopen_gateway_bus_state{network=\"1\",interface=\"can0\",state=\"error-warning\"} 0\n"
      "canopen_gateway_bus_state{network=\"1\",interface=\"can0\",state=\"error-passive\"} 1\n"
      "canopen_gateway_bus_state{network=\"1\",interface=\"can0\",state=\"bus-off\"} 0\n"
      "canopen_gateway_bus_state{network=\"1\",interface=\"can0\",state=\"down\"} 0\n"
      "# HELP canopen_gateway_network_events_total Events produced by each network.\n"
      "# TYPE canopen_gateway_network_events_total counter\n"
      "canopen_gateway_network_events_total{network=\"1\",interface=\"can0\"} 5\n"
      "# HELP canopen_gateway_sdo_requests_total SDO transfers started by the gateway.\n"
      "# TYPE canopen_gateway_sdo_requests_total counter\n"
      "canopen_gateway_sdo_requests_total 4\n"
      "# HELP canopen_gateway_sdo_aborts_total SDO transfers that ended with an abort.\n"
      "# TYPE canopen_gateway_sdo_aborts_total counter\n"
      "canopen_gateway_sdo_aborts_total 1\n"
      "# HELP canopen_gateway_sdo_timeouts_total SDO transfers that timed out.\n"
      "# TYPE canopen_gateway_sdo_timeouts_total counter\n"
      "canopen_gateway_sdo_timeouts_total 0\n"
      "# HELP canopen_gateway_nmt_commands_total NMT commands sent.\n"
      "# TYPE canopen_gateway_nmt_commands_total counter\n"
      "canopen_gateway_nmt_commands_total 2\n"
      "# HELP canopen_gateway_events_published_total Events published to clients, by kind.\n"
      "# TYPE canopen_gateway_events_published_total counter\n"
      "canopen_gateway_events_published_total{kind=\"tpdo\"} 5\n"
      "# HELP canopen_gateway_mqtt_enabled 1 when MQTT publishing is configured.\n"
      "# TYPE canopen_gateway_mqtt_enabled gauge\n"
      "canopen_gateway_mqtt_enabled 0\n"
      "# HELP canopen_gateway_websocket_clients Connected WebSocket clients.\n"
      "# TYPE canopen_gateway_websocket_clients gauge\n"
      "canopen_gateway_websocket_clients 1\n"
      "# HELP canopen_gateway_websocket_messages_total WebSocket messages by result: sent, or dropped for a slow "
      "client.\n"
      "# TYPE canopen_gateway_websocket_messages_total counter\n"
      "canopen_gateway_websocket_messages_total{result=\"sent\"} 9\n"
      "canopen_gateway_websocket_messages_total{result=\"dropped\"} 0\n"
      "# HELP canopen_gateway_http_responses_total HTTP responses by status code.\n"
      "# TYPE canopen_gateway_http_responses_total counter\n"
      "canopen_gateway_http_responses_total{code=\"200\"} 3\n"
      "canopen_gateway_http_responses_total{code=\"404\"} 1\n"
      "# HELP canopen_gateway_uptime_seconds Seconds since the gateway started.\n"
      "# TYPE canopen_gateway_uptime_seconds gauge\n"
      "canopen_gateway_uptime_seconds 1.25\n";
  EXPECT_EQ(render(s), expected);
}

TEST(RenderMetrics, MqttFamiliesWhenEnabled) {
  const std::string text = render(full_snapshot());
  EXPECT_NE(text.find("canopen_gateway_mqtt_enabled 1\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_connected 1\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_messages_total{result=\"published\"} 40\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_messages_total{result=\"acked\"} 39\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_messages_total{result=\"dropped\"} 0\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_queue_depth 1\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_queue_bytes 128\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_reconnects_total 0\n"), std::string::npos);
  EXPECT_NE(text.find("# HELP canopen_gateway_mqtt_requests_refused_total MQTT requests dropped unanswered"),
            std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_mqtt_requests_refused_total 0\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_build_info{version=\"1.2.3\"} 1\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_bus_state{network=\"2\",interface=\"vcan\\\"x\\\\y\\nz\",state=\"bus-off\"} 1\n"),
            std::string::npos);
  EXPECT_EQ(render(Values{}).find("mqtt_connected"), std::string::npos);
}

// Issue 12: 429s for a caller's share of a node's SDO queue and for the
// MQTT rate limit, one series each.
TEST(RenderMetrics, RequestsLimitedPerCallerByReason) {
  Values s = full_snapshot();
  s.requests_over_sdo_share = 3;
  s.mqtt_requests_rate_limited = 7;
  const std::string text = render(s);
  EXPECT_NE(text.find("# HELP canopen_gateway_requests_limited_total Requests answered 429 for their caller"),
            std::string::npos);
  EXPECT_NE(text.find("# TYPE canopen_gateway_requests_limited_total counter\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_requests_limited_total{reason=\"sdo-queue-share\"} 3\n"), std::string::npos);
  EXPECT_NE(text.find("canopen_gateway_requests_limited_total{reason=\"mqtt-rate-limit\"} 7\n"), std::string::npos);
  EXPECT_EQ(render(full_snapshot()).find("requests_limited"), std::string::npos);  // no App counters: no family
}

// Issue 12: what the MQTT queue's storage does (drops by reason, a full
// disk, corruption found at start, stalls) is visible without the log.
TEST(RenderMetrics, MqttStorageFamilies) {
  auto s = full_snapshot();
  s.mqtt_dropped_by_reason = {{"storage_full", 12}, {"memory_full", 0}, {"queue_full", 3}};
  s.mqtt_memory_depth = 7;
  s.mqtt_spilled = 900;
  s.mqtt_storage_bytes = 4096;
  s.mqtt_storage_syncs = 2;
  s.mqtt_storage_errors = 5;
  s.mqtt_storage_failing = true;
  s.mqtt_corrupt_records = 1;
  s.mqtt_corrupt_bytes = 29;
  s.mqtt_stalls = 0;
  const std::string text = render(s);
  for (const char* line :
       {"canopen_gateway_mqtt_dropped_total{reason=\"memory_full\"} 0\n",
        "canopen_gateway_mqtt_dropped_total{reason=\"queue_full\"} 3\n",
        "canopen_gateway_mqtt_dropped_total{reason=\"storage_full\"} 12\n", "canopen_gateway_mqtt_memory_queue_depth 7\n",
        "canopen_gateway_mqtt_spilled_total 900\n", "canopen_gateway_mqtt_storage_written_bytes_total 4096\n",
        "canopen_gateway_mqtt_storage_syncs_total 2\n", "canopen_gateway_mqtt_storage_errors_total 5\n",
        "canopen_gateway_mqtt_storage_failing 1\n", "canopen_gateway_mqtt_queue_corrupt_records_total 1\n",
        "canopen_gateway_mqtt_queue_corrupt_bytes_total 29\n", "canopen_gateway_mqtt_stalls_total 0\n",
        "# TYPE canopen_gateway_mqtt_storage_failing gauge\n", "# TYPE canopen_gateway_mqtt_dropped_total counter\n"})
    EXPECT_NE(text.find(line), std::string::npos) << line;
  EXPECT_EQ(render(Values{}).find("mqtt_storage"), std::string::npos);
}

// Checks the exposition the way a scraper would: every family has exactly one
// HELP and one TYPE before its samples, every sample line parses as
// name{labels} value and belongs to the family just declared, and no series
// repeats.
void check_exposition(const std::string& text) {
  ASSERT_FALSE(text.empty());
  ASSERT_EQ(text.back(), '\n');
  static const std::regex help_re(R"(# HELP ([a-zA-Z_:][a-zA-Z0-9_:]*) (.*))");
  static const std::regex type_re(R"(# TYPE ([a-zA-Z_:][a-zA-Z0-9_:]*) (counter|gauge))");
  static const std::regex sample_re(
      R"re(([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\\\|\\"|\\n)*")re"
      R"re((?:,[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\\\|\\"|\\n)*")*\})? )re"
      R"re((NaN|[+-]Inf|-?[0-9]+(?:\.[0-9]+)?(?:e[+-][0-9]+)?))re");
  std::set<std::string> helped, typed, series;
  std::string current;
  for (const auto& line : lines_of(text)) {
    std::smatch m;
    if (std::regex_match(line, m, help_re)) {
      EXPECT_TRUE(helped.insert(m[1]).second) << "HELP twice: " << line;
      current = m[1];
    } else if (std::regex_match(line, m, type_re)) {
      EXPECT_EQ(m[1], current) << "TYPE not right after its HELP: " << line;
      EXPECT_TRUE(typed.insert(m[1]).second) << "TYPE twice: " << line;
    } else {
      ASSERT_NE(line.rfind('#', 0), 0U) << "unexpected comment: " << line;
      ASSERT_TRUE(std::regex_match(line, m, sample_re)) << "bad sample line: " << line;
      EXPECT_EQ(m[1], current) << "sample outside its family: " << line;
      EXPECT_TRUE(typed.count(current)) << line;
      EXPECT_TRUE(series.insert(std::string(m[1]) + std::string(m[2])).second) << "duplicate series: " << line;
    }
  }
  EXPECT_EQ(helped, typed);
}

TEST(ExpositionChecker, RejectsBadText) {
  EXPECT_FATAL_FAILURE(check_exposition("# HELP m x\n# TYPE m gauge\nm{a=\"open} 1\n"), "bad sample line");
  EXPECT_FATAL_FAILURE(check_exposition("# HELP m x\n# TYPE m gauge\nm{a=\"x\ny\"} 1\n"), "bad sample line");
  EXPECT_FATAL_FAILURE(check_exposition("# HELP m x\n# TYPE m gauge\nm 1,5\n"), "bad sample line");
  EXPECT_NONFATAL_FAILURE(check_exposition("# HELP m x\n# TYPE m gauge\nm 1\nm 2\n"), "duplicate series");
  EXPECT_NONFATAL_FAILURE(check_exposition("# HELP m x\n# TYPE m gauge\n# HELP m x\n"), "HELP twice");
  EXPECT_NONFATAL_FAILURE(check_exposition("# HELP m x\n# TYPE m gauge\nn 1\n"), "outside its family");
}

TEST(RenderMetrics, ParsesAsExposition) {
  check_exposition(render(full_snapshot()));
  Values s = full_snapshot();
  s.mqtt_enabled = false;
  s.uptime_seconds = 0.1;
  check_exposition(render(s));
  check_exposition(render(Values{}));
}

TEST(RenderMetrics, EveryFamilyHasHelpAndTypeOnce) {
  const std::string text = render(full_snapshot());
  std::map<std::string, int> help, type;
  for (const auto& line : lines_of(text)) {
    if (line.rfind("# HELP ", 0) == 0) ++help[line.substr(7, line.find(' ', 7) - 7)];
    if (line.rfind("# TYPE ", 0) == 0) ++type[line.substr(7, line.find(' ', 7) - 7)];
  }
  for (const char* name :
       {"canopen_gateway_can_frames_total", "canopen_gateway_can_frames_dropped_total",
        "canopen_gateway_can_error_frames_total", "canopen_gateway_bus_state", "canopen_gateway_sdo_requests_total",
        "canopen_gateway_sdo_aborts_total", "canopen_gateway_sdo_timeouts_total", "canopen_gateway_nmt_commands_total",
        "canopen_gateway_events_published_total", "canopen_gateway_mqtt_connected",
        "canopen_gateway_mqtt_messages_total", "canopen_gateway_mqtt_queue_depth", "canopen_gateway_mqtt_queue_bytes",
        "canopen_gateway_mqtt_reconnects_total", "canopen_gateway_websocket_clients",
        "canopen_gateway_websocket_messages_total", "canopen_gateway_http_responses_total",
        "canopen_gateway_uptime_seconds"}) {
    EXPECT_EQ(help[name], 1) << name;
    EXPECT_EQ(type[name], 1) << name;
  }
  for (const auto& [name, n] : help) EXPECT_EQ(n, 1) << name;
  for (const auto& [name, n] : type) EXPECT_EQ(n, 1) << name;
  EXPECT_EQ(help.size(), type.size());
}

TEST(RenderMetrics, NoDuplicateSeriesAndOneBusStatePerNetwork) {
  const std::string text = render(full_snapshot());
  std::set<std::string> series;
  int bus_ones = 0, bus_lines = 0;
  for (const auto& line : lines_of(text)) {
    if (line.empty() || line[0] == '#') continue;
    const auto space = line.rfind(' ');
    EXPECT_TRUE(series.insert(line.substr(0, space)).second) << line;
    if (line.rfind("canopen_gateway_bus_state{", 0) == 0) {
      ++bus_lines;
      if (line.substr(space + 1) == "1") ++bus_ones;
    }
  }
  EXPECT_EQ(bus_lines, 10);  // 2 networks x 5 states
  EXPECT_EQ(bus_ones, 2);
}

TEST(RenderMetrics, HttpConnectionFamiliesWhenGiven) {
  Values s;
  EXPECT_EQ(render(s).find("canopen_gateway_http_connections"), std::string::npos);
  HttpConnectionMetrics h;
  h.open = 40;
  h.idle = 7;
  h.refused_per_address = 12;
  h.refused_full = 3;
  h.evicted_idle = 5;
  h.header_timeouts = 2;
  h.refused_framing = 1;
  h.refused_host = 4;
  h.refused_origin = 6;
  h.refused_media_type = 8;
  s.http_connections = h;
  const std::string text = render(s);
  check_exposition(text);
  for (const char* line : {"canopen_gateway_http_connections{state=\"open\"} 40\n",
                           "canopen_gateway_http_connections{state=\"idle\"} 7\n",
                           "canopen_gateway_http_connections_refused_total{reason=\"per-address\"} 12\n",
                           "canopen_gateway_http_connections_refused_total{reason=\"full\"} 3\n",
                           "canopen_gateway_http_connections_evicted_total 5\n",
                           "canopen_gateway_http_header_timeouts_total 2\n",
                           "canopen_gateway_http_requests_refused_total{reason=\"framing\"} 1\n",
                           "canopen_gateway_http_requests_refused_total{reason=\"host\"} 4\n",
                           "canopen_gateway_http_requests_refused_total{reason=\"origin\"} 6\n",
                           "canopen_gateway_http_requests_refused_total{reason=\"media-type\"} 8\n",
                           "# TYPE canopen_gateway_http_connections gauge\n",
                           "# TYPE canopen_gateway_http_connections_refused_total counter\n"})
    EXPECT_NE(text.find(line), std::string::npos) << line;
}

TEST(RenderMetrics, UnknownBusStateGivesAllZero) {
  Values s;
  s.networks.push_back(NetworkMetrics{.network = 3, .interface = "can9", .bus_state = "weird"});
  const std::string text = render(s);
  EXPECT_EQ(text.find("canopen_gateway_bus_state{network=\"3\",interface=\"can9\",state=\"weird\""),
            std::string::npos);
  EXPECT_EQ(text.find("state=\"down\"} 0\n") != std::string::npos, true);
  EXPECT_EQ(text.find("\"} 1\n"), std::string::npos);
}

// The SDO latency histogram: cumulative buckets with the bounds as %g, +Inf,
// _sum and _count, between the NMT counter and the refusals.
TEST(RenderMetrics, SdoLatencyHistogram) {
  Values s;
  s.sdo_latency_bounds = {0.0005, 0.001, 2.5};
  s.sdo_latency_counts = {1, 0, 3, 2};
  s.sdo_latency_sum = 7.25;
  s.request_auth_failures = 0;
  const std::string text = render(s);
  const std::string expected =
      "# HELP canopen_gateway_sdo_latency_seconds SDO transfers from submission to result, queueing included.\n"
      "# TYPE canopen_gateway_sdo_latency_seconds histogram\n"
      "canopen_gateway_sdo_latency_seconds_bucket{le=\"0.0005\"} 1\n"
      "canopen_gateway_sdo_latency_seconds_bucket{le=\"0.001\"} 1\n"
      "canopen_gateway_sdo_latency_seconds_bucket{le=\"2.5\"} 4\n"
      "canopen_gateway_sdo_latency_seconds_bucket{le=\"+Inf\"} 6\n"
      "canopen_gateway_sdo_latency_seconds_sum 7.25\n"
      "canopen_gateway_sdo_latency_seconds_count 6\n";
  const auto at = text.find(expected);
  ASSERT_NE(at, std::string::npos) << text;
  EXPECT_LT(text.find("canopen_gateway_nmt_commands_total 0"), at);
  EXPECT_GT(text.find("# HELP canopen_gateway_request_auth_failures_total"), at);
  s.sdo_latency_counts.pop_back();  // one count per bound plus one, or a programming error
  EXPECT_THROW(render(s), std::invalid_argument);
}

TEST(Metrics, ContentType) { EXPECT_EQ(kContentType, "text/plain; version=0.0.4; charset=utf-8"); }

}  // namespace
}  // namespace gateway::metrics
