// BdSeqStore: bdSeq goes up by one with every CONNECT and is kept in
// state-dir, across restarts and kill -9 (contract "Sparkplug B"; facts A.5,
// spec ch4 [tck-id-topics-nbirth-bdseq-increment]).
#include "sparkplug/bdseq_store.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include "unit/gateway/sparkplug/sparkplug_support.hpp"

namespace gateway::sparkplug {
namespace {

using sparkplug_test::TempDir;

std::string content(const std::filesystem::path& f) {
  std::ifstream in(f);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(BdSeqStore, FirstConnectIsZeroAndEachConnectAddsOne) {
  TempDir dir;
  BdSeqStore s(dir.path());
  EXPECT_FALSE(s.current());
  const auto a = s.next();
  EXPECT_EQ(a.bd_seq, 0);
  EXPECT_TRUE(a.note.empty());
  EXPECT_FALSE(a.error);
  EXPECT_EQ(s.next().bd_seq, 1);
  EXPECT_EQ(s.current(), 1);
  EXPECT_EQ(content(dir.path() / "sparkplug-bdseq"), "1\n");
}

// A restart goes on from the last CONNECT: hosts and the TCK flag an edge
// node whose bdSeq begins at 0 again (facts A.5, sparkplug#425).
TEST(BdSeqStore, ARestartContinuesFromTheLastConnect) {
  TempDir dir;
  {
    BdSeqStore s(dir.path());
    s.next();
    s.next();
    s.next();
  }
  BdSeqStore again(dir.path());
  EXPECT_EQ(again.next().bd_seq, 3);
}

// kill -9 right after the value was stored (the CONNECT carrying it as the
// Will may be at the broker): the next process must not reuse it.
TEST(BdSeqStore, AKillAfterTheConnectNeverReusesItsBdSeq) {
  TempDir dir;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    BdSeqStore s(dir.path());
    s.next();
    s.next();  // 1: this run's CONNECT
    ::kill(::getpid(), SIGKILL);
    ::_exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  BdSeqStore after(dir.path());
  EXPECT_EQ(after.next().bd_seq, 2);
}

// A crash in the middle of a write leaves the temp file: the stored value
// is still the old one (rename is atomic), and the temp file is harmless.
TEST(BdSeqStore, AHalfWrittenTempFileDoesNotCount) {
  TempDir dir;
  {
    BdSeqStore s(dir.path());
    s.next();
    s.next();
  }
  std::ofstream(dir.path() / "sparkplug-bdseq.tmp") << "20";
  BdSeqStore s(dir.path());
  EXPECT_EQ(s.next().bd_seq, 2);
  EXPECT_EQ(content(dir.path() / "sparkplug-bdseq"), "2\n");
}

// Spec ch4: 255 wraps to 0.
TEST(BdSeqStore, WrapsFrom255ToZero) {
  TempDir dir;
  std::ofstream(dir.path() / "sparkplug-bdseq") << "255\n";
  BdSeqStore s(dir.path());
  EXPECT_EQ(s.next().bd_seq, 0);
  EXPECT_EQ(s.next().bd_seq, 1);
}

TEST(BdSeqStore, AnUnreadableFileStartsAtZeroAndSaysSo) {
  TempDir dir;
  std::ofstream(dir.path() / "sparkplug-bdseq") << "300\n";
  BdSeqStore s(dir.path());
  const auto n = s.next();
  EXPECT_EQ(n.bd_seq, 0);
  EXPECT_NE(n.note.find("sparkplug-bdseq"), std::string::npos) << n.note;
  EXPECT_EQ(content(dir.path() / "sparkplug-bdseq"), "0\n");
}

TEST(BdSeqStore, AnUnwritableDirectoryIsReportedAndTheValueStillUsed) {
  BdSeqStore s("/nonexistent-spb-dir");
  const auto n = s.next();
  EXPECT_EQ(n.bd_seq, 0);
  EXPECT_TRUE(n.error);
  EXPECT_EQ(s.next().bd_seq, 1);
}

TEST(BdSeqStore, WithoutADirectoryNothingIsKept) {
  BdSeqStore s({});
  EXPECT_EQ(s.next().bd_seq, 0);
  EXPECT_EQ(s.next().bd_seq, 1);
  EXPECT_FALSE(s.next().error);
}

}  // namespace
}  // namespace gateway::sparkplug
