#include "metrics/registry.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace gateway::metrics {

namespace {

std::string label_key(const Labels& labels) {
  std::string key;
  for (const auto& [k, v] : labels) {
    if (!valid_label_name(k)) throw std::invalid_argument("metrics: bad label name '" + k + "'");
    key += k;
    key += '=';
    key += escape_label_value(v);
    key += '\n';
  }
  return key;
}

}  // namespace

Histogram::Histogram(std::vector<double> bounds) : bounds_(std::move(bounds)) {
  if (bounds_.empty()) throw std::invalid_argument("metrics: histogram without bounds");
  for (std::size_t i = 1; i < bounds_.size(); ++i) {
    if (!(bounds_[i - 1] < bounds_[i])) throw std::invalid_argument("metrics: histogram bounds not ascending");
  }
  values_.counts.assign(bounds_.size() + 1, 0);
}

void Histogram::observe(double v) noexcept {
  // First bound >= v: Prometheus buckets are "less than or equal".
  const auto slot = static_cast<std::size_t>(std::lower_bound(bounds_.begin(), bounds_.end(), v) - bounds_.begin());
  ++values_.counts[slot];
  values_.sum += v;
  ++count_;
}

Registry::Family& Registry::declare(std::string_view name, std::string_view help, MetricType type) {
  if (!valid_metric_name(name)) throw std::invalid_argument("metrics: bad metric name '" + std::string(name) + "'");
  for (auto& f : families_) {
    if (f->name != name) continue;
    if (f->type != type || f->help != help)
      throw std::invalid_argument("metrics: family '" + std::string(name) + "' registered twice differently");
    return *f;
  }
  auto f = std::make_unique<Family>();
  f->name = std::string(name);
  f->help = std::string(help);
  f->type = type;
  families_.push_back(std::move(f));
  return *families_.back();
}

// Labels are checked before the family is declared, so a bad registration
// leaves no empty family behind.
void Registry::add_series(std::string_view name, std::string_view help, MetricType type, Labels labels, Read read) {
  std::string key = label_key(labels);
  Family& f = declare(name, help, type);
  for (const auto& s : f.series) {
    if (s.key == key) throw std::invalid_argument("metrics: series of '" + f.name + "' registered twice");
  }
  f.series.push_back(Series{std::move(labels), std::move(key), std::move(read)});
}

void Registry::family(std::string_view name, std::string_view help, MetricType type) { declare(name, help, type); }

Counter& Registry::counter(std::string_view name, std::string_view help, Labels labels) {
  auto cell = std::make_unique<Counter>();
  const Counter* c = cell.get();
  add_series(name, help, MetricType::Counter, std::move(labels), [c] { return Value(c->value()); });
  counters_.push_back(std::move(cell));
  return *counters_.back();
}

Gauge& Registry::gauge(std::string_view name, std::string_view help, Labels labels) {
  auto cell = std::make_unique<Gauge>();
  const Gauge* g = cell.get();
  add_series(name, help, MetricType::Gauge, std::move(labels), [g] { return Value(g->value()); });
  gauges_.push_back(std::move(cell));
  return *gauges_.back();
}

Histogram& Registry::histogram(std::string_view name, std::string_view help, std::vector<double> bounds) {
  auto cell = std::make_unique<Histogram>(bounds);
  const Histogram* h = cell.get();
  histogram_fn(name, help, std::move(bounds), [h] { return h->values(); });
  histograms_.push_back(std::move(cell));
  return *histograms_.back();
}

void Registry::counter_fn(std::string_view name, std::string_view help, Labels labels, Read read) {
  add_series(name, help, MetricType::Counter, std::move(labels), std::move(read));
}

void Registry::gauge_fn(std::string_view name, std::string_view help, Labels labels, Read read) {
  add_series(name, help, MetricType::Gauge, std::move(labels), std::move(read));
}

void Registry::histogram_fn(std::string_view name, std::string_view help, std::vector<double> bounds,
                            std::function<HistogramValues()> read) {
  (void)Histogram(bounds);  // the same checks as an owned one
  Family& f = declare(name, help, MetricType::Histogram);
  if (f.histogram) throw std::invalid_argument("metrics: histogram '" + f.name + "' registered twice");
  f.bounds = std::move(bounds);
  f.histogram = std::move(read);
}

void Registry::collect(std::string_view name, std::string_view help, MetricType type, Collect collect) {
  declare(name, help, type).collectors.push_back(std::move(collect));
}

std::string Registry::render() const {
  TextWriter w;
  for (const auto& f : families_) {
    if (f->histogram) {
      const HistogramValues v = f->histogram();
      w.histogram(f->name, f->help, f->bounds, v.counts, v.sum);
      continue;
    }
    w.family(f->name, f->help, f->type);
    for (const auto& s : f->series) w.sample(f->name, s.labels, s.read());
    for (const auto& c : f->collectors) c([&](const Labels& labels, Value v) { w.sample(f->name, labels, v); });
  }
  return w.str();
}

}  // namespace gateway::metrics
