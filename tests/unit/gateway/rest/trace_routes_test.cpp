// The bus trace and capture routes on the demo gateway (contract "Bus
// trace and capture"): the trace WebSocket (decoded frames, id filters, a
// slow client told what it lost while a fast one gets everything), the
// capture as candump -L lines and as pcapng (read back by
// tests/tools/pcapng_read.py), ?seconds= streamed as the frames come, bus
// load in GET /api/v1/networks/{net}.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <thread>
#include <fstream>
#include <regex>
#include <sstream>

#include "rest_rig.hpp"
#include "rest/trace_routes.hpp"
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

// The independent reader's view of a pcapng file (tests/tools/pcapng_read.py):
// one candump -L line plus direction per frame, "# ..." statistics lines.
std::string read_pcapng(const std::string& bytes) {
  const auto file = std::filesystem::temp_directory_path() / ("capture-" + std::to_string(::getpid()) + ".pcapng");
  std::ofstream(file, std::ios::binary) << bytes;
  const std::string cmd = "python3 " CANOPEN_SOURCE_DIR "/tests/tools/pcapng_read.py " + file.string() + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  EXPECT_NE(p, nullptr);
  std::string out;
  char buf[512];
  while (p != nullptr && std::fgets(buf, sizeof buf, p)) out += buf;
  EXPECT_EQ(p != nullptr ? ::pclose(p) : -1, 0) << out;
  std::filesystem::remove(file);
  return out;
}

// Frame times of the reader's lines, in seconds since the epoch.
std::vector<double> frame_times(const std::string& out) {
  std::vector<double> t;
  std::istringstream lines(out);
  std::string line;
  while (std::getline(lines, line))
    if (line.starts_with("(")) t.push_back(std::stod(line.substr(1, 17)));
  return t;
}

// A plain socket on its own thread: sends one GET, tells when the body's
// first bytes are in, then reads to the close.
struct StreamingGet {
  StreamingGet(std::uint16_t port, const std::string& target, int rcvbuf = 0) : sock(io) {
    sock.open(tcp::v4());
    if (rcvbuf > 0) sock.set_option(boost::asio::socket_base::receive_buffer_size(rcvbuf));
    sock.connect({boost::asio::ip::make_address("127.0.0.1"), port});
    boost::asio::write(sock, boost::asio::buffer("GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"));
  }
  // The header and at least `body_bytes` more.
  void read_head(std::size_t body_bytes) {
    boost::system::error_code ec;
    boost::asio::read_until(sock, boost::asio::dynamic_buffer(raw), "\r\n\r\n", ec);
    while (!ec && raw.size() < raw.find("\r\n\r\n") + 4 + body_bytes) {
      const auto n = sock.read_some(boost::asio::buffer(tmp), ec);
      raw.append(tmp.data(), n);
    }
  }
  HttpReply finish() {
    boost::system::error_code ec;
    boost::asio::read(sock, boost::asio::dynamic_buffer(raw), ec);
    HttpReply r;
    const auto head_end = raw.find("\r\n\r\n");
    r.status = std::stoi(raw.substr(9, 3));
    r.head = raw.substr(0, head_end);
    for (char& c : r.head) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    std::size_t pos = head_end + 4;  // de-chunk
    for (;;) {
      const auto eol = raw.find("\r\n", pos);
      if (eol == std::string::npos) break;
      const auto n = std::stoul(raw.substr(pos, eol - pos), nullptr, 16);
      if (n == 0) {
        complete = true;
        break;
      }
      r.body += raw.substr(eol + 2, n);
      pos = eol + 2 + n + 2;
    }
    return r;
  }
  boost::asio::io_context io;
  tcp::socket sock;
  std::string raw;
  std::array<char, 4096> tmp{};
  bool complete = false;
};

// ?seconds=S is streamed (contract "Bus trace and capture"): the header
// and the pcapng's section header and interface block arrive at once, each
// frame as the bus carries it, so a frame put on the bus after the first
// bytes were read is in the file; the file covers the whole period and
// ends with the interface statistics (nothing dropped).
TEST(CaptureRoute, SecondsIsStreamedAsTheFramesCome) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  auto tap = rig.app->frame_tap(1);
  ASSERT_TRUE(tap);
  const auto started = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  std::atomic<bool> first_bytes{false};
  auto client = std::async(std::launch::async, [&] {
    StreamingGet get(rig.port, "/api/v1/networks/1/capture?seconds=2");
    get.read_head(28);  // a pcapng section header block is 28 bytes and more
    first_bytes = true;
    auto r = get.finish();
    return std::make_pair(r, get.complete);
  });
  ASSERT_TRUE(rig.run_until([&] { return first_bytes.load(); }, 5s));
  // A marker no demo device sends (123h), after the client had its first bytes.
  auto marker = canopen::can::Frame::standard(0x123, {});
  marker.len = 2;
  marker.data[0] = 0xCA;
  marker.data[1] = 0xFE;
  tap->sent(marker, std::chrono::steady_clock::now(), std::chrono::system_clock::now());
  ASSERT_TRUE(rig.run_until([&] { return client.wait_for(0s) == std::future_status::ready; }, 10s));
  const auto [r, complete] = client.get();
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_TRUE(r.has_header("content-type: application/x-pcapng")) << r.head;
  EXPECT_TRUE(r.has_header("transfer-encoding: chunked")) << r.head;
  EXPECT_THAT(r.head, HasSubstr(".pcapng\""));
  EXPECT_TRUE(complete) << "the last chunk ends the body";
  const auto out = read_pcapng(r.body);
  EXPECT_THAT(out, HasSubstr(" 123#CAFE tx\n")) << "the frame sent after the first bytes is in the file";
  EXPECT_THAT(out, HasSubstr(" rx\n"));
  EXPECT_THAT(out, HasSubstr("# demo1: statistics dropped=0 received="));
  const auto times = frame_times(out);
  ASSERT_FALSE(times.empty());
  // All inside the capture, from its start to its end (the demo's
  // heartbeats and PDOs keep the bus busy all along).
  EXPECT_GE(*std::min_element(times.begin(), times.end()), started);
  EXPECT_LE(*std::min_element(times.begin(), times.end()), started + 0.9);
  EXPECT_GE(*std::max_element(times.begin(), times.end()), started + 1.1);
  EXPECT_LE(*std::max_element(times.begin(), times.end()), started + 4);
}

// The same as candump -L lines; a client that disconnects ends the
// recording (no recorder left on the tap).
TEST(CaptureRoute, SecondsAsCandumpAndADisconnectEndsIt) {
  RestRig rig;
  ASSERT_TRUE(rig.run_until([&] { return rig.all_operational(); }));
  const auto r = rig.request("GET", "/api/v1/networks/1/capture?seconds=1&format=candump");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_THAT(r.content_type, HasSubstr("text/plain"));
  EXPECT_THAT(r.head, HasSubstr(".log\""));
  std::istringstream lines(r.body);
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    ++n;
    EXPECT_TRUE(std::regex_match(line, std::regex(R"(\(\d{10}\.\d{6}\) demo1 [0-9A-F]{3}#([0-9A-F]{2})*)"))) << line;
  }
  EXPECT_GT(n, 5);

  auto tap = rig.app->frame_tap(1);
  const auto before = tap->recorders();
  auto client = std::async(std::launch::async, [&] {
    StreamingGet get(rig.port, "/api/v1/networks/1/capture?seconds=3600");
    get.read_head(28);
    return 0;  // closes the socket
  });
  ASSERT_TRUE(rig.run_until([&] { return client.wait_for(0s) == std::future_status::ready; }, 5s));
  EXPECT_TRUE(rig.run_until([&] { return tap->recorders() == before; }, 5s))
      << "the hour-long capture still records after its client left";
}

// A client that does not read: the gateway buffers a bounded amount, then
// drops frames and counts them; the bus path never waits, and the file
// says how many were dropped (pcapng Interface Statistics Block).
TEST(CaptureRoute, SlowClientLosesFramesCountedInTheFile) {
  RestRig rig;
  auto tap = rig.app->frame_tap(1);
  ASSERT_TRUE(tap);
  std::atomic<bool> go{false}, first_bytes{false};
  auto client = std::async(std::launch::async, [&] {
    StreamingGet get(rig.port, "/api/v1/networks/1/capture?seconds=2", 4096);
    get.read_head(28);
    first_bytes = true;
    while (!go) std::this_thread::sleep_for(10ms);  // does not read meanwhile
    return get.finish();
  });
  ASSERT_TRUE(rig.run_until([&] { return first_bytes.load(); }, 5s));
  auto f = canopen::can::Frame::standard(0x123, {});
  f.len = 8;
  constexpr std::uint32_t kFrames = 100000;  // 64-byte pcapng blocks: 6.4 MB, beyond the 1 MiB bound and the sockets
  for (std::uint32_t i = 0; i < kFrames; i += 1000) {
    for (std::uint32_t k = i; k < i + 1000; ++k)
      tap->sent(f, std::chrono::steady_clock::now(), std::chrono::system_clock::now());
    rig.io.poll();
  }
  go = true;
  ASSERT_TRUE(rig.run_until([&] { return client.wait_for(0s) == std::future_status::ready; }, 15s));
  const auto r = client.get();
  const auto out = read_pcapng(r.body);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(# demo1: statistics dropped=(\d+) received=(\d+))"))) << out;
  const auto dropped = std::stoull(m[1]);
  const auto received = std::stoull(m[2]);
  std::uint64_t markers = 0;
  for (std::size_t p = out.find(" 123#"); p != std::string::npos; p = out.find(" 123#", p + 1)) ++markers;
  EXPECT_GT(dropped, 0u);
  EXPECT_GT(markers, 0u);
  EXPECT_EQ(frame_times(out).size(), received - dropped) << "every frame not counted as dropped is in the file";
}

TEST(CaptureRoute, BadQueriesAre400UnknownNetwork404) {
  RestRig rig;
  for (const char* q : {"?format=xml", "?last=0", "?last=x", "?last=5&seconds=1", "?seconds=0", "?seconds=3601"}) {
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
