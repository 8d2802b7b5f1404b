#include "metrics/registry.hpp"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <string>

namespace gateway::metrics {
namespace {

TEST(MetricsRegistry, OwnedCellsAreRenderedWithTheirCurrentValues) {
  Registry r;
  Counter& rx = r.counter("x_frames_total", "Frames.", {{"direction", "rx"}});
  Counter& tx = r.counter("x_frames_total", "Frames.", {{"direction", "tx"}});
  Gauge& depth = r.gauge("x_depth", "Depth.");
  rx.inc();
  rx.inc(4);
  tx.inc();
  depth.set(7);
  depth.add(-2);
  EXPECT_EQ(r.render(),
            "# HELP x_frames_total Frames.\n# TYPE x_frames_total counter\n"
            "x_frames_total{direction=\"rx\"} 5\nx_frames_total{direction=\"tx\"} 1\n"
            "# HELP x_depth Depth.\n# TYPE x_depth gauge\nx_depth 5\n");
  rx.inc();  // a later scrape sees the update
  EXPECT_NE(r.render().find("x_frames_total{direction=\"rx\"} 6\n"), std::string::npos);
}

TEST(MetricsRegistry, HistogramBucketsAreLessOrEqualAndCumulativeWhenRendered) {
  Registry r;
  Histogram& h = r.histogram("x_latency_seconds", "Latency.", {0.001, 0.01});
  h.observe(0.001);  // on the bound: that bucket (le)
  h.observe(0.005);
  h.observe(5.0);    // above every bound: +Inf only
  EXPECT_EQ(h.count(), 3U);
  EXPECT_EQ(h.values().counts, (std::vector<std::uint64_t>{1, 1, 1}));
  EXPECT_EQ(r.render(),
            "# HELP x_latency_seconds Latency.\n# TYPE x_latency_seconds histogram\n"
            "x_latency_seconds_bucket{le=\"0.001\"} 1\nx_latency_seconds_bucket{le=\"0.01\"} 2\n"
            "x_latency_seconds_bucket{le=\"+Inf\"} 3\nx_latency_seconds_sum 5.0060000000000002\n"
            "x_latency_seconds_count 3\n");
}

TEST(MetricsRegistry, ReadsRunAtScrapeTimeAndCollectorsFollowFixedSeries) {
  Registry r;
  std::uint64_t frames = 1;
  std::map<int, std::uint64_t> by_code{{200, 3}};
  r.counter_fn("x_total", "X.", {}, [&frames] { return Value(frames); });
  r.family("x_responses_total", "Responses.", MetricType::Counter);
  r.counter_fn("x_responses_total", "Responses.", {{"code", "100"}}, [] { return Value(9U); });
  r.collect("x_responses_total", "Responses.", MetricType::Counter, [&by_code](const Registry::Emit& emit) {
    for (const auto& [code, n] : by_code) emit({{"code", std::to_string(code)}}, n);
  });
  frames = 42;
  by_code[404] = 1;
  EXPECT_EQ(r.render(),
            "# HELP x_total X.\n# TYPE x_total counter\nx_total 42\n"
            "# HELP x_responses_total Responses.\n# TYPE x_responses_total counter\n"
            "x_responses_total{code=\"100\"} 9\nx_responses_total{code=\"200\"} 3\nx_responses_total{code=\"404\"} 1\n");
}

TEST(MetricsRegistry, AFamilyWithoutSeriesKeepsItsPlaceWithHelpAndTypeOnly) {
  Registry r;
  r.family("x_a_total", "A.", MetricType::Counter);
  r.counter("x_b_total", "B.");
  r.counter("x_a_total", "A.", {{"k", "v"}});
  EXPECT_EQ(r.render(),
            "# HELP x_a_total A.\n# TYPE x_a_total counter\nx_a_total{k=\"v\"} 0\n"
            "# HELP x_b_total B.\n# TYPE x_b_total counter\nx_b_total 0\n");
  Registry empty_family;
  empty_family.family("x_c_total", "C.", MetricType::Counter);
  EXPECT_EQ(empty_family.render(), "# HELP x_c_total C.\n# TYPE x_c_total counter\n");
}

TEST(MetricsRegistry, MisregistrationThrowsAndLeavesWhatWasRegistered) {
  Registry r;
  r.counter("x_total", "X.", {{"k", "a"}});
  const std::string before = r.render();
  EXPECT_THROW(r.counter("x_total", "X.", {{"k", "a"}}), std::invalid_argument);        // same series twice
  EXPECT_THROW(r.gauge("x_total", "X.", {{"k", "b"}}), std::invalid_argument);          // another type
  EXPECT_THROW(r.counter("x_total", "Other help.", {{"k", "b"}}), std::invalid_argument);  // another help
  EXPECT_THROW(r.counter("9bad", "X."), std::invalid_argument);
  EXPECT_THROW(r.counter("x_other_total", "X.", {{"__reserved", "v"}}), std::invalid_argument);
  EXPECT_THROW(r.histogram("x_h", "H.", {}), std::invalid_argument);
  EXPECT_THROW(r.histogram("x_h2", "H.", {0.5, 0.5}), std::invalid_argument);
  r.histogram("x_h3", "H.", {1.0});
  EXPECT_THROW(r.histogram("x_h3", "H.", {1.0}), std::invalid_argument);
  EXPECT_EQ(r.render().substr(0, before.size()), before);
}

TEST(MetricsRegistry, LabelValuesAreEscaped) {
  Registry r;
  r.counter("x_total", "X.", {{"interface", "a\"b\\c\nd"}}).inc(2);
  EXPECT_NE(r.render().find("x_total{interface=\"a\\\"b\\\\c\\nd\"} 2\n"), std::string::npos);
}

}  // namespace
}  // namespace gateway::metrics
