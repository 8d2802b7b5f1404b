// A bounded in-memory history of the numeric values nodes send in their
// TPDOs (issue 18: the dashboard's charts, GET .../nodes/{node}/history).
//
// Per object (network, node, index, sub) three rings of fixed-width
// buckets, each allocated once when the object is first seen (no
// allocation per sample):
//
//   tier 0:  1-s buckets x  600  (the last 10 minutes)
//   tier 1: 10-s buckets x  360  (the last hour)
//   tier 2: 60-s buckets x 1440  (the last 24 hours)
//
// A sample goes into the bucket of its time in every tier (min, max,
// running mean, count). A break (the node left Operational or was lost)
// marks a gap: the bucket of the break when no sample of the object is in
// it yet, else the next one. The gap keeps its bucket: samples that fall
// into it (a node started again within the same bucket) are left out of
// that tier, so a stop always shows, at the cost of at most one bucket
// width of samples after it (1 s in the 1-s tier).
//
// Precision: min, max and mean are stored as float (24-bit mantissa):
// integers up to 2^24 (16777216) are exact, larger ones (32/64-bit
// counters) keep about 7 significant digits. That is what a trend chart
// draws; the exact current value is in the events and over SDO. The mean
// is computed in double and stored as float.
//
// Time is the caller's: unix time (system_clock) of each sample, as the
// stack's events carry it (the frame's receive time); the store reads no
// clock. A wall-clock step backwards within a tier's span lands in older
// buckets; a larger one starts that tier afresh.
//
// Memory: bytes_per_object() exactly for what an object holds (its struct,
// its buckets, its name, the index entry); an object that would take the
// total over max_bytes is not recorded and counted (refused_objects()).
// Objects without a sample for 24 h are freed (checked at most once a
// minute of sample time, and by expire()).
//
// Thread safety: none; one store per process, used on the io thread.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "canopen/events.hpp"
#include "canopen/types.hpp"

namespace gateway::history {

using WallClock = std::chrono::system_clock;
using WallTime = WallClock::time_point;

struct Tier {
  std::int64_t width;   // seconds per bucket
  std::size_t buckets;  // ring size
};
inline constexpr std::array<Tier, 3> kTiers = {Tier{1, 600}, Tier{10, 360}, Tier{60, 1440}};
inline constexpr std::int64_t kMinWindow = 60;
inline constexpr std::int64_t kMaxWindow = 86400;
inline constexpr std::int64_t kDefaultWindow = 600;
// Objects whose newest sample is older than this are freed.
inline constexpr std::chrono::seconds kKeep{86400};
// Default history.max-bytes: 64 MiB, about 1700 objects for 24 h
// (docs/reference/rest.md has the arithmetic).
inline constexpr std::uint64_t kDefaultMaxBytes = std::uint64_t{64} << 20;

// The tier a window (seconds) is served from: <= 600 s the 1-s tier,
// <= 3600 s the 10-s tier, else the 60-s tier.
std::size_t tier_for_window(std::int64_t window_seconds);

// The number a sample is recorded as; nullopt for what is not recorded
// (strings, octet strings, domains, TIME_OF_DAY/TIME_DIFFERENCE).
// BOOLEAN is 0 or 1.
std::optional<double> numeric(const canopen::Value& v);

struct ObjectId {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  friend bool operator==(const ObjectId&, const ObjectId&) = default;
};

// One entry of a queried series: a bucket with samples, or a gap (null).
struct Point {
  std::int64_t t = 0;  // unix seconds, start of the bucket
  bool gap = false;    // true: a break; min/max/mean are meaningless
  float mean = 0, min = 0, max = 0;
};

struct Series {
  ObjectId object;
  std::string name;  // the mapped entry's name when first recorded
  canopen::DataType type = canopen::DataType::Domain;
  std::vector<Point> points;  // ascending t
};

struct QueryResult {
  std::int64_t resolution = 1;  // seconds per bucket of the tier used
  std::vector<Series> series;   // ascending (index, sub)
};

class ValueHistory {
 public:
  // max_bytes 0: nothing is ever recorded (history off).
  explicit ValueHistory(std::uint64_t max_bytes = kDefaultMaxBytes) : max_bytes_(max_bytes) {}

  // What one object holds in bytes, name excluded (a name longer than the
  // library's short-string buffer adds its capacity).
  static std::size_t bytes_per_object();

  // One sample of `node`'s object on network `net` at `when`. A value that
  // is not numeric() is ignored. A new object that does not fit under
  // max_bytes is not recorded (refused_objects()).
  void record(std::uint32_t net, std::uint8_t node, std::uint16_t index, std::uint8_t sub, std::string_view name,
              const canopen::Value& value, WallTime when);
  // The node left Operational or was lost at `when`: a gap in each of its
  // objects (once until the next sample).
  void mark_break(std::uint32_t net, std::uint8_t node, WallTime when);
  // A stack event of network `net`: a PdoEvent of a node (not unclaimed,
  // no error) records its numeric mapped values at the event's time; a
  // NodeStateEvent to anything but Operational, or Lost, is a break.
  // Everything else is ignored. Cheap enough for every event.
  void on_event(std::uint32_t net, const canopen::Event& ev);
  // Frees the node's objects (its configuration was replaced or removed).
  void forget_node(std::uint32_t net, std::uint8_t node);
  // Frees objects whose newest sample is older than `now` - kKeep.
  void expire(WallTime now);

  // The node's series over [now - window, now] from tier_for_window(window):
  // `objects` empty = every object of the node with history; an object
  // without history is absent. Only buckets with samples and gaps appear.
  QueryResult query(std::uint32_t net, std::uint8_t node, std::span<const ObjectId> objects,
                    std::int64_t window_seconds, WallTime now) const;

  std::uint64_t bytes() const { return bytes_; }
  std::uint64_t max_bytes() const { return max_bytes_; }
  std::size_t objects() const { return objects_.size(); }
  // Objects not recorded now for want of room (retried once room is freed).
  std::size_t refused_objects() const { return refused_.size(); }
  // Times an object was refused since start (a counter for /metrics).
  std::uint64_t refused_total() const { return refused_total_; }

 private:
  struct Bucket {
    float min, max, mean;
    std::uint16_t count;  // saturates; the mean then weighs the newest samples a little more
    std::uint16_t gap;    // 1: a break; shown when count is 0
  };
  struct Ring {
    std::int64_t newest = -1;  // bucket number (unix seconds / width) in slot newest % size; -1: empty
  };
  struct Object {
    std::string name;
    canopen::DataType type;
    std::int64_t last_sample;  // unix seconds
    bool broken = false;       // a break was marked after the newest sample
    std::array<Ring, kTiers.size()> rings;
    std::unique_ptr<Bucket[]> buckets;  // the tiers one after another
  };
  static std::uint64_t key(std::uint32_t net, std::uint8_t node, std::uint16_t index, std::uint8_t sub) {
    return static_cast<std::uint64_t>(net) << 32 | static_cast<std::uint64_t>(node) << 24 |
           static_cast<std::uint64_t>(index) << 8 | sub;
  }
  static std::size_t object_bytes(const Object& o);
  static Bucket* tier_buckets(Object& o, std::size_t tier);
  static const Bucket* tier_buckets(const Object& o, std::size_t tier);
  // Moves the ring's newest bucket forward to `b`, emptying the slots it
  // passes; returns the slot of bucket `b`, or nullptr when `b` fell out of
  // the ring's past.
  static Bucket* slot(Object& o, std::size_t tier, std::int64_t b);
  void free_where(auto&& pred);

  std::uint64_t max_bytes_;
  std::uint64_t bytes_ = 0;
  std::unordered_map<std::uint64_t, Object> objects_;
  std::unordered_set<std::uint64_t> refused_;
  std::uint64_t refused_total_ = 0;
  std::int64_t next_expiry_ = 0;  // unix seconds
};

}  // namespace gateway::history
