// The PDO value history (gateway/history/value_history.hpp; issue 18, the
// route's shape in docs/reference/rest.md "GET .../history"): samples land
// in the bucket of their time in each tier (1 s, 10 s, 60 s) with min, max
// and mean; a node leaving Operational or lost (CiA 301 7.2.8.2.1 NMT
// states, 7.2.8.2.2 error control) leaves a null entry and later samples
// follow it; the window picks the tier; and under load the store never
// holds more than max-bytes, refuses and counts what does not fit, and
// frees objects 24 h after their last sample. Time is fed, never read.
#include <gtest/gtest.h>

#include <algorithm>

#include "history/value_history.hpp"

namespace gateway::history {
namespace {

using namespace std::chrono_literals;
using canopen::DataType;
using canopen::Value;

// A time on a 60-s boundary (so on every tier's boundary too).
const WallTime kT0 = WallTime(std::chrono::seconds(1764000000));

Value i16(std::int64_t v) { return Value::of_signed(DataType::Integer16, v); }

std::vector<Point> points(const ValueHistory& h, std::int64_t window, WallTime now, std::uint8_t node = 10,
                          ObjectId id = {0x6401, 1}) {
  const auto r = h.query(1, node, std::span(&id, 1), window, now);
  return r.series.empty() ? std::vector<Point>{} : r.series[0].points;
}

std::int64_t secs(WallTime t) { return std::chrono::duration_cast<std::chrono::seconds>(t.time_since_epoch()).count(); }

TEST(ValueHistory, SamplesLandInTheBucketOfTheirTimeWithMinMaxMeanInEachTier) {
  ValueHistory h;
  const auto rec = [&](WallTime t, std::int64_t v) { h.record(1, 10, 0x6401, 1, "Analogue input 1", i16(v), t); };
  rec(kT0, 1);
  rec(kT0 + 999ms, 2);   // still the first second
  rec(kT0 + 1s, 6);      // the next 1-s bucket, same 10-s and 60-s bucket
  rec(kT0 + 9999ms, 3);  // last moment of the first 10-s bucket
  rec(kT0 + 10s, 100);   // next 10-s bucket
  rec(kT0 + 59s, -4);    // last second of the first minute
  rec(kT0 + 60s, 50);    // next minute
  const WallTime now = kT0 + 61s;

  const auto t0 = points(h, 600, now);
  ASSERT_EQ(t0.size(), 6U);
  const std::int64_t base = secs(kT0);
  EXPECT_EQ(t0[0].t, base);
  EXPECT_FLOAT_EQ(t0[0].min, 1);
  EXPECT_FLOAT_EQ(t0[0].max, 2);
  EXPECT_FLOAT_EQ(t0[0].mean, 1.5F);
  EXPECT_EQ(t0[1].t, base + 1);
  EXPECT_FLOAT_EQ(t0[1].mean, 6);
  EXPECT_EQ(t0[2].t, base + 9);
  EXPECT_EQ(t0[3].t, base + 10);
  EXPECT_EQ(t0[4].t, base + 59);
  EXPECT_EQ(t0[5].t, base + 60);

  const auto t1 = points(h, 3600, now);
  ASSERT_EQ(t1.size(), 4U);  // 0-9, 10-19, 50-59, 60-69
  EXPECT_EQ(t1[0].t, base);
  EXPECT_FLOAT_EQ(t1[0].min, 1);
  EXPECT_FLOAT_EQ(t1[0].max, 6);
  EXPECT_FLOAT_EQ(t1[0].mean, 3);  // (1 + 2 + 6 + 3) / 4
  EXPECT_EQ(t1[1].t, base + 10);
  EXPECT_EQ(t1[2].t, base + 50);
  EXPECT_EQ(t1[3].t, base + 60);

  const auto t2 = points(h, 86400, now);
  ASSERT_EQ(t2.size(), 2U);
  EXPECT_EQ(t2[0].t, base);
  EXPECT_FLOAT_EQ(t2[0].min, -4);
  EXPECT_FLOAT_EQ(t2[0].max, 100);
  EXPECT_FLOAT_EQ(t2[0].mean, 108.0F / 6);
  EXPECT_EQ(t2[1].t, base + 60);
  EXPECT_FLOAT_EQ(t2[1].mean, 50);
  for (const auto& p : t2) EXPECT_FALSE(p.gap);
}

TEST(ValueHistory, TheWindowPicksTheTierAndLimitsTheBuckets) {
  EXPECT_EQ(tier_for_window(60), 0U);
  EXPECT_EQ(tier_for_window(600), 0U);
  EXPECT_EQ(tier_for_window(601), 1U);
  EXPECT_EQ(tier_for_window(3600), 1U);
  EXPECT_EQ(tier_for_window(3601), 2U);
  EXPECT_EQ(tier_for_window(86400), 2U);

  ValueHistory h;
  // One sample a second for 20 minutes: the 1-s ring keeps the last 600.
  for (int s = 0; s < 1200; ++s) h.record(1, 10, 0x6401, 1, "in", i16(s), kT0 + std::chrono::seconds(s));
  const WallTime now = kT0 + 1199s;
  const ObjectId id{0x6401, 1};
  auto r = h.query(1, 10, std::span(&id, 1), 600, now);
  EXPECT_EQ(r.resolution, 1);
  ASSERT_EQ(r.series.size(), 1U);
  ASSERT_EQ(r.series[0].points.size(), 600U);
  EXPECT_EQ(r.series[0].points.front().t, secs(kT0) + 600);
  EXPECT_EQ(r.series[0].points.back().t, secs(kT0) + 1199);
  EXPECT_FLOAT_EQ(r.series[0].points.back().mean, 1199);
  // A one-minute window: the last 60 seconds only.
  EXPECT_EQ(h.query(1, 10, std::span(&id, 1), 60, now).series[0].points.size(), 60U);
  r = h.query(1, 10, std::span(&id, 1), 3600, now);
  EXPECT_EQ(r.resolution, 10);
  EXPECT_EQ(r.series[0].points.size(), 120U);
  r = h.query(1, 10, std::span(&id, 1), 7200, now);
  EXPECT_EQ(r.resolution, 60);
  EXPECT_EQ(r.series[0].points.size(), 20U);
}

TEST(ValueHistory, AStopOrALostNodeLeavesANullEntryAndLaterSamplesFollowIt) {
  ValueHistory h;
  auto pdo = [&](WallTime t, std::uint8_t node, std::int64_t v) {
    canopen::PdoEvent p;
    p.node = node;
    p.number = 2;
    p.values.push_back({0x6401, 1, "Analogue input 1", i16(v)});
    h.on_event(1, canopen::Event{0, t, p});
  };
  auto state = [&](WallTime t, std::uint8_t node, std::optional<canopen::NmtState> s) {
    canopen::NodeStateEvent e;
    e.node = node;
    e.state = s;
    e.cause = s ? canopen::NodeStateEvent::Cause::Heartbeat : canopen::NodeStateEvent::Cause::Lost;
    h.on_event(1, canopen::Event{0, t, e});
  };
  for (int s = 0; s <= 4; ++s) {
    pdo(kT0 + std::chrono::seconds(s), 10, s);
    pdo(kT0 + std::chrono::seconds(s), 11, s);
  }
  state(kT0 + 4500ms, 10, canopen::NmtState::Stopped);  // NMT stop (7.2.8.3.1.2)
  state(kT0 + 4600ms, 10, canopen::NmtState::PreOperational);  // no second null
  auto p = points(h, 600, kT0 + 5s);
  ASSERT_EQ(p.size(), 6U);
  EXPECT_FALSE(p[4].gap);
  EXPECT_TRUE(p[5].gap);
  EXPECT_EQ(p[5].t, secs(kT0) + 5);  // the bucket after the last sample's
  const auto other = points(h, 600, kT0 + 5s, 11);
  EXPECT_TRUE(std::none_of(other.begin(), other.end(), [](const Point& x) { return x.gap; }))
      << "another node's series has no break";

  state(kT0 + 5200ms, 10, canopen::NmtState::Operational);  // started: no break
  pdo(kT0 + 5500ms, 10, 55);  // in the gap's bucket: the gap keeps it
  pdo(kT0 + 6s, 10, 6);
  pdo(kT0 + 7s, 10, 7);
  p = points(h, 600, kT0 + 8s);
  ASSERT_EQ(p.size(), 8U);
  EXPECT_TRUE(p[5].gap);
  EXPECT_EQ(p[6].t, secs(kT0) + 6);
  EXPECT_FLOAT_EQ(p[6].mean, 6);
  EXPECT_FALSE(p[7].gap);
  // The 10-s and 60-s tiers: the first bucket had samples, so the gap is
  // the next bucket; the samples after the restart are in that one too
  // (the gap keeps it).
  const auto p1 = points(h, 3600, kT0 + 8s);
  ASSERT_EQ(p1.size(), 2U);
  EXPECT_FALSE(p1[0].gap);
  EXPECT_TRUE(p1[1].gap);
  EXPECT_EQ(p1[1].t, secs(kT0) + 10);

  // Lost (heartbeat consumer, 7.2.8.2.2): a break too, in the bucket of
  // its time (no sample there).
  state(kT0 + 9s, 10, std::nullopt);
  p = points(h, 600, kT0 + 20s);
  ASSERT_EQ(p.size(), 9U);
  EXPECT_TRUE(p.back().gap);
  EXPECT_EQ(p.back().t, secs(kT0) + 9);
}

TEST(ValueHistory, NumericValuesOnlyBooleansAsZeroOrOne) {
  EXPECT_EQ(numeric(Value::of_bool(true)), 1.0);
  EXPECT_EQ(numeric(Value::of_bool(false)), 0.0);
  EXPECT_EQ(numeric(Value::of_unsigned(DataType::Unsigned32, 4000000000U)), 4000000000.0);
  EXPECT_EQ(numeric(Value::of_real32(2.5F)), 2.5);
  EXPECT_FALSE(numeric(Value::of_string("abc")).has_value());
  EXPECT_FALSE(numeric(Value::of_bytes(DataType::OctetString, {1, 2})).has_value());
  EXPECT_FALSE(numeric(Value::of_bytes(DataType::Domain, {1})).has_value());

  ValueHistory h;
  canopen::PdoEvent p;
  p.node = 10;
  p.values.push_back({0x6000, 1, "Digital input", Value::of_bool(true)});
  p.values.push_back({0x2000, 0, "Name", Value::of_string("x")});
  h.on_event(1, canopen::Event{0, kT0, p});
  EXPECT_EQ(h.objects(), 1U);
  // Unclaimed COB-IDs (node 0) and frames that did not match the mapping are not recorded.
  p.node = 0;
  h.on_event(1, canopen::Event{0, kT0, p});
  p.node = 11;
  p.error = "length 3 does not match the mapping's 2";
  h.on_event(1, canopen::Event{0, kT0, p});
  EXPECT_EQ(h.objects(), 1U);
  const auto series = h.query(1, 10, {}, 600, kT0);
  ASSERT_EQ(series.series.size(), 1U);
  EXPECT_EQ(series.series[0].type, DataType::Boolean);
  EXPECT_FLOAT_EQ(series.series[0].points.at(0).mean, 1);
}

TEST(ValueHistory, EveryObjectOfANodeAscendingAndAbsentWhenWithoutHistory) {
  ValueHistory h;
  h.record(1, 10, 0x6401, 2, "b", i16(2), kT0);
  h.record(1, 10, 0x6000, 1, "a", i16(1), kT0);
  h.record(1, 11, 0x6401, 1, "other node", i16(1), kT0);
  h.record(2, 10, 0x6401, 1, "other network", i16(1), kT0);
  const auto all = h.query(1, 10, {}, 600, kT0);
  ASSERT_EQ(all.series.size(), 2U);
  EXPECT_EQ(all.series[0].object, (ObjectId{0x6000, 1}));
  EXPECT_EQ(all.series[1].object, (ObjectId{0x6401, 2}));
  const ObjectId some[] = {{0x6401, 2}, {0x7000, 1}};
  const auto chosen = h.query(1, 10, some, 600, kT0);
  ASSERT_EQ(chosen.series.size(), 1U);
  EXPECT_EQ(chosen.series[0].name, "b");
}

TEST(ValueHistory, ANodeForgottenFreesItsObjectsOnly) {
  ValueHistory h;
  h.record(1, 10, 0x6401, 1, "a", i16(1), kT0);
  h.record(1, 10, 0x6401, 2, "b", i16(1), kT0);
  h.record(1, 11, 0x6401, 1, "c", i16(1), kT0);
  EXPECT_EQ(h.bytes(), 3 * ValueHistory::bytes_per_object());
  h.forget_node(1, 10);
  EXPECT_EQ(h.objects(), 1U);
  EXPECT_EQ(h.bytes(), ValueHistory::bytes_per_object());
  EXPECT_TRUE(h.query(1, 10, {}, 600, kT0).series.empty());
  EXPECT_EQ(h.query(1, 11, {}, 600, kT0).series.size(), 1U);
}

TEST(ValueHistory, ALongNameCountsItsBytes) {
  ValueHistory h;
  const std::string name(40, 'x');
  h.record(1, 10, 0x6401, 1, name, i16(1), kT0);
  EXPECT_EQ(h.bytes(), ValueHistory::bytes_per_object() + 41);
}

TEST(ValueHistory, HistoryOffRecordsNothing) {
  ValueHistory h(0);
  h.record(1, 10, 0x6401, 1, "a", i16(1), kT0);
  EXPECT_EQ(h.objects(), 0U);
  EXPECT_EQ(h.bytes(), 0U);
  EXPECT_EQ(h.refused_objects(), 0U);
}

// 127 nodes x 4 TPDOs x 8 objects (an 8-byte PDO of UNSIGNED8s: the most a
// classic frame maps) for a simulated 26 h, one sample per object per
// minute (every 60-s bucket filled; the bound does not depend on the rate:
// rings are allocated once per object).
TEST(ValueHistory, BoundsUnderLoadNeverOverMaxBytesRefusesAndCountsFreesStaleObjects) {
  constexpr std::uint64_t kCap = kDefaultMaxBytes;
  constexpr int kNodes = 127, kTpdos = 4, kPerTpdo = 8;
  constexpr std::size_t kAll = kNodes * kTpdos * kPerTpdo;
  const std::size_t fit = kCap / ValueHistory::bytes_per_object();
  ASSERT_LT(fit, kAll) << "the test needs more objects than the cap holds";
  ValueHistory h(kCap);
  auto feed = [&](WallTime t, int nodes) {
    for (int node = 1; node <= nodes; ++node) {
      canopen::PdoEvent p;
      p.node = static_cast<std::uint8_t>(node);
      for (int tpdo = 0; tpdo < kTpdos; ++tpdo) {
        p.number = static_cast<std::uint16_t>(tpdo + 1);
        p.values.clear();
        for (int o = 1; o <= kPerTpdo; ++o)
          p.values.push_back({static_cast<std::uint16_t>(0x6000 + tpdo), static_cast<std::uint8_t>(o), "in",
                              Value::of_unsigned(DataType::Unsigned8, static_cast<std::uint64_t>(node + o))});
        h.on_event(1, canopen::Event{0, t, p});
      }
    }
    ASSERT_LE(h.bytes(), kCap);
    ASSERT_EQ(h.bytes(), h.objects() * ValueHistory::bytes_per_object());
  };
  // The first hour: every node sends; what does not fit is refused, once per object.
  WallTime t = kT0;
  for (int minute = 0; minute < 60; ++minute, t += 60s) feed(t, kNodes);
  EXPECT_EQ(h.objects(), fit);
  EXPECT_EQ(h.refused_objects(), kAll - fit);
  EXPECT_EQ(h.refused_total(), kAll - fit);
  const std::size_t nodes_in = fit / (kTpdos * kPerTpdo);  // fed in node order: the first ones got in
  ASSERT_GT(nodes_in, 40U);
  EXPECT_EQ(h.query(1, 1, {}, 86400, t).series.size(), static_cast<std::size_t>(kTpdos * kPerTpdo));
  EXPECT_TRUE(h.query(1, 127, {}, 86400, t).series.empty());

  // 25 more hours with only nodes 1..40 sending: 24 h after their last
  // sample the other nodes' objects are freed, and the refused ones may
  // try again.
  for (int minute = 0; minute < 25 * 60; ++minute, t += 60s) feed(t, 40);
  EXPECT_EQ(h.objects(), 40U * kTpdos * kPerTpdo);
  EXPECT_EQ(h.refused_objects(), 0U);
  const auto series = h.query(1, 1, {}, 86400, t - 60s);  // at the last sample
  ASSERT_EQ(series.series.size(), static_cast<std::size_t>(kTpdos * kPerTpdo));
  EXPECT_EQ(series.series[0].points.size(), 1440U);  // the 24-h ring, full

  // Everyone again: filled up to the cap once more, the rest refused and counted again.
  feed(t, kNodes);
  EXPECT_EQ(h.objects(), fit);
  EXPECT_EQ(h.refused_total(), 2 * (kAll - fit));
}

}  // namespace
}  // namespace gateway::history
