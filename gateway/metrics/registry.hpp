// The gateway's metrics registry: each component registers its counters,
// gauges and histograms once (name, help, labels) and /metrics renders all
// of them in the Prometheus text format (TextWriter, metrics.hpp).
//
// Two ways to hold a value:
//   - owned cells (counter(), gauge(), histogram()): the registry keeps the
//     cell, the component keeps the reference and updates it on its hot
//     path: Counter::inc() is one add on a plain uint64, Histogram::observe()
//     a search over a few bounds and two adds. No atomics, no locks;
//   - reads (counter_fn(), gauge_fn(), histogram_fn(), collect()): for a
//     component that already keeps its own stats (a channel's ChannelStats,
//     the HTTP server's HttpStats), a function the registry calls at scrape
//     time. collect() serves a family whose series come and go (responses by
//     status code).
// Why our own and not prometheus-cpp (Debian's prometheus-cpp-dev 1.0.1),
// measured (bench/registry_bench.cpp, bench/README.md "Metrics registry"):
// its cost per update would be acceptable (Counter::Increment ~5 ns, a
// compare-and-swap on an atomic double; Histogram::Observe ~14 ns, under a
// mutex; ours 0.3 ns and 5 ns, against ~4 us of CPU per PDO frame), but its
// text serializer changes what /metrics users read: counters are doubles
// (18446744073709551615 becomes 1.844674407370955e+19, exact only to 2^53)
// and a histogram's _count and _sum come before its buckets. Keeping our
// TextWriter and using only its cells would buy thread safety the gateway
// does not need (one io_context thread) for 3-18x the cost and a dependency.
//
// Families are written in the order first registered; series within a family
// in the order registered, then what its collectors add.
//
// Registration is a programming error when wrong and throws
// std::invalid_argument (at start-up, not at scrape time): a bad metric or
// label name, a family registered again with another type or help, the same
// series (family + labels) twice, histogram bounds not ascending.
//
// Thread safety: none. Register, update and render on one thread (the
// io_context's); a component MUST outlive the registry's render() calls
// that read it (or not be registered with a read that refers to it).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "metrics/metrics.hpp"

namespace gateway::metrics {

class Counter {
 public:
  void inc(std::uint64_t n = 1) noexcept { value_ += n; }
  std::uint64_t value() const noexcept { return value_; }

 private:
  std::uint64_t value_ = 0;
};

class Gauge {
 public:
  void set(std::int64_t v) noexcept { value_ = v; }
  void add(std::int64_t d) noexcept { value_ += d; }
  std::int64_t value() const noexcept { return value_; }

 private:
  std::int64_t value_ = 0;
};

// What a histogram reports: counts per upper bound (v <= bound), NOT
// cumulative, plus one last count for everything above; and the sum.
struct HistogramValues {
  std::vector<std::uint64_t> counts;
  double sum = 0.0;
};

class Histogram {
 public:
  // bounds: ascending upper bounds (seconds, bytes, ...); throws
  // std::invalid_argument when empty or not strictly ascending.
  explicit Histogram(std::vector<double> bounds);
  void observe(double v) noexcept;
  const std::vector<double>& bounds() const noexcept { return bounds_; }
  const HistogramValues& values() const noexcept { return values_; }
  std::uint64_t count() const noexcept { return count_; }

 private:
  std::vector<double> bounds_;
  HistogramValues values_;
  std::uint64_t count_ = 0;
};

class Registry {
 public:
  using Read = std::function<Value()>;
  // Adds one sample per call; the family's name is implied.
  using Emit = std::function<void(const Labels&, Value)>;
  using Collect = std::function<void(const Emit&)>;

  Registry() = default;
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  // Declares a family without series yet (it is written with HELP and TYPE
  // only until some are added); fixes its place in the output.
  void family(std::string_view name, std::string_view help, MetricType type);

  // Owned cells; the reference stays valid as long as the registry.
  Counter& counter(std::string_view name, std::string_view help, Labels labels = {});
  Gauge& gauge(std::string_view name, std::string_view help, Labels labels = {});
  Histogram& histogram(std::string_view name, std::string_view help, std::vector<double> bounds);

  // Values read at scrape time.
  void counter_fn(std::string_view name, std::string_view help, Labels labels, Read read);
  void gauge_fn(std::string_view name, std::string_view help, Labels labels, Read read);
  void histogram_fn(std::string_view name, std::string_view help, std::vector<double> bounds,
                    std::function<HistogramValues()> read);
  // Series decided at scrape time (after the family's fixed series).
  void collect(std::string_view name, std::string_view help, MetricType type, Collect collect);

  // The exposition text of everything registered (format 0.0.4). Throws
  // std::invalid_argument only for a collector's bad or duplicate series.
  std::string render() const;

 private:
  struct Series {
    Labels labels;
    std::string key;  // rendered labels, for duplicate checks
    Read read;
  };
  struct Family {
    std::string name, help;
    MetricType type;
    std::vector<Series> series;
    std::vector<Collect> collectors;
    std::vector<double> bounds;                    // histograms only
    std::function<HistogramValues()> histogram;    // histograms only; unset until registered
  };
  Family& declare(std::string_view name, std::string_view help, MetricType type);
  void add_series(std::string_view name, std::string_view help, MetricType type, Labels labels, Read read);

  std::vector<std::unique_ptr<Family>> families_;
  std::vector<std::unique_ptr<Counter>> counters_;
  std::vector<std::unique_ptr<Gauge>> gauges_;
  std::vector<std::unique_ptr<Histogram>> histograms_;
};

}  // namespace gateway::metrics
