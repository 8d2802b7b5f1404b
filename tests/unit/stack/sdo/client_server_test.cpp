// Tests for stack/src/sdo/client.cpp against stack/src/sdo/server.cpp over
// the in-memory bus with a fake clock: every transfer mode and size, lost
// and duplicated frames, queueing, cancellation, progress, and servers that
// misbehave (garbage, wrong index, silence).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/clock.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/sdo/server.hpp"
#include "unit/stack/sdo/sdo_test_support.hpp"

namespace canopen::sdo {
namespace {

using namespace std::chrono_literals;
using test::hex;
using test::to_hex;

constexpr std::uint8_t kNode = 5;

// A client, one server (node 5) and a spy on one in-memory bus.
class Network {
 public:
  explicit Network(ClientConfig ccfg = {}, ServerConfig scfg = {}, can::BusFaults faults = {})
      : bus(std::move(faults)), od(test::make_test_dictionary()) {
    server_ep = bus.attach("server");
    client_ep = bus.attach("client");
    spy_ep = bus.attach("spy");
    scfg.node_id = kNode;
    server = std::make_unique<SdoServer>(od, scfg, [this](const can::Frame& f) { server_ep->send(f); });
    client = std::make_unique<SdoClient>(ccfg, [this](const can::Frame& f) { client_ep->send(f); });
    server_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) server->on_frame(f, clock.now());
    });
    client_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) client->on_frame(f, clock.now());
    });
    spy_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) {
        ++seen;
        if (log.size() < log_limit) log.push_back(f);
      }
    });
  }

  // Delivers frames and fires timers until done() holds. Returns the number
  // of clock steps taken, or nullopt when done() never held: nothing was
  // left to happen (a hang) or max_steps passed.
  std::optional<int> run(const std::function<bool()>& done, int max_steps = 100) {
    for (int step = 0; step <= max_steps; ++step) {
      bus.deliver();
      if (done()) return step;
      const TimePoint next = std::min(client->next_deadline(), server->next_deadline());
      if (next == TimePoint::max()) return std::nullopt;
      clock.advance_to(next);
      client->on_time(clock.now());
      server->on_time(clock.now());
    }
    return std::nullopt;
  }

  // Runs until the server is idle too (e.g. after the client gave up).
  void settle() {
    run([this] { return server->state() == SdoServer::State::Idle && bus.pending() == 0; });
  }

  // Frames logged by the spy with this COB-ID, as hex.
  std::vector<std::string> frames(std::uint32_t id) const {
    std::vector<std::string> out;
    for (const auto& f : log) {
      if (f.id == id) out.push_back(to_hex(test::payload(f)));
    }
    return out;
  }
  std::vector<std::string> requests() const { return frames(0x600 + kNode); }
  std::vector<std::string> responses() const { return frames(0x580 + kNode); }

  FakeClock clock;
  can::MemoryBus bus;  // outlives the endpoints below
  od::ObjectDictionary od;
  std::unique_ptr<can::MemoryEndpoint> server_ep;
  std::unique_ptr<can::MemoryEndpoint> client_ep;
  std::unique_ptr<can::MemoryEndpoint> spy_ep;
  std::unique_ptr<SdoServer> server;
  std::unique_ptr<SdoClient> client;
  std::vector<can::Frame> log;
  std::size_t log_limit = 64;
  std::uint64_t seen = 0;
};

// Collects the completion of one request.
struct Outcome {
  std::optional<TransferResult> result;
  CompletionHandler handler() {
    return [this](TransferResult&& r) {
      EXPECT_FALSE(result.has_value()) << "completed twice";
      result = std::move(r);
    };
  }
  bool done() const { return result.has_value(); }
};

Request request(std::uint16_t index, std::uint8_t sub = 0, Mode mode = Mode::Auto) {
  Request r;
  r.node = kNode;
  r.index = index;
  r.sub = sub;
  r.mode = mode;
  return r;
}

std::string describe(const TransferResult& r) {
  return r.error ? r.error.message() + " (" + r.detail + ")" : std::string("ok");
}

// ---- every mode and size -----------------------------------------------------------------------

struct Case {
  bool upload;
  Mode mode;
  std::size_t size;
};

std::string mode_name(Mode m) {
  switch (m) {
    case Mode::Auto: return "Auto";
    case Mode::Expedited: return "Expedited";
    case Mode::Segmented: return "Segmented";
    case Mode::Block: return "Block";
  }
  return "?";
}

std::vector<Case> all_cases() {
  std::vector<Case> out;
  for (const bool upload : {false, true}) {
    for (const Mode mode : {Mode::Auto, Mode::Expedited, Mode::Segmented, Mode::Block}) {
      for (const std::size_t size : {0UL, 1UL, 4UL, 5UL, 7UL, 8UL, 889UL, 890UL, 65537UL, 1048576UL}) {
        if (!upload && mode == Mode::Expedited && (size == 0 || size > 4)) continue;  // refused, tested below
        out.push_back({upload, mode, size});
      }
    }
  }
  return out;
}

// The command byte (and pst) the client's initiate must have.
std::string expected_initiate(const Case& c) {
  if (c.upload) {
    switch (c.mode) {
      case Mode::Auto: return "A4 05 20 00 7F 40";  // block with pst = 64
      case Mode::Block: return "A4 05 20 00 7F 00";
      default: return "40 05 20 00 00 00";
    }
  }
  const bool expedited = c.size >= 1 && c.size <= 4;
  if (c.mode == Mode::Block || (c.mode == Mode::Auto && c.size > 64)) return "C6 05 20 00";
  if (c.mode == Mode::Expedited || (c.mode == Mode::Auto && expedited)) {
    return c.size == 1 ? "2F 05 20 00" : "23 05 20 00";
  }
  return "21 05 20 00";
}

class SdoTransfer : public ::testing::TestWithParam<Case> {};

TEST_P(SdoTransfer, DataArrivesByteForByte) {
  const Case c = GetParam();
  Network net;
  const Bytes data = test::pattern(c.size, static_cast<std::uint32_t>(c.size));
  Outcome out;
  Request r = request(test::kBigDomain, 0, c.mode);
  r.on_done = out.handler();
  if (c.upload) {
    ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
    ASSERT_TRUE(net.client->upload(std::move(r), net.clock.now()));
  } else {
    ASSERT_TRUE(net.client->download(std::move(r), data, net.clock.now()));
  }
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value()) << "transfer never completed";
  EXPECT_EQ(*steps, 0) << "a timer had to fire";
  ASSERT_TRUE(out.result->ok()) << describe(*out.result);
  EXPECT_EQ(out.result->origin, Origin::None);
  if (c.upload) {
    EXPECT_EQ(out.result->data.size(), data.size());
    EXPECT_TRUE(out.result->data == data) << "uploaded bytes differ";
  } else {
    const Bytes stored = test::domain_bytes(net.od, test::kBigDomain);
    EXPECT_EQ(stored.size(), data.size());
    EXPECT_TRUE(stored == data) << "downloaded bytes differ";
  }
  const auto reqs = net.requests();
  ASSERT_FALSE(reqs.empty());
  const std::string want = expected_initiate(c);
  EXPECT_EQ(reqs.front().substr(0, want.size()), want);
  if (c.upload && c.mode == Mode::Auto) {
    // Protocol switch: up to pst bytes the server answers with a normal upload.
    const auto resps = net.responses();
    ASSERT_FALSE(resps.empty());
    EXPECT_EQ(resps.front().substr(0, 1), c.size <= 64 ? "4" : "C");
  }
  EXPECT_EQ(net.server->state(), SdoServer::State::Idle);
  EXPECT_FALSE(net.client->busy(kNode));
}

INSTANTIATE_TEST_SUITE_P(AllModesAndSizes, SdoTransfer, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           const Case& c = param_info.param;
                           return std::string(c.upload ? "Upload" : "Download") + mode_name(c.mode) +
                                  std::to_string(c.size);
                         });

TEST(SdoClient, ExpeditedDownloadNeedsOneToFourBytes) {
  Network net;
  for (const std::size_t n : {0UL, 5UL}) {
    const auto r = net.client->download(request(test::kDomain, 0, Mode::Expedited), Bytes(n), net.clock.now());
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.code(), std::errc::invalid_argument);
  }
  EXPECT_EQ(net.bus.pending(), 0U);
}

TEST(SdoClient, NodeMustBe1To127) {
  Network net;
  Request r = request(test::kDomain);
  r.node = 0;
  EXPECT_EQ(net.client->upload(r, net.clock.now()).code(), std::errc::invalid_argument);
  r.node = 128;
  EXPECT_EQ(net.client->upload(r, net.clock.now()).code(), std::errc::invalid_argument);
}

TEST(SdoClient, TypedObjectsRoundTrip) {
  Network net;
  Outcome w, r1, r2;
  Request wr = request(test::kHeartbeat);
  wr.on_done = w.handler();
  ASSERT_TRUE(net.client->download(wr, Bytes{0xE8, 0x03}, net.clock.now()));
  Request rd = request(test::kHeartbeat);
  rd.on_done = r1.handler();
  ASSERT_TRUE(net.client->upload(rd, net.clock.now()));
  Request rs = request(test::kString, 0, Mode::Segmented);
  rs.on_done = r2.handler();
  ASSERT_TRUE(net.client->upload(rs, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return r2.done(); }));
  ASSERT_TRUE(w.result->ok());
  EXPECT_EQ(net.od.get_unsigned(test::kHeartbeat, 0), 1000U);
  EXPECT_EQ(r1.result->data, (Bytes{0xE8, 0x03}));
  EXPECT_EQ(std::string(r2.result->data.begin(), r2.result->data.end()), "hello world!");
}

TEST(SdoClient, ExpectedSizeSkipsTheBlockInitiateForSmallUploads) {
  Network net;
  Outcome small, large;
  Request r = request(test::kDeviceType);
  r.expected_size = 4;
  r.on_done = small.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  Request big = request(test::kString);
  big.expected_size = 1000;  // above the threshold: block with protocol switch
  big.on_done = large.handler();
  ASSERT_TRUE(net.client->upload(big, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return large.done(); }));
  ASSERT_TRUE(small.result->ok());
  EXPECT_EQ(small.result->data, (Bytes{0x92, 0x01, 0x02, 0x00}));
  ASSERT_TRUE(large.result->ok());
  const auto reqs = net.requests();
  ASSERT_GE(reqs.size(), 2U);
  EXPECT_EQ(reqs[0], "40 00 10 00 00 00 00 00");
  EXPECT_EQ(reqs[1].substr(0, 2), "A4");
}

// ---- errors from the server ------------------------------------------------------------------------

TEST(SdoClient, ServerAbortIsRemoteWithTheStandardText) {
  Network net;
  Outcome out;
  Request r = request(0x3000);
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  EXPECT_EQ(out.result->error, SdoAbort::NoSuchObject);
  EXPECT_EQ(out.result->error.value(), 0x06020000);
  EXPECT_EQ(out.result->error.category(), sdo_abort_category());
  EXPECT_EQ(out.result->error.message(), "Object does not exist in the object dictionary");
  EXPECT_EQ(out.result->origin, Origin::Remote);
  EXPECT_FALSE(out.result->cancelled);
  EXPECT_TRUE(out.result->data.empty());
}

TEST(SdoClient, ServerAbortDuringASegmentedDownload) {
  Network net;
  Outcome out;
  Request r = request(test::kString);
  r.on_done = out.handler();
  net.od.on_write(test::kString, [](od::SubEntry&, const Value&) { return make_error_code(SdoAbort::CannotStore); });
  ASSERT_TRUE(net.client->download(r, Bytes(20, 'x'), net.clock.now()));
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  EXPECT_EQ(out.result->error, SdoAbort::CannotStore);
  EXPECT_EQ(out.result->origin, Origin::Remote);
}

// ---- block fallback -------------------------------------------------------------------------------------

// A server without block transfer: it answers block initiates with 05040001h.
void make_legacy(Network& net) {
  net.server_ep->on_frames([&net](std::span<const can::Frame> fs) {
    for (const auto& f : fs) {
      const PayloadView p = payload_of(f);
      const auto ccs = static_cast<ClientCommand>(command_bits(p));
      if (f.id == 0x600 + kNode && (ccs == ClientCommand::BlockDownload || ccs == ClientCommand::BlockUpload)) {
        net.server_ep->send(make_frame(0x580 + kNode, abort_transfer(multiplexer(p), 0x05040001)));
      } else {
        net.server->on_frame(f, net.clock.now());
      }
    }
  });
}

TEST(SdoClient, AutoFallsBackToSegmentedAndRemembers) {
  Network net;
  make_legacy(net);
  const Bytes data = test::pattern(1000);
  Outcome d1, d2, u1;
  Request r = request(test::kBigDomain);
  r.on_done = d1.handler();
  ASSERT_TRUE(net.client->download(r, data, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return d1.done(); }));
  ASSERT_TRUE(d1.result->ok()) << describe(*d1.result);
  EXPECT_TRUE(test::domain_bytes(net.od, test::kBigDomain) == data);
  auto reqs = net.requests();
  ASSERT_GE(reqs.size(), 2U);
  EXPECT_EQ(reqs[0].substr(0, 2), "C6");
  EXPECT_EQ(reqs[1], "21 05 20 00 E8 03 00 00");

  // Learned: the next large download and an upload go the normal way at once.
  net.log.clear();
  r.on_done = d2.handler();
  ASSERT_TRUE(net.client->download(r, data, net.clock.now()));
  Request u = request(test::kBigDomain);
  u.on_done = u1.handler();
  ASSERT_TRUE(net.client->upload(u, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return u1.done(); }));
  ASSERT_TRUE(d2.result->ok());
  ASSERT_TRUE(u1.result->ok());
  EXPECT_TRUE(u1.result->data == data);
  reqs = net.requests();
  EXPECT_EQ(reqs.front(), "21 05 20 00 E8 03 00 00");
  EXPECT_EQ(std::count_if(reqs.begin(), reqs.end(), [](const std::string& s) { return s.starts_with("C"); }), 0);
  EXPECT_EQ(std::count_if(reqs.begin(), reqs.end(), [](const std::string& s) { return s.starts_with("A4"); }), 0);
}

TEST(SdoClient, AutoUploadFallsBack) {
  Network net;
  make_legacy(net);
  Outcome out;
  Request r = request(test::kString);
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  ASSERT_TRUE(out.result->ok()) << describe(*out.result);
  EXPECT_EQ(std::string(out.result->data.begin(), out.result->data.end()), "hello world!");
  const auto reqs = net.requests();
  ASSERT_GE(reqs.size(), 2U);
  EXPECT_EQ(reqs[0].substr(0, 2), "A4");
  EXPECT_EQ(reqs[1], "40 01 20 00 00 00 00 00");

  // forget_block_support: block is tried again.
  net.client->forget_block_support(kNode);
  net.log.clear();
  Outcome again;
  r.on_done = again.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return again.done(); }));
  EXPECT_EQ(net.requests().front().substr(0, 2), "A4");
}

TEST(SdoClient, ForcedBlockDoesNotFallBack) {
  Network net;
  make_legacy(net);
  Outcome out;
  Request r = request(test::kBigDomain, 0, Mode::Block);
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->download(r, test::pattern(100), net.clock.now()));
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  EXPECT_EQ(out.result->error, SdoAbort::InvalidCommand);
  EXPECT_EQ(out.result->origin, Origin::Remote);
}

// ---- stray aborts and learning block support (7.2.4.3.13, 7.2.4.3.17) ----------------------------------

// Runs `before` on every request frame the server gets, ahead of the server
// itself; frames `before` returns true for are not passed on.
void intercept(Network& net, std::function<bool(PayloadView request)> before) {
  net.server_ep->on_frames([&net, before = std::move(before)](std::span<const can::Frame> fs) {
    for (const auto& f : fs) {
      if (f.id == 0x600 + kNode && before(payload_of(f))) continue;
      net.server->on_frame(f, net.clock.now());
    }
  });
}

std::size_t count_starting(const std::vector<std::string>& frames, std::string_view prefix) {
  return static_cast<std::size_t>(
      std::count_if(frames.begin(), frames.end(), [prefix](const std::string& s) { return s.starts_with(prefix); }));
}

// 7.2.4.3.17: the abort's m is the multiplexer of the aborted transfer. One
// for another object (here 1000h, e.g. late for an earlier transfer) is not
// this transfer's: the block upload goes on, and the server is not taken to
// refuse block transfer, not even for an 05040001h answering the initiate.
TEST(SdoClient, StrayAbortForAnotherObjectDoesNotEndTheTransfer_7_2_4_3_17) {
  Network net;
  net.log_limit = 1000;
  intercept(net, [&net](PayloadView p) {
    if (p[0] == 0xA4 || p[0] == 0xA3) {  // block upload initiate, start
      const std::uint32_t code = p[0] == 0xA4 ? 0x05040001 : 0x08000020;
      net.server_ep->send(make_frame(0x580 + kNode, abort_transfer({0x1000, 0}, code)));
    }
    return false;
  });
  const Bytes data = test::pattern(1000);
  ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
  Outcome out;
  Request r = request(test::kBigDomain);
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value());
  EXPECT_EQ(*steps, 0) << "no timeout";
  ASSERT_TRUE(out.result->ok()) << describe(*out.result);
  EXPECT_TRUE(out.result->data == data);
  EXPECT_EQ(net.client->stray_aborts(), 2U);
  EXPECT_TRUE(net.client->block_allowed(kNode, net.clock.now()));
  EXPECT_EQ(count_starting(net.requests(), "40"), 0U) << "no fallback to a normal upload";
  EXPECT_EQ(count_starting(net.requests(), "80"), 0U) << "the client aborted nothing";

  // The next large upload is a block upload again.
  net.log.clear();
  Outcome again;
  r.on_done = again.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return again.done(); }));
  ASSERT_TRUE(again.result->ok()) << describe(*again.result);
  EXPECT_EQ(net.requests().front().substr(0, 2), "A4");
}

// 7.2.4.3.5 vs 7.2.4.3.13: an upload whose expected size is at most
// block_threshold opens with the normal initiate (ccs=2, 40h), larger or
// unknown ones with the block initiate (ccs=5, A4h, pst = threshold).
TEST(SdoClient, SmallExpectedSizeUploadsWithANormalInitiate_7_2_4_3_5) {
  struct SizeCase {
    std::optional<std::size_t> expected;
    std::size_t actual;
    const char* initiate;
  };
  for (const SizeCase c :
       {SizeCase{4, 4, "40 05 20 00 00 00 00 00"}, SizeCase{64, 64, "40 05 20 00 00 00 00 00"},
        SizeCase{65, 65, "A4 05 20 00 7F 40 00 00"}, SizeCase{std::nullopt, 4, "A4 05 20 00 7F 40 00 00"}}) {
    SCOPED_TRACE(c.expected ? std::to_string(*c.expected) : std::string("unknown"));
    Network net;
    const Bytes data = test::pattern(c.actual);
    ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
    Outcome out;
    Request r = request(test::kBigDomain);
    r.expected_size = c.expected;
    r.on_done = out.handler();
    ASSERT_TRUE(net.client->upload(r, net.clock.now()));
    ASSERT_TRUE(net.run([&] { return out.done(); }));
    ASSERT_TRUE(out.result->ok()) << describe(*out.result);
    EXPECT_TRUE(out.result->data == data);
    ASSERT_FALSE(net.requests().empty());
    EXPECT_EQ(net.requests().front(), c.initiate);
  }
}

// A device without block transfer costs nothing on reads of known small
// size: one request, one response, and nothing learned or forgotten.
TEST(SdoClient, SmallReadsFromADeviceWithoutBlockTakeOneRoundTrip) {
  Network net;
  make_legacy(net);
  Outcome out;
  Request r = request(test::kDeviceType);
  r.expected_size = 4;
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value());
  EXPECT_EQ(*steps, 0);
  ASSERT_TRUE(out.result->ok()) << describe(*out.result);
  EXPECT_EQ(net.requests(), std::vector<std::string>{"40 00 10 00 00 00 00 00"});
  EXPECT_EQ(net.responses().size(), 1U);
}

// A refusal for the request's own index/sub-index (05040001h answering the
// block initiate) is learnt: Auto transfers to that node go the normal way
// for block_retry_interval, then block is tried again.
TEST(SdoClient, RefusedBlockIsLearntAndRetriedAfterTheInterval) {
  ClientConfig cfg;
  cfg.block_retry_interval = 60s;
  Network net(cfg);
  make_legacy(net);
  auto read_string = [&net] {
    net.log.clear();
    Outcome out;
    Request r = request(test::kString);  // VISIBLE_STRING: size unknown
    r.on_done = out.handler();
    EXPECT_TRUE(net.client->upload(r, net.clock.now()));
    const auto steps = net.run([&] { return out.done(); });
    EXPECT_EQ(steps, std::optional<int>(0)) << "no timeout";
    EXPECT_TRUE(out.done() && out.result->ok());
    return net.requests();
  };
  const TimePoint start = net.clock.now();
  auto reqs = read_string();
  ASSERT_GE(reqs.size(), 2U);
  EXPECT_EQ(reqs[0], "A4 01 20 00 7F 40 00 00");
  EXPECT_EQ(reqs[1], "40 01 20 00 00 00 00 00") << "restarted at once the normal way";
  EXPECT_FALSE(net.client->block_allowed(kNode, net.clock.now()));

  net.clock.advance_to(start + 59s);
  reqs = read_string();
  EXPECT_EQ(count_starting(reqs, "A4"), 0U) << "still within the interval";
  EXPECT_EQ(reqs.front(), "40 01 20 00 00 00 00 00");

  net.clock.advance_to(start + 60s);
  EXPECT_TRUE(net.client->block_allowed(kNode, net.clock.now()));
  reqs = read_string();
  ASSERT_GE(reqs.size(), 2U);
  EXPECT_EQ(reqs[0], "A4 01 20 00 7F 40 00 00") << "block tried again";
  EXPECT_EQ(reqs[1], "40 01 20 00 00 00 00 00");
  EXPECT_FALSE(net.client->block_allowed(kNode, net.clock.now())) << "and learnt again";
}

// CANopenNode built without block transfer refuses a block initiate with
// 05040001h carrying the multiplexer of its previous transfer. That abort
// is stray, but the silence after it confirms the refusal: after one
// timeout the request goes the normal way instead of failing, and the node
// is treated as refusing block transfer.
TEST(SdoClient, RefusalWithAStaleMultiplexerIsConfirmedBySilence) {
  ClientConfig cfg;
  cfg.default_timeout = 300ms;
  Network net(cfg);
  std::optional<Multiplexer> previous;
  intercept(net, [&net, &previous](PayloadView p) {
    const auto ccs = static_cast<ClientCommand>(command_bits(p));
    if (ccs == ClientCommand::BlockUpload || ccs == ClientCommand::BlockDownload) {
      net.server_ep->send(make_frame(0x580 + kNode, abort_transfer(previous.value_or(Multiplexer{}), 0x05040001)));
      return true;
    }
    if (ccs == ClientCommand::InitiateUpload || ccs == ClientCommand::InitiateDownload) previous = multiplexer(p);
    return false;
  });
  Outcome first, name, again;
  Request r = request(test::kDeviceType);
  r.expected_size = 4;
  r.on_done = first.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return first.done(); }));
  ASSERT_TRUE(first.result->ok());

  net.log.clear();
  const TimePoint start = net.clock.now();
  Request s = request(test::kString);
  s.on_done = name.handler();
  ASSERT_TRUE(net.client->upload(s, start));
  ASSERT_TRUE(net.run([&] { return name.done(); }));
  ASSERT_TRUE(name.result->ok()) << describe(*name.result);
  EXPECT_EQ(std::string(name.result->data.begin(), name.result->data.end()), "hello world!");
  EXPECT_EQ(net.clock.now(), start + 300ms) << "one timeout, no more";
  const auto reqs = net.requests();
  ASSERT_GE(reqs.size(), 3U);
  EXPECT_EQ(reqs[0], "A4 01 20 00 7F 40 00 00");
  EXPECT_EQ(net.responses().front(), "80 00 10 00 01 00 04 05") << "the refusal names 1000h";
  EXPECT_EQ(reqs[1], "80 01 20 00 00 00 04 05") << "abort (timeout) before starting over";
  EXPECT_EQ(reqs[2], "40 01 20 00 00 00 00 00");
  EXPECT_FALSE(net.client->block_allowed(kNode, net.clock.now()));

  // Learnt: the next string read costs no timeout.
  net.log.clear();
  const TimePoint second = net.clock.now();
  s.on_done = again.handler();
  ASSERT_TRUE(net.client->upload(s, second));
  ASSERT_TRUE(net.run([&] { return again.done(); }));
  ASSERT_TRUE(again.result->ok());
  EXPECT_EQ(net.clock.now(), second);
  EXPECT_EQ(net.requests().front(), "40 01 20 00 00 00 00 00");
}

// ---- lost and duplicated frames ------------------------------------------------------------------------

TEST(SdoFaults, BlockDownloadRecoversFromALostSegment) {
  Network net;
  // Bus frame 0 is the initiate, 1 its response, 2.. the segments: drop segment 10.
  net.bus.set_faults({.verdict = [](const can::Frame&, std::uint64_t i) {
    return i == 11 ? can::FrameVerdict::Drop : can::FrameVerdict::Deliver;
  }});
  net.log_limit = 1000;
  const Bytes data = test::pattern(5000);
  Outcome out;
  Request r = request(test::kBigDomain, 0, Mode::Block);
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->download(r, data, net.clock.now()));
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value());
  EXPECT_EQ(*steps, 0);
  ASSERT_TRUE(out.result->ok()) << describe(*out.result);
  EXPECT_TRUE(test::domain_bytes(net.od, test::kBigDomain) == data);
  const auto resps = net.responses();
  EXPECT_NE(std::find(resps.begin(), resps.end(), "A2 09 7F 00 00 00 00 00"), resps.end())
      << "the server should acknowledge segment 9, the last before the gap";
}

TEST(SdoFaults, BlockUploadRecoversFromALostSegment) {
  Network net;
  // 0 initiate, 1 response, 2 start, 3..129 segments 1..127: drop segment
  // 10; 130 is the ack, 131.. the next sub-block: drop its segment 50.
  net.bus.set_faults({.verdict = [](const can::Frame&, std::uint64_t i) {
    return i == 12 || i == 131 + 49 ? can::FrameVerdict::Drop : can::FrameVerdict::Deliver;
  }});
  net.log_limit = 1000;
  const Bytes data = test::pattern(5000);
  ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
  Outcome out;
  Request r = request(test::kBigDomain, 0, Mode::Block);
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value());
  EXPECT_EQ(*steps, 0);
  ASSERT_TRUE(out.result->ok()) << describe(*out.result);
  EXPECT_TRUE(out.result->data == data);
  const auto reqs = net.requests();
  EXPECT_NE(std::find(reqs.begin(), reqs.end(), "A2 09 7F 00 00 00 00 00"), reqs.end());
  EXPECT_NE(std::find(reqs.begin(), reqs.end(), "A2 31 7F 00 00 00 00 00"), reqs.end());
}

TEST(SdoFaults, ReorderedFramesAreRecovered) {
  // A frame overtaking another makes a gap in a sub-block: go-back-n resends.
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    for (const bool upload : {false, true}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + (upload ? " upload" : " download"));
      Network net({}, {}, {.reorder = 0.02, .seed = seed, .verdict = nullptr});
      const Bytes data = test::pattern(20000, static_cast<std::uint32_t>(seed));
      Outcome out;
      Request r = request(test::kBigDomain, 0, Mode::Block);
      r.on_done = out.handler();
      if (upload) {
        ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
        ASSERT_TRUE(net.client->upload(r, net.clock.now()));
      } else {
        ASSERT_TRUE(net.client->download(r, data, net.clock.now()));
      }
      const auto steps = net.run([&] { return out.done(); });
      ASSERT_TRUE(steps.has_value());
      EXPECT_EQ(*steps, 0);
      ASSERT_TRUE(out.result->ok()) << describe(*out.result);
      EXPECT_TRUE((upload ? out.result->data : test::domain_bytes(net.od, test::kBigDomain)) == data);
    }
  }
}

TEST(SdoFaults, LostAcknowledgementTimesOutOnBothSides) {
  Network net;
  // Drop every server frame after the initiate response: the client waits
  // for an ack that never comes.
  net.bus.set_faults({.verdict = [](const can::Frame& f, std::uint64_t i) {
    return f.id == 0x580 + kNode && i > 1 ? can::FrameVerdict::Drop : can::FrameVerdict::Deliver;
  }});
  Outcome out;
  Request r = request(test::kBigDomain, 0, Mode::Block);
  r.on_done = out.handler();
  const TimePoint start = net.clock.now();
  ASSERT_TRUE(net.client->download(r, test::pattern(2000), net.clock.now()));
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value());
  EXPECT_EQ(out.result->error, SdoAbort::Timeout);
  EXPECT_EQ(out.result->origin, Origin::Local);
  EXPECT_EQ(net.clock.now(), start + 1s);
  net.settle();
  EXPECT_EQ(net.server->state(), SdoServer::State::Idle);
  EXPECT_TRUE(test::domain_bytes(net.od, test::kBigDomain).empty());
}

TEST(SdoFaults, EveryFrameDuplicated) {
  for (const Mode mode : {Mode::Expedited, Mode::Segmented, Mode::Block}) {
    for (const bool upload : {false, true}) {
      SCOPED_TRACE(mode_name(mode) + (upload ? " upload" : " download"));
      Network net;
      net.bus.set_faults({.verdict = [](const can::Frame&, std::uint64_t) { return can::FrameVerdict::Duplicate; }});
      const Bytes data = test::pattern(mode == Mode::Expedited ? 4 : 3000);
      Outcome out;
      Request r = request(test::kBigDomain, 0, mode);
      r.on_done = out.handler();
      if (upload) {
        ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
        ASSERT_TRUE(net.client->upload(r, net.clock.now()));
      } else {
        ASSERT_TRUE(net.client->download(r, data, net.clock.now()));
      }
      const auto steps = net.run([&] { return out.done(); });
      ASSERT_TRUE(steps.has_value());
      ASSERT_TRUE(out.result->ok()) << describe(*out.result);
      EXPECT_EQ(*steps, 0);
      EXPECT_TRUE((upload ? out.result->data : test::domain_bytes(net.od, test::kBigDomain)) == data);
      net.settle();
      EXPECT_EQ(net.server->state(), SdoServer::State::Idle);
    }
  }
}

// Random loss, duplication and reordering: each transfer either delivers
// the exact data or fails with an SDO abort code, within a bounded number of
// clock steps, and both sides end idle.
TEST(SdoFaults, RandomFaultsNeverHangNorCorrupt) {
  int block_ok = 0;
  int block_runs = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    for (const Mode mode : {Mode::Segmented, Mode::Block}) {
      for (const bool upload : {false, true}) {
        SCOPED_TRACE("seed " + std::to_string(seed) + " " + mode_name(mode) + (upload ? " upload" : " download"));
        Network net({}, {}, {.loss = 0.002, .duplicate = 0.01, .reorder = 0.005, .seed = seed, .verdict = nullptr});
        const Bytes data = test::pattern(2000, static_cast<std::uint32_t>(seed));
        Outcome out;
        Request r = request(test::kBigDomain, 0, mode);
        r.on_done = out.handler();
        if (upload) {
          ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
          ASSERT_TRUE(net.client->upload(r, net.clock.now()));
        } else {
          ASSERT_TRUE(net.client->download(r, data, net.clock.now()));
        }
        const auto steps = net.run([&] { return out.done(); }, 10);
        ASSERT_TRUE(steps.has_value()) << "hung";
        const TransferResult& res = *out.result;
        if (mode == Mode::Block) ++block_runs;
        if (res.ok()) {
          if (mode == Mode::Block) ++block_ok;
          EXPECT_TRUE((upload ? res.data : test::domain_bytes(net.od, test::kBigDomain)) == data);
        } else {
          EXPECT_EQ(res.error.category(), sdo_abort_category()) << res.error.message();
          if (!upload) {
            // A failed download leaves the object as it was (or, rarely, the
            // server completed and only the confirmation was lost).
            const Bytes stored = test::domain_bytes(net.od, test::kBigDomain);
            EXPECT_TRUE(stored.empty() || stored == data);
          }
        }
        net.settle();
        EXPECT_EQ(net.server->state(), SdoServer::State::Idle);
        EXPECT_FALSE(net.client->busy(kNode));
      }
    }
  }
  // Block transfers resend lost segments; only a lost ack, initiate or end
  // (a few frames per transfer) makes them fail.
  EXPECT_GE(block_ok * 10, block_runs * 8) << block_ok << " of " << block_runs << " block transfers succeeded";
}

// ---- misbehaving servers ---------------------------------------------------------------------------------

// A scripted server: answers each request with what reply() returns.
class ScriptedNetwork {
 public:
  using Reply = std::function<std::vector<can::Frame>(const Payload& request, std::size_t n)>;

  explicit ScriptedNetwork(Reply reply, ClientConfig ccfg = {}) : reply_(std::move(reply)) {
    server_ep_ = bus_.attach("server");
    client_ep_ = bus_.attach("client");
    client = std::make_unique<SdoClient>(ccfg, [this](const can::Frame& f) { client_ep_->send(f); });
    client_ep_->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) client->on_frame(f, clock.now());
    });
    server_ep_->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) {
        if (f.id != 0x600 + kNode) continue;
        received.push_back(to_hex(test::payload(f)));
        if (reply_) {
          for (const auto& out : reply_(test::payload(f), received.size() - 1)) server_ep_->send(out);
        }
      }
    });
  }

  std::optional<int> run(const std::function<bool()>& done, int max_steps = 10) {
    for (int step = 0; step <= max_steps; ++step) {
      bus_.deliver();
      if (done()) return step;
      const TimePoint next = client->next_deadline();
      if (next == TimePoint::max()) return std::nullopt;
      clock.advance_to(next);
      client->on_time(clock.now());
    }
    return std::nullopt;
  }

  FakeClock clock;
  std::unique_ptr<SdoClient> client;
  std::vector<std::string> received;  // what the server got, as hex

 private:
  can::MemoryBus bus_;
  Reply reply_;
  std::unique_ptr<can::MemoryEndpoint> server_ep_;
  std::unique_ptr<can::MemoryEndpoint> client_ep_;
};

can::Frame response(std::string_view text) { return make_frame(0x580 + kNode, hex(text)); }

struct GarbageCase {
  const char* name;
  bool upload;
  Mode mode;
  std::vector<std::string> replies;  // answer to request 0, 1, ...
  SdoAbort expected;
  std::string abort_frame;
};

class SdoGarbage : public ::testing::TestWithParam<GarbageCase> {};

TEST_P(SdoGarbage, ClientAbortsWithTheRightCode) {
  const GarbageCase& g = GetParam();
  ScriptedNetwork net([&g](const Payload&, std::size_t n) {
    std::vector<can::Frame> out;
    if (n < g.replies.size()) {
      const std::string& text = g.replies[n];
      if (text.empty()) {
        // no answer to this one
      } else if (text.starts_with("short")) {
        out.push_back(can::Frame::standard(0x580 + kNode, {0x43, 0x00, 0x10}));
      } else {
        out.push_back(response(text));
      }
    }
    return out;
  });
  Outcome out;
  Request r = request(0x1000, 0, g.mode);
  r.on_done = out.handler();
  if (g.upload) {
    ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  } else {
    ASSERT_TRUE(net.client->download(r, test::pattern(20), net.clock.now()));
  }
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value());
  EXPECT_EQ(*steps, 0) << "must fail at once, not by timeout";
  EXPECT_EQ(out.result->error, g.expected) << describe(*out.result);
  EXPECT_EQ(out.result->origin, Origin::Local);
  ASSERT_FALSE(net.received.empty());
  EXPECT_EQ(net.received.back(), g.abort_frame);
  EXPECT_FALSE(net.client->busy(kNode));
}

INSTANTIATE_TEST_SUITE_P(
    Responses, SdoGarbage,
    ::testing::Values(
        GarbageCase{"WrongIndexExpedited", true, Mode::Segmented, {"43 01 10 00 01 02 03 04"},
                    SdoAbort::ParameterIncompatible, "80 00 10 00 43 00 04 06"},
        GarbageCase{"WrongSubIndex", true, Mode::Segmented, {"43 00 10 01 01 02 03 04"},
                    SdoAbort::ParameterIncompatible, "80 00 10 00 43 00 04 06"},
        GarbageCase{"WrongIndexDownload", false, Mode::Segmented, {"60 17 10 00 00 00 00 00"},
                    SdoAbort::ParameterIncompatible, "80 00 10 00 43 00 04 06"},
        GarbageCase{"WrongIndexBlockDownload", false, Mode::Block, {"A4 17 10 00 7F 00 00 00"},
                    SdoAbort::ParameterIncompatible, "80 00 10 00 43 00 04 06"},
        GarbageCase{"WrongIndexBlockUpload", true, Mode::Block, {"C6 17 10 00 14 00 00 00"},
                    SdoAbort::ParameterIncompatible, "80 00 10 00 43 00 04 06"},
        GarbageCase{"WrongIndexAfterProtocolSwitch", true, Mode::Auto, {"43 17 10 00 01 02 03 04"},
                    SdoAbort::ParameterIncompatible, "80 00 10 00 43 00 04 06"},
        GarbageCase{"UnknownCommand", true, Mode::Segmented, {"E0 00 10 00 00 00 00 00"},
                    SdoAbort::InvalidCommand, "80 00 10 00 01 00 04 05"},
        GarbageCase{"UnexpectedCommand", false, Mode::Segmented, {"43 00 10 00 00 00 00 00"},
                    SdoAbort::InvalidCommand, "80 00 10 00 01 00 04 05"},
        GarbageCase{"ShortFrame", true, Mode::Segmented, {"short"}, SdoAbort::InvalidCommand,
                    "80 00 10 00 01 00 04 05"},
        GarbageCase{"WrongToggleUpload", true, Mode::Segmented, {"41 00 10 00 0E 00 00 00", "10 01 02 03 04 05 06 07"},
                    SdoAbort::ToggleNotAlternated, "80 00 10 00 00 00 03 05"},
        GarbageCase{"WrongToggleDownload", false, Mode::Segmented, {"60 00 10 00 00 00 00 00", "30 00 00 00 00 00 00 00"},
                    SdoAbort::ToggleNotAlternated, "80 00 10 00 00 00 03 05"},
        GarbageCase{"MoreThanIndicated", true, Mode::Segmented, {"41 00 10 00 03 00 00 00", "00 01 02 03 04 05 06 07"},
                    SdoAbort::LengthMismatch, "80 00 10 00 10 00 07 06"},
        GarbageCase{"LessThanIndicated", true, Mode::Segmented, {"41 00 10 00 09 00 00 00", "01 01 02 03 04 05 06 07"},
                    SdoAbort::LengthMismatch, "80 00 10 00 10 00 07 06"},
        GarbageCase{"UploadTooLarge", true, Mode::Segmented, {"41 00 10 00 00 00 00 40"}, SdoAbort::OutOfMemory,
                    "80 00 10 00 05 00 04 05"},
        GarbageCase{"ServerBlockSizeZero", false, Mode::Block, {"A4 00 10 00 00 00 00 00"},
                    SdoAbort::InvalidBlockSize, "80 00 10 00 02 00 04 05"},
        GarbageCase{"AckSeqBeyondSent", false, Mode::Block, {"A4 00 10 00 7F 00 00 00", "", "", "A2 05 7F 00 00 00 00 00"},
                    SdoAbort::InvalidSequenceNumber, "80 00 10 00 03 00 04 05"},
        GarbageCase{"AckBlockSizeZero", false, Mode::Block, {"A4 00 10 00 7F 00 00 00", "", "", "A2 03 00 00 00 00 00 00"},
                    SdoAbort::InvalidBlockSize, "80 00 10 00 02 00 04 05"},
        GarbageCase{"SegmentSeqnoZero", true, Mode::Block, {"C6 00 10 00 14 00 00 00", "00 01 02 03 04 05 06 07"},
                    SdoAbort::InvalidSequenceNumber, "80 00 10 00 03 00 04 05"},
        GarbageCase{"UploadCrcError", true, Mode::Block,
                    {"C6 00 10 00 02 00 00 00", "81 01 02 00 00 00 00 00", "D5 00 00 00 00 00 00 00"},
                    SdoAbort::CrcError, "80 00 10 00 04 00 04 05"}),
    [](const ::testing::TestParamInfo<GarbageCase>& param_info) { return std::string(param_info.param.name); });

TEST(SdoClient, SilentServerTimesOutExactlyAfterTheConfiguredTime) {
  ClientConfig cfg;
  cfg.default_timeout = 500ms;
  ScriptedNetwork net(nullptr, cfg);
  Outcome out;
  Request r = request(0x1000);
  r.on_done = out.handler();
  const TimePoint start = net.clock.now();
  ASSERT_TRUE(net.client->upload(r, start));
  EXPECT_EQ(net.client->next_deadline(), start + 500ms);
  net.client->on_time(start + 500ms - 1ns);
  EXPECT_FALSE(out.done());
  net.clock.advance(500ms);
  net.client->on_time(net.clock.now());
  ASSERT_TRUE(out.done());
  EXPECT_EQ(out.result->error, SdoAbort::Timeout);
  EXPECT_EQ(out.result->origin, Origin::Local);
  EXPECT_EQ(net.client->next_deadline(), TimePoint::max());
  net.run([] { return false; }, 0);
  ASSERT_EQ(net.received.size(), 2U);
  EXPECT_EQ(net.received[1], "80 00 10 00 00 00 04 05");
}

TEST(SdoClient, ServerFallsSilentInTheMiddle) {
  // Answers the initiate and the first segment, then nothing.
  ScriptedNetwork net([](const Payload&, std::size_t n) {
    std::vector<can::Frame> out;
    if (n == 0) out.push_back(response("41 00 10 00 20 00 00 00"));
    if (n == 1) out.push_back(response("00 01 02 03 04 05 06 07"));
    return out;
  });
  Outcome out;
  Request r = request(0x1000);
  r.mode = Mode::Segmented;
  r.timeout = 300ms;
  r.on_done = out.handler();
  const TimePoint start = net.clock.now();
  ASSERT_TRUE(net.client->upload(r, start));
  const auto steps = net.run([&] { return out.done(); });
  ASSERT_TRUE(steps.has_value());
  EXPECT_EQ(*steps, 1);
  EXPECT_EQ(net.clock.now(), start + 300ms);
  EXPECT_EQ(out.result->error, SdoAbort::Timeout);
}

TEST(SdoClient, TimeoutsPerRequestAndPerNode) {
  ScriptedNetwork net(nullptr);
  net.client->set_node_timeout(kNode, 2s);
  Outcome a, b, c;
  Request ra = request(0x1000);
  ra.on_done = a.handler();
  Request rb = request(0x1001);
  rb.timeout = 100ms;
  rb.on_done = b.handler();
  Request rc = request(0x1002);
  rc.on_done = c.handler();
  const TimePoint start = net.clock.now();
  ASSERT_TRUE(net.client->upload(ra, start));
  ASSERT_TRUE(net.client->upload(rb, start));
  ASSERT_TRUE(net.client->upload(rc, start));
  // Each timer belongs to one transfer and starts with it, not when queued.
  TimePoint at_a, at_b, at_c;
  net.run([&] {
    if (a.done() && at_a == TimePoint{}) at_a = net.clock.now();
    if (b.done() && at_b == TimePoint{}) at_b = net.clock.now();
    if (c.done() && at_c == TimePoint{}) at_c = net.clock.now();
    return c.done();
  });
  EXPECT_EQ(at_a, start + 2s);
  EXPECT_EQ(at_b, start + 2s + 100ms);
  EXPECT_EQ(at_c, start + 4s + 100ms);
}

TEST(SdoClient, FramesWithoutTransferAreIgnored) {
  ScriptedNetwork net(nullptr);
  EXPECT_FALSE(net.client->on_frame(response("43 00 10 00 01 02 03 04"), net.clock.now()));
  EXPECT_FALSE(net.client->on_frame(response("80 00 10 00 00 00 04 05"), net.clock.now()));
  EXPECT_FALSE(net.client->busy(kNode));
}

TEST(SdoClient, FramesOfOtherNodesDoNotDisturb) {
  // While node 5 transfers, frames from node 6 and other ids are not taken.
  ScriptedNetwork net([](const Payload&, std::size_t n) {
    std::vector<can::Frame> out;
    if (n == 0) {
      out.push_back(make_frame(0x586, hex("43 00 10 00 09 09 09 09")));
      out.push_back(make_frame(0x185, hex("43 00 10 00 09 09 09 09")));
      out.push_back(response("43 00 10 00 01 02 03 04"));
    }
    return out;
  });
  Outcome out;
  Request r = request(0x1000);
  r.mode = Mode::Segmented;
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  ASSERT_TRUE(out.result->ok());
  EXPECT_EQ(out.result->data, (Bytes{1, 2, 3, 4}));
}

// A stray abort does not advance the transfer, so it does not restart its timeout.
TEST(SdoClient, StrayAbortDoesNotRestartTheTimeout) {
  ClientConfig cfg;
  cfg.default_timeout = 500ms;
  ScriptedNetwork net(nullptr, cfg);
  Outcome out;
  Request r = request(0x1000, 0, Mode::Segmented);
  r.on_done = out.handler();
  const TimePoint start = net.clock.now();
  ASSERT_TRUE(net.client->upload(r, start));
  EXPECT_TRUE(net.client->on_frame(response("80 01 10 00 00 00 02 06"), start + 400ms));
  EXPECT_FALSE(out.done());
  EXPECT_EQ(net.client->next_deadline(), start + 500ms);
  net.client->on_time(start + 500ms);
  ASSERT_TRUE(out.done());
  EXPECT_EQ(out.result->error, SdoAbort::Timeout) << "not the stray abort's 06020000h";
}

// ---- queueing ------------------------------------------------------------------------------------------------

TEST(SdoClient, QueuedRequestsCompleteInOrder) {
  Network net;
  std::vector<RequestId> order;
  std::vector<RequestId> ids;
  std::vector<Outcome> outs(10);
  for (std::size_t i = 0; i < outs.size(); ++i) {
    // Downloads and uploads of one object alternate: each upload must see
    // the download before it.
    Request r = request(test::kBigDomain);
    r.on_done = [&order, &outs, i](TransferResult&& res) {
      order.push_back(res.id);
      outs[i].result = std::move(res);
    };
    if (i % 2 == 0) {
      auto id = net.client->download(r, test::pattern(100 * i + 1, static_cast<std::uint32_t>(i)), net.clock.now());
      ASSERT_TRUE(id);
      ids.push_back(*id);
    } else {
      auto id = net.client->upload(r, net.clock.now());
      ASSERT_TRUE(id);
      ids.push_back(*id);
    }
  }
  EXPECT_EQ(net.client->pending(kNode), 10U);
  ASSERT_TRUE(net.run([&] { return order.size() == outs.size(); }));
  EXPECT_EQ(order, ids);
  for (std::size_t i = 0; i < outs.size(); ++i) {
    ASSERT_TRUE(outs[i].result->ok()) << i << ": " << describe(*outs[i].result);
    if (i % 2 == 1) {
      EXPECT_EQ(outs[i].result->data, test::pattern(100 * (i - 1) + 1, static_cast<std::uint32_t>(i - 1)));
    }
  }
  EXPECT_EQ(net.client->pending(kNode), 0U);
}

TEST(SdoClient, QueueBoundRefusesWithNoSdoConnection) {
  ClientConfig cfg;
  cfg.queue_limit = 2;
  Network net(cfg);
  Request r = request(test::kDeviceType);
  EXPECT_TRUE(net.client->upload(r, net.clock.now()));  // running
  EXPECT_TRUE(net.client->upload(r, net.clock.now()));  // waiting 1
  EXPECT_TRUE(net.client->upload(r, net.clock.now()));  // waiting 2
  const auto refused = net.client->upload(r, net.clock.now());
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.code(), SdoAbort::NoSdoConnection);
  EXPECT_EQ(refused.code().value(), 0x060A0023);
  EXPECT_FALSE(refused.error().detail.empty());
  EXPECT_EQ(net.client->pending(kNode), 3U);
  // Other nodes have their own queue.
  Request other = r;
  other.node = 6;
  EXPECT_TRUE(net.client->upload(other, net.clock.now()));
}

TEST(SdoClient, ManyCallersQueuedFromCompletionHandlers) {
  Network net;
  int done = 0;
  std::function<void(TransferResult&&)> again;
  again = [&](TransferResult&& res) {
    EXPECT_TRUE(res.ok());
    if (++done < 5) {
      Request r = request(test::kDeviceType);
      r.on_done = again;
      EXPECT_TRUE(net.client->upload(r, net.clock.now()));
    }
  };
  Request r = request(test::kDeviceType);
  r.on_done = again;
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return done == 5; }));
}

TEST(SdoClient, TwoNodesTransferConcurrently) {
  Network net;
  od::ObjectDictionary od6 = test::make_test_dictionary();
  auto ep6 = net.bus.attach("server6");
  ServerConfig cfg6;
  cfg6.node_id = 6;
  SdoServer server6(od6, cfg6, [&](const can::Frame& f) { ep6->send(f); });
  ep6->on_frames([&](std::span<const can::Frame> fs) {
    for (const auto& f : fs) server6.on_frame(f, net.clock.now());
  });
  const Bytes big = test::pattern(65537);
  ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, big)));
  Outcome on5, on6;
  Request r5 = request(test::kBigDomain, 0, Mode::Segmented);
  r5.on_done = on5.handler();
  Request r6 = request(test::kString, 0, Mode::Segmented);
  r6.node = 6;
  r6.on_done = on6.handler();
  ASSERT_TRUE(net.client->upload(r5, net.clock.now()));
  ASSERT_TRUE(net.client->upload(r6, net.clock.now()));
  EXPECT_TRUE(net.client->busy(5));
  EXPECT_TRUE(net.client->busy(6));
  // Node 6 finishes long before node 5's 9363 segments.
  for (int i = 0; i < 20 && !on6.done(); ++i) net.bus.deliver_one();
  EXPECT_TRUE(on6.done());
  EXPECT_FALSE(on5.done());
  ASSERT_TRUE(net.run([&] { return on5.done(); }));
  ASSERT_TRUE(on5.result->ok());
  ASSERT_TRUE(on6.result->ok());
  EXPECT_TRUE(on5.result->data == big);
  EXPECT_EQ(std::string(on6.result->data.begin(), on6.result->data.end()), "hello world!");
}

// ---- cancellation --------------------------------------------------------------------------------------------

TEST(SdoClient, CancelQueuedRequest) {
  Network net;
  Outcome first, second;
  Request r1 = request(test::kDeviceType);
  r1.on_done = first.handler();
  Request r2 = request(test::kHeartbeat);
  r2.on_done = second.handler();
  ASSERT_TRUE(net.client->upload(r1, net.clock.now()));
  const auto id2 = net.client->upload(r2, net.clock.now());
  ASSERT_TRUE(id2);
  EXPECT_TRUE(net.client->cancel(*id2, net.clock.now()));
  ASSERT_TRUE(second.done());  // inside cancel()
  EXPECT_TRUE(second.result->cancelled);
  EXPECT_EQ(second.result->error, SdoAbort::GeneralError);
  EXPECT_EQ(second.result->origin, Origin::Local);
  EXPECT_FALSE(net.client->cancel(*id2, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return first.done(); }));
  EXPECT_TRUE(first.result->ok());
  net.bus.deliver();
  for (const auto& req : net.requests()) EXPECT_FALSE(req.starts_with("A4 17 10")) << "cancelled request was sent";
}

TEST(SdoClient, CancelRunningRequestAbortsOnTheBus) {
  Network net;
  Outcome out;
  Request r = request(test::kBigDomain, 0, Mode::Block);
  r.on_done = out.handler();
  net.log_limit = 100000;
  const auto id = net.client->download(r, test::pattern(65537), net.clock.now());
  ASSERT_TRUE(id);
  net.bus.deliver(300);  // some sub-blocks in
  ASSERT_FALSE(out.done());
  EXPECT_EQ(net.server->state(), SdoServer::State::BlockDownloadSubBlock);
  EXPECT_TRUE(net.client->cancel(*id, net.clock.now()));
  ASSERT_TRUE(out.done());
  EXPECT_TRUE(out.result->cancelled);
  EXPECT_EQ(out.result->error, SdoAbort::GeneralError);
  EXPECT_FALSE(net.client->busy(kNode));
  net.log.clear();
  net.bus.deliver();
  EXPECT_EQ(net.requests().back(), "80 05 20 00 00 00 00 08");
  EXPECT_EQ(net.server->state(), SdoServer::State::Idle);
  EXPECT_TRUE(test::domain_bytes(net.od, test::kBigDomain).empty());
  EXPECT_FALSE(net.client->cancel(*id, net.clock.now()));
  EXPECT_FALSE(net.client->cancel(12345, net.clock.now()));
}

// ---- progress ------------------------------------------------------------------------------------------------

TEST(SdoClient, ProgressOfALongBlockDownload) {
  Network net;
  const std::size_t size = 65537;
  std::vector<std::pair<std::size_t, std::optional<std::size_t>>> reports;
  Outcome out;
  Request r = request(test::kBigDomain);
  r.on_progress = [&](std::size_t done, std::optional<std::size_t> total) { reports.emplace_back(done, total); };
  r.on_done = [&](TransferResult&& res) {
    EXPECT_FALSE(reports.empty());
    EXPECT_EQ(reports.back().first, size) << "the last report comes before completion";
    out.result = std::move(res);
  };
  ASSERT_TRUE(net.client->download(r, test::pattern(size), net.clock.now()));
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  ASSERT_TRUE(out.result->ok());
  ASSERT_GE(reports.size(), 10U);
  EXPECT_LE(reports.size(), 20U);  // every 4096 bytes, not every frame
  for (std::size_t i = 0; i < reports.size(); ++i) {
    EXPECT_EQ(reports[i].second, size);
    if (i > 0) {
      EXPECT_GT(reports[i].first, reports[i - 1].first);
    }
  }
  EXPECT_EQ(reports.back().first, size);
}

TEST(SdoClient, ProgressOfASegmentedUploadKnowsTheTotal) {
  ClientConfig cfg;
  cfg.progress_step = 1000;
  Network net(cfg);
  const Bytes data = test::pattern(10000);
  ASSERT_FALSE(net.od.set(test::kBigDomain, 0, Value::of_bytes(DataType::Domain, data)));
  std::vector<std::pair<std::size_t, std::optional<std::size_t>>> reports;
  Outcome out;
  Request r = request(test::kBigDomain, 0, Mode::Segmented);
  r.on_progress = [&](std::size_t done, std::optional<std::size_t> total) { reports.emplace_back(done, total); };
  r.on_done = out.handler();
  ASSERT_TRUE(net.client->upload(r, net.clock.now()));
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  ASSERT_TRUE(out.result->ok());
  ASSERT_GE(reports.size(), 10U);
  EXPECT_EQ(reports.front().second, data.size());
  EXPECT_EQ(reports.back(), std::make_pair(data.size(), std::optional<std::size_t>(data.size())));
}

TEST(SdoClient, CancelFromTheProgressHandler) {
  Network net;
  Outcome out;
  RequestId id = 0;
  int calls = 0;
  Request r = request(test::kBigDomain, 0, Mode::Block);
  r.on_progress = [&](std::size_t, std::optional<std::size_t>) {
    if (++calls == 2) net.client->cancel(id, net.clock.now());
  };
  r.on_done = out.handler();
  const auto res = net.client->download(r, test::pattern(65537), net.clock.now());
  ASSERT_TRUE(res);
  id = *res;
  ASSERT_TRUE(net.run([&] { return out.done(); }));
  EXPECT_TRUE(out.result->cancelled);
  EXPECT_EQ(calls, 2);
  net.settle();
  EXPECT_EQ(net.server->state(), SdoServer::State::Idle);
}

}  // namespace
}  // namespace canopen::sdo
