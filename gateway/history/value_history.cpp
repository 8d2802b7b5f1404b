#include "history/value_history.hpp"

#include <algorithm>
#include <limits>
#include <type_traits>
#include <variant>

namespace gateway::history {

namespace {

constexpr std::size_t kTotalBuckets = [] {
  std::size_t n = 0;
  for (const auto& t : kTiers) n += t.buckets;
  return n;
}();

std::int64_t unix_seconds(WallTime t) {
  return std::chrono::duration_cast<std::chrono::seconds>(t.time_since_epoch()).count();
}

// Floor division: bucket numbers stay right for times before 1970 too.
std::int64_t bucket_of(std::int64_t seconds, std::int64_t width) {
  return seconds >= 0 ? seconds / width : -((-seconds + width - 1) / width);
}

// Heap bytes of a name copied into an object: none while it fits the
// string's own buffer (15 characters in libstdc++), else its characters
// and the terminator.
std::size_t name_heap(std::size_t size) { return size > 15 ? size + 1 : 0; }

}  // namespace

std::size_t tier_for_window(std::int64_t window_seconds) {
  if (window_seconds <= 600) return 0;
  if (window_seconds <= 3600) return 1;
  return 2;
}

std::optional<double> numeric(const canopen::Value& v) {
  return std::visit(
      [](const auto& x) -> std::optional<double> {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, bool>) return x ? 1.0 : 0.0;
        else if constexpr (std::is_arithmetic_v<T>) return static_cast<double>(x);
        else return std::nullopt;
      },
      v.data);
}

std::size_t ValueHistory::bytes_per_object() {
  // The hash map's node (key, object, next pointer) and its bucket-array
  // slot, plus the buckets of all tiers.
  return sizeof(std::pair<const std::uint64_t, Object>) + 2 * sizeof(void*) + kTotalBuckets * sizeof(Bucket);
}

std::size_t ValueHistory::object_bytes(const Object& o) { return bytes_per_object() + name_heap(o.name.size()); }

ValueHistory::Bucket* ValueHistory::tier_buckets(Object& o, std::size_t tier) {
  std::size_t offset = 0;
  for (std::size_t i = 0; i < tier; ++i) offset += kTiers[i].buckets;
  return o.buckets.get() + offset;
}

const ValueHistory::Bucket* ValueHistory::tier_buckets(const Object& o, std::size_t tier) {
  return tier_buckets(const_cast<Object&>(o), tier);
}

ValueHistory::Bucket* ValueHistory::slot(Object& o, std::size_t tier, std::int64_t b) {
  const auto size = static_cast<std::int64_t>(kTiers[tier].buckets);
  Ring& ring = o.rings[tier];
  Bucket* buckets = tier_buckets(o, tier);
  auto at = [&](std::int64_t n) -> Bucket& { return buckets[((n % size) + size) % size]; };
  if (ring.newest < 0 || b - ring.newest >= size || ring.newest - b >= size) {
    // First use, a jump past the whole ring, or the clock stepped back
    // beyond it: the ring starts afresh at `b`.
    std::fill(buckets, buckets + size, Bucket{});
    ring.newest = b;
  } else if (b > ring.newest) {
    for (std::int64_t n = ring.newest + 1; n <= b; ++n) at(n) = Bucket{};
    ring.newest = b;
  }
  return &at(b);
}

void ValueHistory::record(std::uint32_t net, std::uint8_t node, std::uint16_t index, std::uint8_t sub,
                          std::string_view name, const canopen::Value& value, WallTime when) {
  const auto x = numeric(value);
  if (!x || max_bytes_ == 0) return;
  const std::int64_t now = unix_seconds(when);
  if (now >= next_expiry_ || now + 60 < next_expiry_) {  // due, or the clock stepped back
    expire(when);
    next_expiry_ = now + 60;
  }
  const auto k = key(net, node, index, sub);
  auto it = objects_.find(k);
  if (it == objects_.end()) {
    if (refused_.contains(k)) return;
    const std::uint64_t need = bytes_per_object() + name_heap(name.size());
    if (bytes_ + need > max_bytes_) {
      refused_.insert(k);
      ++refused_total_;
      return;
    }
    Object o{std::string(name), value.type, now, false, {}, std::make_unique<Bucket[]>(kTotalBuckets)};
    bytes_ += object_bytes(o);
    it = objects_.emplace(k, std::move(o)).first;
  }
  Object& o = it->second;
  o.last_sample = std::max(o.last_sample, now);
  o.broken = false;
  const auto f = static_cast<float>(*x);
  for (std::size_t tier = 0; tier < kTiers.size(); ++tier) {
    Bucket* bk = slot(o, tier, bucket_of(now, kTiers[tier].width));
    if (bk->gap) continue;  // the break keeps its bucket: a gap must show as one
    if (bk->count == 0) {
      bk->min = bk->max = bk->mean = f;
      bk->count = 1;
      continue;
    }
    bk->min = std::min(bk->min, f);
    bk->max = std::max(bk->max, f);
    if (bk->count < std::numeric_limits<std::uint16_t>::max()) ++bk->count;
    const auto mean = static_cast<double>(bk->mean);
    bk->mean = static_cast<float>(mean + (*x - mean) / bk->count);
  }
}

void ValueHistory::on_event(std::uint32_t net, const canopen::Event& ev) {
  if (max_bytes_ == 0) return;
  if (const auto* p = std::get_if<canopen::PdoEvent>(&ev.body)) {
    if (p->node == 0 || p->error) return;
    for (const auto& v : p->values) record(net, p->node, v.index, v.sub, v.name, v.value, ev.timestamp);
  } else if (const auto* s = std::get_if<canopen::NodeStateEvent>(&ev.body)) {
    if (!s->state || *s->state != canopen::NmtState::Operational) mark_break(net, s->node, ev.timestamp);
  }
}

void ValueHistory::mark_break(std::uint32_t net, std::uint8_t node, WallTime when) {
  const std::int64_t now = unix_seconds(when);
  const auto first = key(net, node, 0, 0);
  const auto last = key(net, node, 0xFFFF, 0xFF);
  for (auto& [k, o] : objects_) {
    if (k < first || k > last || o.broken) continue;
    o.broken = true;
    for (std::size_t tier = 0; tier < kTiers.size(); ++tier) {
      std::int64_t b = bucket_of(now, kTiers[tier].width);
      // Before the newest bucket (the clock stepped back): mark after it.
      b = std::max(b, o.rings[tier].newest);
      Bucket* bk = slot(o, tier, b);
      if (bk->count > 0) bk = slot(o, tier, b + 1);
      bk->gap = 1;
    }
  }
}

void ValueHistory::free_where(auto&& pred) {
  bool freed = false;
  for (auto it = objects_.begin(); it != objects_.end();) {
    if (pred(it->first, it->second)) {
      bytes_ -= object_bytes(it->second);
      it = objects_.erase(it);
      freed = true;
    } else {
      ++it;
    }
  }
  // Room again: refused objects get another chance (and count again if
  // they still do not fit).
  if (freed) refused_.clear();
}

void ValueHistory::forget_node(std::uint32_t net, std::uint8_t node) {
  const auto first = key(net, node, 0, 0);
  const auto last = key(net, node, 0xFFFF, 0xFF);
  free_where([&](std::uint64_t k, const Object&) { return k >= first && k <= last; });
  std::erase_if(refused_, [&](std::uint64_t k) { return k >= first && k <= last; });
}

void ValueHistory::expire(WallTime now) {
  const std::int64_t oldest = unix_seconds(now) - kKeep.count();
  free_where([&](std::uint64_t, const Object& o) { return o.last_sample < oldest; });
}

QueryResult ValueHistory::query(std::uint32_t net, std::uint8_t node, std::span<const ObjectId> objects,
                                std::int64_t window_seconds, WallTime now) const {
  QueryResult out;
  const std::size_t tier = tier_for_window(window_seconds);
  const std::int64_t width = kTiers[tier].width;
  const auto size = static_cast<std::int64_t>(kTiers[tier].buckets);
  out.resolution = width;
  const std::int64_t to = unix_seconds(now);
  // Buckets that overlap the window; one more after `to` for a gap marked
  // just after the newest sample.
  const std::int64_t first_b = bucket_of(to - window_seconds, width) + 1;
  const std::int64_t last_b = bucket_of(to, width) + 1;

  auto add = [&](std::uint16_t index, std::uint8_t sub, const Object& o) {
    Series s;
    s.object = {index, sub};
    s.name = o.name;
    s.type = o.type;
    const Ring& ring = o.rings[tier];
    const Bucket* buckets = tier_buckets(o, tier);
    if (ring.newest >= 0) {
      const std::int64_t lo = std::max(first_b, ring.newest - size + 1);
      const std::int64_t hi = std::min(last_b, ring.newest);
      for (std::int64_t b = lo; b <= hi; ++b) {
        const Bucket& bk = buckets[((b % size) + size) % size];
        if (bk.count > 0) s.points.push_back({b * width, false, bk.mean, bk.min, bk.max});
        else if (bk.gap) s.points.push_back({b * width, true, 0, 0, 0});
      }
    }
    out.series.push_back(std::move(s));
  };

  if (objects.empty()) {
    std::vector<std::uint64_t> keys;
    const auto first = key(net, node, 0, 0);
    const auto last = key(net, node, 0xFFFF, 0xFF);
    for (const auto& [k, o] : objects_)
      if (k >= first && k <= last) keys.push_back(k);
    std::sort(keys.begin(), keys.end());
    for (auto k : keys)
      add(static_cast<std::uint16_t>(k >> 8 & 0xFFFF), static_cast<std::uint8_t>(k & 0xFF), objects_.at(k));
  } else {
    std::vector<ObjectId> wanted(objects.begin(), objects.end());
    std::sort(wanted.begin(), wanted.end(),
              [](const ObjectId& a, const ObjectId& b) { return a.index != b.index ? a.index < b.index : a.sub < b.sub; });
    wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
    for (const auto& id : wanted) {
      auto it = objects_.find(key(net, node, id.index, id.sub));
      if (it != objects_.end()) add(id.index, id.sub, it->second);
    }
  }
  return out;
}

}  // namespace gateway::history
