// The bus trace and capture routes on the demo gateway (contract "Bus
// trace and capture"): the trace WebSocket (decoded frames, id filters, a
// slow client told what it lost while a fast one gets everything), the
// capture as candump -L lines and as pcapng (read back by
// tests/tools/pcapng_read.py), bus load in GET /api/v1/networks/{net}.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <atomic>
#include <fstream>
#include <regex>
#include <sstream>

#include "rest_rig.hpp"
#include "trace_routes.hpp"
#include "trace/network_trace.hpp"

namespace gateway::test {
namespace {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
using boost::asio::ip::tcp;
using ::testing::HasSubstr;
using ::testing::Not;

// A blocking WebSocket client on its own thread's calls (the test thread
// runs the gateway's io_context meanwhile).
struct TraceClient {
  TraceClient(std::uint16_t port, const std::string& target, int rcvbuf = 0) : ws(ioc) {
    auto& sock = ws.next_layer();
    sock.open(tcp::v4());
    if (rcvbuf > 0) sock.set_option(boost::asio::socket_base::receive_buffer_size(rcvbuf));
    sock.connect({boost::asio::ip::make_address("127.0.0.1"), port});
    ws.handshake("127.0.0.1:" + std::to_string(port), target);
  }
  std::string read() {
    beast::flat_buffer b;
    ws.read(b);
    return beast::buffers_to_string(b.data());
  }
  void send(const std::string& text) { ws.write(boost::asio::buffer(text)); }
  boost::asio::io_context ioc;
  websocket::stream<tcp::socket> ws;
};

// Runs `f` on a thread while the rig's io_context runs; its result.
template <typename F>
auto beside(RestRig& rig, F f, std::chrono::milliseconds limit = 20s) {
  auto fut = std::async(std::launch::async, std::move(f));
  EXPECT_TRUE(rig.run_until([&] { return fut.wait_for(0s) == std::future_status::ready; }, limit));
  return fut.get();
}

TEST(TraceRoute, DecodedFramesOfTheBusFiltered) {
  RestRig rig;
  auto client = beside(rig, [&] { return std::make_unique<TraceClient>(rig.port, "/api/v1/networks/1/trace"); });
  // Heartbeats and boot-ups only (700h..77Fh).
  const auto subscribed = beside(rig, [&] {
    client->send(R"({"ids": [[1792, 1919]]})");
    for (;;) {
      auto m = client->read();
      if (m.find("subscribed") != std::string::npos) return m;
    }
  });
  EXPECT_EQ(subscribed, R"({"subscribed":{"ids":[[1792,1919]]}})");
  const auto frames = beside(rig, [&] {
    std::vector<json::value> out;
    while (out.size() < 4) out.push_back(json::parse(client->read()));
    return out;
  });
  for (const auto& f : frames) {
    const auto id = f.at("id").to_number<std::int64_t>();
    EXPECT_GE(id, 0x700);
    EXPECT_LE(id, 0x77F);
    EXPECT_FALSE(f.at("ext").as_bool());
    EXPECT_TRUE(std::regex_match(std::string(f.at("t").as_string()),
                                 std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{6}Z)")))
        << f.at("t");
    const std::string decoded(f.at("decoded").as_string());
    EXPECT_TRUE(decoded.starts_with("HB ") || decoded.starts_with("boot-up ")) << decoded;
    // The gateway's own heartbeat (77Fh) is sent; the devices' received.
    EXPECT_EQ(f.at("dir").as_string(), id == 0x77F ? "tx" : "rx");
  }
  // A bad filter: an error, the filter in force stays.
  const auto error = beside(rig, [&] {
    client->send(R"({"ids": [[5, 1]]})");
    for (;;) {
      auto m = client->read();
      if (m.starts_with(R"({"error":)")) return m;  // not a frame's "service":"error-control"
    }
  });
  EXPECT_THAT(error, HasSubstr("from <= to"));
  const auto after = beside(rig, [&] { return json::parse(client->read()); });
  EXPECT_GE(after.at("id").to_number<std::int64_t>(), 0x700);
  beside(rig, [&] { client->ws.close(websocket::close_code::normal); return 0; });
}

// A client that does not read loses frames (its queue is bounded) and is
// told how many when it reads again; the fast client misses nothing, and
// the bus path never waited for either.
TEST(TraceRoute, SlowClientToldHowManyItLostFastOneGetsAll) {
  RestRig rig;
  auto tap = rig.app->frame_tap(1);
  ASSERT_TRUE(tap);
  const std::string filter = R"({"ids": [[291, 291]]})";  // 123h: no demo device uses it
  auto fast = beside(rig, [&] {
    auto c = std::make_unique<TraceClient>(rig.port, "/api/v1/networks/1/trace");
    c->send(filter);
    while (c->read().find("subscribed") == std::string::npos) {}
    return c;
  });
  auto slow = beside(rig, [&] {
    auto c = std::make_unique<TraceClient>(rig.port, "/api/v1/networks/1/trace", 4096);
    c->send(filter);
    while (c->read().find("subscribed") == std::string::npos) {}
    return c;
  });
  constexpr std::uint32_t kTotal = 40000;
  std::atomic<std::uint32_t> fast_got{0};
  std::atomic<bool> fast_in_order{true};
  auto reader = std::async(std::launch::async, [&] {
    while (fast_got < kTotal) {
      const auto v = json::parse(fast->read());
      const auto data = std::string(v.at("data").as_string());
      if (std::stoul(data, nullptr, 16) != fast_got) fast_in_order = false;
      ++fast_got;
    }
  });
  auto frame_no = [](std::uint32_t i) {
    canopen::can::Frame f = canopen::can::Frame::standard(0x123, {});
    f.len = 4;
    for (int b = 0; b < 4; ++b) f.data[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(i >> (24 - 8 * b));
    return f;
  };
  // Bursts like a busy bus, as the channel would hand them to the tap.
  for (std::uint32_t i = 0; i < kTotal; i += 500) {
    for (std::uint32_t k = i; k < i + 500; ++k)
      tap->sent(frame_no(k), std::chrono::steady_clock::now(), std::chrono::system_clock::now());
    ASSERT_TRUE(rig.run_until([&] { return fast_got >= i + 500; }, 10s)) << "fast client stuck at " << fast_got;
  }
  // The slow one now reads what it has, in order, and once caught up is
  // told how many it lost.
  struct SlowView {
    std::uint64_t frames = 0, lost = 0;
    bool in_order = true;
  };
  const auto seen = beside(rig, [&] {
    SlowView s;
    std::int64_t last = -1;
    while (s.frames + s.lost < kTotal) {
      const auto v = json::parse(slow->read());
      if (const auto* l = v.as_object().if_contains("lost")) {
        s.lost += l->to_number<std::uint64_t>();
        continue;
      }
      ++s.frames;
      const auto n = static_cast<std::int64_t>(std::stoul(std::string(v.at("data").as_string()), nullptr, 16));
      if (n <= last) s.in_order = false;
      last = n;
    }
    return s;
  }, 30s);
  ASSERT_TRUE(rig.run_until([&] { return reader.wait_for(0s) == std::future_status::ready; }, 10s));
  EXPECT_EQ(fast_got, kTotal);
  EXPECT_TRUE(fast_in_order);
  EXPECT_GT(seen.lost, 0u);
  EXPECT_EQ(seen.frames + seen.lost, kTotal);
  EXPECT_TRUE(seen.in_order);
  beside(rig, [&] {
    fast->ws.close(websocket::close_code::normal);
    slow->ws.close(websocket::close_code::normal);
    return 0;
  });
}

// Up to kMaxTraceClients per network; the next is told to retry later.
TEST(TraceRoute, ClientsAreCapped) {
  RestRig rig;
  std::vector<std::unique_ptr<TraceClient>> clients;
  for (std::size_t i = 0; i < kMaxTraceClients; ++i)
    clients.push_back(beside(rig, [&] { return std::make_unique<TraceClient>(rig.port, "/api/v1/networks/1/trace"); }));
  const auto r = rig.request("GET", "/api/v1/networks/1/trace", {},
                             {"Upgrade: websocket", "Connection: Upgrade", "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
                              "Sec-WebSocket-Version: 13"});
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/9/trace", {},
                        {"Upgrade: websocket", "Connection: Upgrade",
                         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==", "Sec-WebSocket-Version: 13"})
                .status,
            404);
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/1/trace").status, 426);
}

// candump -L lines of the last seconds, as a file (canplayer -I replays it).
TEST(CaptureRoute, CandumpLinesOfTheLastSeconds) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  rig.run_until([] { return false; }, 1500ms);
  const auto r = rig.request("GET", "/api/v1/networks/1/capture?last=5&format=candump");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_THAT(r.content_type, HasSubstr("text/plain"));
  EXPECT_TRUE(r.has_header("content-disposition: attachment; filename=\"canopen-net1-")) << r.head;
  EXPECT_THAT(r.head, HasSubstr(".log\""));
  std::istringstream lines(r.body);
  std::string line;
  const std::regex form(R"(\(\d{10}\.\d{6}\) demo1 [0-9A-F]{3}#([0-9A-F]{2})*)");
  int n = 0;
  bool own_heartbeat = false, device_heartbeat = false;
  while (std::getline(lines, line)) {
    ++n;
    EXPECT_TRUE(std::regex_match(line, form)) << line;
    own_heartbeat = own_heartbeat || line.ends_with(" 77F#05") || line.ends_with(" 77F#7F");
    device_heartbeat = device_heartbeat || line.ends_with(" 705#05");
  }
  EXPECT_GT(n, 10);
  EXPECT_TRUE(own_heartbeat) << "the frames the gateway sent are captured too";
  EXPECT_TRUE(device_heartbeat);
}

// pcapng, read back by the independent reader: every frame with its
// direction; ?seconds= captures the next seconds.
TEST(CaptureRoute, PcapngReadBackAndTheNextSeconds) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  const auto started = std::chrono::system_clock::now();
  const auto r = rig.request("GET", "/api/v1/networks/1/capture?seconds=1");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "application/x-pcapng");
  EXPECT_THAT(r.head, HasSubstr(".pcapng\""));
  const auto file = std::filesystem::temp_directory_path() / ("capture-" + std::to_string(::getpid()) + ".pcapng");
  std::ofstream(file, std::ios::binary) << r.body;
  const std::string cmd = "python3 " CANOPEN_SOURCE_DIR "/tests/tools/pcapng_read.py " + file.string() + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  EXPECT_EQ(::pclose(p), 0) << out;
  std::filesystem::remove(file);
  EXPECT_THAT(out, HasSubstr(" rx\n"));
  EXPECT_THAT(out, HasSubstr(" tx\n"));
  // Every frame inside the second asked for (whole seconds of the timestamps).
  const auto first = std::chrono::duration_cast<std::chrono::seconds>(started.time_since_epoch()).count();
  std::istringstream lines(out);
  std::string line;
  while (std::getline(lines, line)) {
    const auto secs = std::stoll(line.substr(1, 10));
    EXPECT_GE(secs, first);
    EXPECT_LE(secs, first + 3);
  }
}

TEST(CaptureRoute, BadQueriesAre400UnknownNetwork404) {
  RestRig rig;
  for (const char* q : {"?format=xml", "?last=0", "?last=x", "?last=5&seconds=1", "?seconds=3600"}) {
    const auto r = rig.request("GET", std::string("/api/v1/networks/1/capture") + q);
    EXPECT_EQ(r.status, 400) << q << " " << r.body;
    EXPECT_EQ(r.content_type, "application/problem+json");
  }
  EXPECT_EQ(rig.request("GET", "/api/v1/networks/9/capture").status, 404);
}

// Bus load: null with the reason without a bit rate; with one, a share of it.
TEST(BusLoadRoute, PercentWithTheConfiguredBitRateOnly) {
  {
    RestRig rig({}, [](Config& c) { c.networks.at(0).bitrate = 0; });
    const auto n = rig.request("GET", "/api/v1/networks/1").json();
    EXPECT_TRUE(n.at("busLoad").at("percent1s").is_null());
    EXPECT_EQ(n.at("busLoad").at("reason"), "no bitrate configured for this network");
    EXPECT_THAT(rig.request("GET", "/metrics").body, Not(HasSubstr("canopen_gateway_bus_load_percent{")));
  }
  RestRig rig({}, [](Config& c) { c.networks.at(0).bitrate = 125000; });
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  rig.run_until([] { return false; }, 1200ms);
  const auto n = rig.request("GET", "/api/v1/networks/1").json();
  EXPECT_EQ(n.at("busLoad").at("bitrate"), 125000);
  EXPECT_GT(n.at("busLoad").at("percent1s").to_number<double>(), 0.0);
  EXPECT_LT(n.at("busLoad").at("percent10s").to_number<double>(), 100.0);
  EXPECT_GT(n.at("capture").at("frames").to_number<std::int64_t>(), 0);
  EXPECT_THAT(rig.request("GET", "/metrics").body,
              HasSubstr("canopen_gateway_bus_load_percent{network=\"1\",interface=\"demo\",window=\"1s\"} "));
}

}  // namespace
}  // namespace gateway::test
