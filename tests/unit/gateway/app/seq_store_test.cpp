// SeqStore: the per-network seq kept in the state directory across restarts
// (issue 12 item 4) without a write per event.
#include "app/seq_store.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <string>

#include "unit/gateway/mqtt/mqtt_support.hpp"

namespace gateway {
namespace {

using mqtt_test::TempDir;
using namespace std::chrono_literals;

// A fixed wall clock: 2026-01-01T00:00:00Z.
const std::chrono::system_clock::time_point kWall = std::chrono::system_clock::from_time_t(1'767'225'600);
SeqStore::WallClock wall() {
  return [] { return kWall; };
}
std::uint64_t wall_us() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(kWall.time_since_epoch()).count());
}

std::string content(const std::filesystem::path& f) {
  std::ifstream in(f);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write(const std::filesystem::path& f, const std::string& text) { std::ofstream(f) << text; }

TEST(SeqStore, WithoutADirectoryEveryRunStartsAtOne) {
  SeqStore s({}, 1);
  const auto o = s.open();
  EXPECT_EQ(o.first, 1U);
  EXPECT_TRUE(o.note.empty());
  EXPECT_FALSE(s.use(5'000'000));
}

// No file (first start, or a version that kept none): the wall clock in
// microseconds, which no earlier run can have reached; said in the log.
TEST(SeqStore, WithoutAFileTheSequenceStartsAtTheWallClock) {
  TempDir dir;
  SeqStore s(dir.path(), 2, 100, wall());
  const auto o = s.open();
  EXPECT_EQ(o.first, wall_us());
  EXPECT_FALSE(o.corrupt);
  EXPECT_NE(o.note.find("seq-net2"), std::string::npos) << o.note;
  EXPECT_FALSE(o.error);
  EXPECT_EQ(content(dir.path() / "seq-net2"), std::to_string(wall_us() + 100) + "\n") << "a block reserved at once";
}

TEST(SeqStore, AfterACleanStopTheNextRunGoesOnWithoutAGap) {
  TempDir dir;
  std::uint64_t last = 0;
  {
    SeqStore s(dir.path(), 1, 100, wall());
    const auto first = s.open().first;
    for (last = first; last < first + 250; ++last) ASSERT_FALSE(s.use(last));
    --last;
    ASSERT_FALSE(s.close(last + 1));
  }
  SeqStore again(dir.path(), 1, 100, wall());
  const auto o = again.open();
  EXPECT_EQ(o.first, last + 1);
  EXPECT_TRUE(o.note.empty()) << o.note;
}

// A crash (no close): the next run starts at the reserved bound, above every
// number used, with a gap of at most one block; the file was written once
// per block, not per event (flash wear).
TEST(SeqStore, AfterACrashNumbersNeverRepeatAndTheFileIsWrittenOncePerBlock) {
  TempDir dir;
  constexpr std::uint64_t kBlock = 16;
  std::uint64_t last = 0;
  std::set<std::string> stored;
  {
    SeqStore s(dir.path(), 1, kBlock, wall());
    const auto first = s.open().first;
    stored.insert(content(s.file()));
    for (std::uint64_t seq = first; seq < first + 5 * kBlock; ++seq) {
      ASSERT_FALSE(s.use(seq));
      ASSERT_LT(seq, s.reserved()) << "used beyond the durable bound";
      stored.insert(content(s.file()));
      last = seq;
    }
  }  // no close(): the process died
  EXPECT_EQ(stored.size(), 5U) << "one write at start and one at each of the 4 block boundaries passed";
  SeqStore again(dir.path(), 1, kBlock, wall());
  const auto o = again.open();
  EXPECT_GT(o.first, last);
  EXPECT_LE(o.first, last + kBlock + 1);
}

TEST(SeqStore, AnUnreadableFileDoesNotStopTheStartAndTakesTheWallClock) {
  for (const std::string bad : {"", "abc\n", "12x\n", "0\n", "123", "99999999999999999999999\n"}) {
    TempDir dir;
    write(dir.path() / "seq-net1", bad);
    SeqStore s(dir.path(), 1, 100, wall());
    const auto o = s.open();
    EXPECT_EQ(o.first, wall_us()) << "'" << bad << "'";
    EXPECT_TRUE(o.corrupt) << "'" << bad << "'";
    EXPECT_NE(o.note.find("unreadable"), std::string::npos) << o.note;
    EXPECT_EQ(content(s.file()), std::to_string(wall_us() + 100) + "\n") << "repaired";
  }
}

// A failing disk costs one attempt per block, not one per event, and the
// numbers still go on.
TEST(SeqStore, AnUnwritableDirectoryIsReportedOncePerBlock) {
  TempDir dir;
  write(dir.path() / "file", "x");
  SeqStore s(dir.path() / "file", 1, 10, wall());  // ENOTDIR
  const auto o = s.open();
  EXPECT_TRUE(o.error);
  int errors = 0;
  for (std::uint64_t seq = o.first; seq < o.first + 100; ++seq) errors += s.use(seq) ? 1 : 0;
  EXPECT_EQ(errors, 9) << "one attempt at each of the 9 block boundaries passed, not one per event";
  EXPECT_TRUE(s.close(o.first + 100));
}

}  // namespace
}  // namespace gateway
