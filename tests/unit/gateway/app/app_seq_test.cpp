// The gateway's event seq across a restart of the App with the same state
// directory (issue 12 item 4; api-contract: seq "continues across restarts,
// kept in state-dir"): after a clean stop it goes on without a gap, after a
// crash it never repeats a number.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <memory>
#include <vector>

#include "app/app.hpp"
#include "app/seq_store.hpp"
#include "unit/gateway/mqtt/mqtt_support.hpp"

namespace gateway {
namespace {

using namespace std::chrono_literals;

// One run of the gateway on the demo network with `state_dir`.
struct GatewayRun {
  explicit GatewayRun(const std::filesystem::path& state_dir) {
    CliOptions cli;
    cli.demo = true;
    cli.gateway_id = "test";
    Config c = merge(Config{}, cli);
    c.state_dir = state_dir.string();
    app = std::make_unique<App>(io, c, log);
    app->add_consumer([this](const EncodedEventPtr& ev) {
      if (ev->network == 1) seqs.push_back(ev->seq);
    });
    app->start();
  }
  // Runs the loop until network 1 has had `n` events.
  bool events(std::size_t n) {
    const auto end = std::chrono::steady_clock::now() + 10s;
    while (seqs.size() < n && std::chrono::steady_clock::now() < end) io.run_for(10ms);
    return seqs.size() >= n;
  }

  boost::asio::io_context io;
  Logger log{LogLevel::Error};
  std::vector<std::uint64_t> seqs;  // network 1, in order; outlives app (its stop() still emits)
  std::unique_ptr<App> app;
};

TEST(AppSeq, AfterACleanStopTheSequenceGoesOnWithoutAGap) {
  mqtt_test::TempDir state;
  std::uint64_t last = 0;
  {
    GatewayRun first(state.path());
    ASSERT_TRUE(first.events(20));
    first.app->stop();  // its last event: the bus going down
    for (std::size_t i = 1; i < first.seqs.size(); ++i) ASSERT_EQ(first.seqs[i], first.seqs[i - 1] + 1);
    last = first.seqs.back();
  }
  GatewayRun second(state.path());
  ASSERT_TRUE(second.events(1));
  EXPECT_EQ(second.seqs.front(), last + 1);
}

// kill -9 in the middle of a run: the next run's numbers are all new.
TEST(AppSeq, AfterACrashNoNumberComesAgain) {
  mqtt_test::TempDir state;
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(fds[0]);
    std::uint64_t seen[2] = {0, 0};  // first and last seq
    {
      GatewayRun run(state.path());
      if (run.events(20)) {
        seen[0] = run.seqs.front();
        seen[1] = run.seqs.back();
      }
      (void)!::write(fds[1], seen, sizeof seen);
      ::kill(::getpid(), SIGKILL);  // no stop, no destructor
    }
    ::_exit(1);
  }
  ::close(fds[1]);
  std::uint64_t seen[2] = {0, 0};
  const auto got = ::read(fds[0], seen, sizeof seen);
  ::close(fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_EQ(got, static_cast<ssize_t>(sizeof seen));
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_GT(seen[1], 0U) << "the crashed run had no events";

  GatewayRun next(state.path());
  ASSERT_TRUE(next.events(1));
  EXPECT_GT(next.seqs.front(), seen[1]) << "a number of the crashed run again";
  EXPECT_LE(next.seqs.front(), seen[0] + SeqStore::kDefaultBlock) << "the gap is at most the reserved block";
}

}  // namespace
}  // namespace gateway
