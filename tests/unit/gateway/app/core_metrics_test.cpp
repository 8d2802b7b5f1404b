// The request core's metrics as its owner registers them
// (gateway/app/core_metrics.hpp): read from the core's Counters at scrape
// time, the refusal families always there, the SDO latency histogram with
// the core's bounds.
#include "app/core_metrics.hpp"

#include <gtest/gtest.h>

#include <string>

namespace gateway {
namespace {

using core::Counters;

bool has_line(const std::string& text, const std::string& line) { return text.find(line + "\n") != std::string::npos; }

TEST(CoreMetrics, FamiliesFollowTheCountersAfterRegistration) {
  Counters c;
  metrics::Registry r;
  register_core_metrics(r, c);
  const std::string before = r.render();
  EXPECT_TRUE(has_line(before, "canopen_gateway_sdo_requests_total 0"));
  // Counted 0 so far, but /metrics has the refusal families from the start.
  EXPECT_TRUE(has_line(before, "canopen_gateway_request_auth_failures_total 0"));
  EXPECT_TRUE(has_line(before, "canopen_gateway_requests_limited_total{reason=\"sdo-queue-share\"} 0"));
  EXPECT_TRUE(has_line(before, "canopen_gateway_requests_limited_total{reason=\"mqtt-rate-limit\"} 0"));
  EXPECT_TRUE(has_line(before, "canopen_gateway_sdo_latency_seconds_count 0"));

  c.sdo_requests = 3;
  c.sdo_aborts = 1;
  c.sdo_timeouts = 2;
  c.nmt_commands = 4;
  c.auth_failures = 5;
  c.sdo_share_refused = 6;
  c.requests_rate_limited = 7;
  c.sdo_latency_counts.front() = 2;  // <= 0.5 ms
  c.sdo_latency_counts.back() = 1;   // > 2.5 s
  c.sdo_latency_sum = 3.25;
  const std::string text = r.render();
  for (const char* line : {"canopen_gateway_sdo_requests_total 3", "canopen_gateway_sdo_aborts_total 1",
                           "canopen_gateway_sdo_timeouts_total 2", "canopen_gateway_nmt_commands_total 4",
                           "canopen_gateway_request_auth_failures_total 5",
                           "canopen_gateway_requests_limited_total{reason=\"sdo-queue-share\"} 6",
                           "canopen_gateway_requests_limited_total{reason=\"mqtt-rate-limit\"} 7",
                           "canopen_gateway_sdo_latency_seconds_bucket{le=\"0.0005\"} 2",
                           "canopen_gateway_sdo_latency_seconds_bucket{le=\"2.5\"} 2",
                           "canopen_gateway_sdo_latency_seconds_bucket{le=\"+Inf\"} 3",
                           "canopen_gateway_sdo_latency_seconds_sum 3.25",
                           "canopen_gateway_sdo_latency_seconds_count 3"})
    EXPECT_TRUE(has_line(text, line)) << line << "\n" << text;
  // One bucket per bound of the core, plus +Inf.
  std::size_t buckets = 0;
  for (auto at = text.find("_bucket{"); at != std::string::npos; at = text.find("_bucket{", at + 1)) ++buckets;
  EXPECT_EQ(buckets, Counters::kSdoLatencyBounds.size() + 1);
}

// Contract "Remote configuration and maintenance": program downloads and
// DCF transfers counted by operation and result, every series from the start.
TEST(CoreMetrics, MaintenanceOperationsByOperationAndResult) {
  Counters c;
  metrics::Registry r;
  register_core_metrics(r, c);
  EXPECT_TRUE(has_line(r.render(),
                       "canopen_gateway_maintenance_operations_total{operation=\"program-download\",result=\"failed\"} 0"));
  c.maintenance[Counters::program_download][Counters::ok] = 2;
  c.maintenance[Counters::dcf_read][Counters::busy] = 1;
  const std::string text = r.render();
  EXPECT_TRUE(has_line(text,
                       "canopen_gateway_maintenance_operations_total{operation=\"program-download\",result=\"ok\"} 2"))
      << text;
  EXPECT_TRUE(
      has_line(text, "canopen_gateway_maintenance_operations_total{operation=\"dcf-read\",result=\"busy\"} 1"));
}

}  // namespace
}  // namespace gateway
