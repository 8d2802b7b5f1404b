// The trace WebSocket's message, filter and per-client queue (contract,
// "Bus trace and capture").
#include "trace/trace_stream.hpp"

#include <gtest/gtest.h>

#include <boost/json/parse.hpp>

namespace gateway::trace {
namespace {

Traced traced(const char* text, Direction d = Direction::Rx) {
  Traced t{*canopen::can::parse_frame(text), d};
  t.frame.timestamp = WallTime(std::chrono::microseconds(1700000000123456));
  return t;
}

// The contract's shape: t (RFC 3339, µs), id, ext, rtr, fd, dir, data,
// decoded; plus service and node (docs/reference/websocket.md "Bus trace").
TEST(TraceMessage, ContractShape) {
  EXPECT_EQ(frame_json(traced("185#0A0B"), "TPDO1 5", {"tpdo", 5}),
            R"({"t":"2023-11-14T22:13:20.123456Z","id":389,"ext":false,"rtr":false,"fd":false,"dir":"rx","data":"0a0b","decoded":"TPDO1 5","service":"tpdo","node":5})");
  const auto v =
      boost::json::parse(frame_json(traced("12345678#R2", Direction::Tx), "raw \"x\"", {"other", 0}));
  EXPECT_EQ(v.at("id").as_int64(), 0x12345678);
  EXPECT_TRUE(v.at("ext").as_bool());
  EXPECT_TRUE(v.at("rtr").as_bool());
  EXPECT_EQ(v.at("dir").as_string(), "tx");
  EXPECT_EQ(v.at("data").as_string(), "");
  EXPECT_EQ(v.at("decoded").as_string(), "raw \"x\"");
  EXPECT_EQ(v.at("service").as_string(), "other");
  EXPECT_FALSE(v.as_object().contains("node"));  // about no single node: absent, not 0
}

TEST(IdFilter, RangesSelectFrames) {
  IdFilter f;
  EXPECT_TRUE(f.matches(0x123));  // before any filter: everything
  std::string error;
  ASSERT_TRUE(f.parse(R"({"ids": [[384, 511], [1797, 1797]]})", error)) << error;
  EXPECT_TRUE(f.matches(0x185));
  EXPECT_TRUE(f.matches(0x705));
  EXPECT_FALSE(f.matches(0x706));
  EXPECT_FALSE(f.matches(0x000));
  EXPECT_EQ(f.to_json(), R"({"ids":[[384,511],[1797,1797]]})");
  ASSERT_TRUE(f.parse("{}", error));
  EXPECT_TRUE(f.matches(0x706));
}

// A bad filter message is refused with a reason; the filter in force stays.
TEST(IdFilter, BadMessageChangesNothing) {
  IdFilter f;
  std::string error;
  ASSERT_TRUE(f.parse(R"({"ids": [[1, 2]]})", error));
  for (const char* bad : {"not json", "[]", R"({"nodes": [1]})", R"({"ids": 5})", R"({"ids": [[2, 1]]})",
                          R"({"ids": [[1]]})", R"({"ids": [[-1, 5]]})", R"({"ids": [[0, 536870912]]})",
                          R"({"ids": [["1", 2]]})"}) {
    error.clear();
    EXPECT_FALSE(f.parse(bad, error)) << bad;
    EXPECT_FALSE(error.empty()) << bad;
    EXPECT_EQ(f.to_json(), R"({"ids":[[1,2]]})") << bad;
  }
}

// A slow client loses frames, never blocks; it is told how many it lost,
// right where the gap is.
TEST(TraceQueue, SlowClientToldHowManyItLost) {
  TraceQueue q({4, 1u << 20});
  auto msg = [](int i) { return std::make_shared<const std::string>("frame " + std::to_string(i)); };
  for (int i = 0; i < 10; ++i) q.push_frame(msg(i));  // 4 fit, 6 lost
  EXPECT_EQ(q.lost(), 6u);
  EXPECT_EQ(*q.pop(), "frame 0");
  EXPECT_EQ(*q.pop(), "frame 1");
  q.push_frame(msg(10));  // room for the lost message and frame 10
  EXPECT_EQ(*q.pop(), "frame 2");
  EXPECT_EQ(*q.pop(), "frame 3");
  EXPECT_EQ(*q.pop(), R"({"lost":6})");
  EXPECT_EQ(*q.pop(), "frame 10");
  EXPECT_TRUE(q.empty());
  q.push_frame(msg(11));
  EXPECT_EQ(*q.pop(), "frame 11");  // no second lost message
  EXPECT_EQ(q.take_lost(), nullptr);
}

// Caught up (queue empty) after losing frames: told at once, not only
// when the next frame comes.
TEST(TraceQueue, CaughtUpClientToldWithoutWaitingForAFrame) {
  TraceQueue q({2, 1u << 20});
  for (int i = 0; i < 5; ++i) q.push_frame(std::make_shared<const std::string>("f"));
  q.pop();
  q.pop();
  ASSERT_TRUE(q.empty());
  EXPECT_EQ(*q.take_lost(), R"({"lost":3})");
  EXPECT_EQ(q.take_lost(), nullptr);
  EXPECT_EQ(q.lost(), 3u);
}

TEST(TraceQueue, BoundedByBytesToo) {
  TraceQueue q({1000, 20});
  EXPECT_TRUE(q.push_frame(std::make_shared<const std::string>(std::string(15, 'x'))));
  EXPECT_FALSE(q.push_frame(std::make_shared<const std::string>(std::string(15, 'y'))));
  EXPECT_EQ(q.lost(), 1u);
}

}  // namespace
}  // namespace gateway::trace
