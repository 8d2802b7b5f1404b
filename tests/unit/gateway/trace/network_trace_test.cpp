// The frame tap of a network: ring, load and subscribers fed from the
// frames received and sent, decoded once for every client.
#include "trace/network_trace.hpp"

#include <gtest/gtest.h>

#include <boost/json/parse.hpp>

namespace gateway::trace {
namespace {

using namespace std::chrono_literals;
using canopen::can::Frame;

const auto kSteady = std::chrono::steady_clock::time_point(100s);
const WallTime kWall = WallTime(1700000000s);

Frame frame(const char* text) { return *canopen::can::parse_frame(text); }

TEST(NetworkTrace, RxAndTxReachRingClientsAndLoadWithTheirDirection) {
  NetworkTrace trace({"vcan0", 127, 125000, {60s, 1u << 20}}, kSteady);
  std::vector<std::string> a, b;
  IdFilter only_sdo;
  std::string error;
  ASSERT_TRUE(only_sdo.parse(R"({"ids": [[1408, 1663]]})", error));  // 580h..67Fh
  trace.add_client({[](std::uint32_t) { return true; }, [&](const Message& m) { a.push_back(*m); }});
  const auto id_b = trace.add_client(
      {[&](std::uint32_t id) { return only_sdo.matches(id); }, [&](const Message& m) { b.push_back(*m); }});

  Frame rx[] = {frame("705#05"), frame("585#4318100178563412")};
  rx[0].timestamp = kWall + 1ms;  // kernel time kept
  trace.sent(frame("605#4018100100000000"), kSteady, kWall);
  trace.received(rx, kSteady + 1ms, kWall + 5ms);

  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 2u);
  auto v = boost::json::parse(a[0]);
  EXPECT_EQ(v.at("dir").as_string(), "tx");
  EXPECT_EQ(v.at("decoded").as_string(), "SDO tx 5 upload 1018h:01");
  v = boost::json::parse(a[1]);
  EXPECT_EQ(v.at("decoded").as_string(), "HB 5 operational");
  EXPECT_EQ(v.at("service").as_string(), "error-control");
  EXPECT_EQ(v.at("node").as_int64(), 5);
  EXPECT_EQ(v.at("t").as_string(), "2023-11-14T22:13:20.001000Z");
  v = boost::json::parse(a[2]);
  EXPECT_EQ(v.at("dir").as_string(), "rx");
  EXPECT_EQ(v.at("t").as_string(), "2023-11-14T22:13:20.005000Z");  // no kernel time: when received
  EXPECT_EQ(b[1], a[2]);  // one message for both clients

  const auto ring = trace.ring().since(WallTime{});
  ASSERT_EQ(ring.size(), 3u);
  EXPECT_EQ(ring[0].dir, Direction::Tx);
  EXPECT_EQ(ring[1].dir, Direction::Rx);
  EXPECT_GT(*trace.load().percent(1s, kSteady + 500ms), 0.0);

  trace.remove(id_b);
  trace.sent(frame("605#4018100100000000"), kSteady, kWall);
  EXPECT_EQ(b.size(), 2u);
  EXPECT_EQ(a.size(), 4u);
}

TEST(NetworkTrace, RecorderGetsEveryFrame) {
  NetworkTrace trace({"vcan0", 127, 0, {60s, 1u << 20}}, kSteady);
  std::vector<Traced> got;
  trace.add_recorder([&](const Traced& t) { got.push_back(t); });
  trace.sent(frame("000#0100"), kSteady, kWall);
  Frame rx[] = {frame("705#00")};
  trace.received(rx, kSteady, kWall);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].dir, Direction::Tx);
  EXPECT_EQ(got[1].frame, frame("705#00"));
  EXPECT_FALSE(trace.load().percent(1s, kSteady));  // bit rate unknown
}

}  // namespace
}  // namespace gateway::trace
