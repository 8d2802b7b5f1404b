#include "mqtt/disk_queue.hpp"

#include <gtest/gtest.h>

#include <boost/crc.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <sys/mount.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "mqtt_support.hpp"  // TempDir

namespace fs = std::filesystem;
using gateway::mqtt::DiskQueue;
using gateway::mqtt::DiskQueueOptions;
using gateway::mqtt::QueuedMessage;
using mqtt_test::TempDir;

namespace {

QueuedMessage msg(int i, std::uint8_t qos = 1, bool retained = false) {
  return QueuedMessage{"t/" + std::to_string(i), "payload-" + std::to_string(i), qos, retained};
}

DiskQueueOptions opts(const fs::path& dir) {
  DiskQueueOptions o;
  o.dir = dir;
  return o;
}

std::vector<fs::path> segments(const fs::path& dir) {
  std::vector<fs::path> out;
  for (auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".seg") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// Offsets of the records in a segment file (as written: [u32 length][u32
// CRC][body]).
std::vector<std::size_t> record_offsets(const fs::path& seg) {
  std::ifstream f(seg, std::ios::binary);
  std::string data((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::vector<std::size_t> out;
  std::size_t at = 0;
  while (at + 8 <= data.size()) {
    std::uint32_t len = 0;
    for (int i = 0; i < 4; ++i) len |= std::uint32_t{static_cast<unsigned char>(data[at + static_cast<std::size_t>(i)])} << (8 * i);
    out.push_back(at);
    at += 8 + len;
  }
  return out;
}

void poke(const fs::path& file, std::size_t offset, char value) {
  std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  f.put(value);
}

char peek_byte(const fs::path& file, std::size_t offset) {
  std::ifstream f(file, std::ios::binary);
  f.seekg(static_cast<std::streamoff>(offset));
  return static_cast<char>(f.get());
}

// Drains everything next() hands out, acking each.
std::vector<std::string> drain_all(DiskQueue& q, bool ack = true) {
  std::vector<std::string> out;
  DiskQueue::Item it;
  while (q.next(it)) {
    out.push_back(it.msg.payload);
    if (ack) q.ack(it.seq);
  }
  return out;
}

}  // namespace

TEST(DiskQueue, KeepsOrderAndFields) {
  TempDir d;
  DiskQueue q(opts(d.path()));
  q.push(msg(1, 1, true));
  q.push(msg(2, 0, false));
  q.push(QueuedMessage{"t/empty", "", 1, false});
  DiskQueue::Item it;
  ASSERT_TRUE(q.next(it));
  EXPECT_EQ(it.msg.topic, "t/1");
  EXPECT_EQ(it.msg.payload, "payload-1");
  EXPECT_EQ(it.msg.qos, 1);
  EXPECT_TRUE(it.msg.retained);
  ASSERT_TRUE(q.next(it));
  EXPECT_EQ(it.msg.topic, "t/2");
  EXPECT_EQ(it.msg.qos, 0);
  EXPECT_FALSE(it.msg.retained);
  ASSERT_TRUE(q.next(it));
  EXPECT_EQ(it.msg.payload, "");
  EXPECT_FALSE(q.next(it));
  EXPECT_EQ(q.depth(), 3u);
  EXPECT_EQ(q.counters().written, 3u);
}

TEST(DiskQueue, RewindResendsUnackedInOrder) {
  TempDir d;
  DiskQueue q(opts(d.path()));
  for (int i = 0; i < 5; ++i) q.push(msg(i));
  DiskQueue::Item it;
  std::vector<std::uint64_t> seqs;
  while (q.next(it)) seqs.push_back(it.seq);
  ASSERT_EQ(seqs.size(), 5u);
  EXPECT_TRUE(q.ack(seqs[0]));
  EXPECT_TRUE(q.ack(seqs[2]));  // out of order: head stays at seqs[1]
  EXPECT_FALSE(q.ack(seqs[2]));  // idempotent
  EXPECT_EQ(q.head_seq(), seqs[1]);
  q.rewind();
  EXPECT_EQ(drain_all(q, false), (std::vector<std::string>{"payload-1", "payload-3", "payload-4"}));
  EXPECT_EQ(q.counters().acked, 2u);
  EXPECT_EQ(q.depth(), 3u);
}

TEST(DiskQueue, DropsOldestQos0FirstThenOldestQos1) {
  TempDir d;
  auto o = opts(d.path());
  o.max_messages = 4;
  DiskQueue q(o);
  q.push(msg(1, 1));
  q.push(msg(2, 0));
  q.push(msg(3, 1));
  q.push(msg(4, 0));
  q.push(msg(5, 1));  // full: drops 2 (oldest QoS 0)
  q.push(msg(6, 1));  // drops 4
  q.push(msg(7, 1));  // no QoS 0 left: drops 1 (oldest QoS 1)
  EXPECT_EQ(q.counters().dropped_qos0, 2u);
  EXPECT_EQ(q.counters().dropped_qos1, 1u);
  EXPECT_EQ(q.depth(), 4u);
  EXPECT_EQ(drain_all(q), (std::vector<std::string>{"payload-3", "payload-5", "payload-6", "payload-7"}));
  EXPECT_EQ(q.depth(), 0u);
}

TEST(DiskQueue, ByteBoundAndTooBig) {
  TempDir d;
  auto o = opts(d.path());
  o.max_bytes = 1000;
  DiskQueue q(o);
  const std::string big(300, 'x');
  for (int i = 0; i < 10; ++i) q.push(QueuedMessage{"t", big + std::to_string(i), 1, false});
  EXPECT_LE(q.counters().bytes, 1000u);
  EXPECT_EQ(q.depth(), 3u);  // 3 x ~322 bytes fit
  EXPECT_EQ(q.counters().dropped_qos1, 7u);
  EXPECT_EQ(q.push(QueuedMessage{"t", std::string(2000, 'y'), 1, false}), 0u);
  EXPECT_EQ(q.counters().dropped_too_big, 1u);
  auto got = drain_all(q);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got.back(), big + "9");
}

TEST(DiskQueue, ReopenAfterCleanCloseReplaysUnacked) {
  TempDir d;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < 10; ++i) q.push(msg(i));
    DiskQueue::Item it;
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(q.next(it));
      q.ack(it.seq);
    }
  }
  DiskQueue q(opts(d.path()));
  EXPECT_EQ(q.counters().replayed, 6u);
  EXPECT_EQ(q.depth(), 6u);
  q.push(msg(10));
  auto got = drain_all(q);
  ASSERT_EQ(got.size(), 7u);
  EXPECT_EQ(got.front(), "payload-4");
  EXPECT_EQ(got.back(), "payload-10");
}

TEST(DiskQueue, AckPositionPersistsAcrossReopens) {
  TempDir d;
  std::uint64_t last_seq = 0;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < 3; ++i) q.push(msg(i));
    drain_all(q);  // all acked
  }
  {
    DiskQueue q(opts(d.path()));
    EXPECT_EQ(q.depth(), 0u);
    DiskQueue::Item it;
    EXPECT_FALSE(q.next(it));
    last_seq = q.push(msg(3));
    EXPECT_EQ(last_seq, 4u);  // numbering continues
  }
  DiskQueue q(opts(d.path()));
  EXPECT_EQ(drain_all(q), (std::vector<std::string>{"payload-3"}));
}

TEST(DiskQueue, TornLastRecordIsTruncated) {
  TempDir d;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < 5; ++i) q.push(msg(i));
  }
  auto segs = segments(d.path());
  ASSERT_EQ(segs.size(), 1u);
  const auto size = fs::file_size(segs[0]);
  fs::resize_file(segs[0], size - 5);  // cut into the last record
  {
    DiskQueue q(opts(d.path()));
    EXPECT_EQ(q.depth(), 4u);
    EXPECT_GT(q.counters().truncated_bytes, 0u);
    q.push(msg(99));  // appends after the cut
  }
  DiskQueue q(opts(d.path()));
  EXPECT_EQ(q.counters().truncated_bytes, 0u);
  EXPECT_EQ(drain_all(q), (std::vector<std::string>{"payload-0", "payload-1", "payload-2", "payload-3", "payload-99"}));
}

// A damaged last record cannot be told from a torn write: it is cut.
TEST(DiskQueue, CorruptLastRecordIsCutLikeATornTail) {
  TempDir d;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < 5; ++i) q.push(msg(i));
  }
  auto seg = segments(d.path()).at(0);
  {
    std::fstream f(seg, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-3, std::ios::end);  // flip a payload byte of the last record
    f.put('#');
  }
  DiskQueue q(opts(d.path()));
  EXPECT_EQ(q.depth(), 4u);
  EXPECT_GT(q.counters().truncated_bytes, 0u);
}

TEST(DiskQueue, GarbageTailAndTornAckFile) {
  TempDir d;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < 3; ++i) q.push(msg(i));
    DiskQueue::Item it;
    ASSERT_TRUE(q.next(it));
    q.ack(it.seq);  // position 2, slot 1
    ASSERT_TRUE(q.next(it));
    q.ack(it.seq);  // position 3, slot 0
  }
  {
    std::ofstream f(segments(d.path()).at(0), std::ios::app | std::ios::binary);
    f << std::string("\xff\xff\xff\x7f garbage", 12);
  }
  {
    // A torn write of the newest slot: the older one (position 2) is used,
    // so message 1 comes again (a duplicate, never a loss).
    std::fstream f(d.path() / "acked", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(10);
    f.put('\x55');
  }
  DiskQueue q(opts(d.path()));
  EXPECT_EQ(drain_all(q), (std::vector<std::string>{"payload-1", "payload-2"}));
}

// A process that dies without running any destructor (as kill -9) loses
// nothing it pushed: the records are in the page cache.
TEST(DiskQueue, ProcessDeathWithoutCleanupLosesNothing) {
  TempDir d;
  pid_t pid = ::fork();
  if (pid == 0) {
    auto* q = new DiskQueue(opts(d.path()));  // never deleted: no close, no sync
    for (int i = 0; i < 500; ++i) q->push(msg(i));
    DiskQueue::Item it;
    for (int i = 0; i < 100; ++i) {
      if (!q->next(it)) ::_exit(3);
      q->ack(it.seq);
    }
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 0);
  DiskQueue q(opts(d.path()));
  auto got = drain_all(q);
  ASSERT_EQ(got.size(), 400u);
  EXPECT_EQ(got.front(), "payload-100");
  EXPECT_EQ(got.back(), "payload-499");
}

// Buffered writes (as MqttPublisher uses them): records reach the file at
// flush() (or when the buffer fills), the ack position at flush(true) or
// sync(); next() hands out records before they are written.
namespace {
// Runs `child` in a process that then dies without cleanup; returns what a
// new queue on the directory hands out.
template <class F>
std::vector<std::string> after_death(const fs::path& dir, F child) {
  pid_t pid = ::fork();
  if (pid == 0) {
    auto o = opts(dir);
    o.buffered_writes = true;
    auto* q = new DiskQueue(o);  // never deleted: no close, no sync
    child(*q);
    ::_exit(0);
  }
  int status = 0;
  EXPECT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  DiskQueue q(opts(dir));
  return drain_all(q);
}
}  // namespace

TEST(DiskQueue, BufferedWritesReachTheFileOnFlush) {
  {
    TempDir d;
    auto got = after_death(d.path(), [](DiskQueue& q) {
      for (int i = 0; i < 500; ++i) q.push(msg(i));
      DiskQueue::Item it;
      for (int i = 0; i < 100; ++i) {
        if (!q.next(it) || it.msg.payload != "payload-" + std::to_string(i)) ::_exit(3);  // from memory
        q.ack(it.seq);
      }
      if (!q.flush_pending()) ::_exit(4);
      q.flush();  // records only: the acked 100 come again
      if (q.flush_pending()) ::_exit(5);
    });
    ASSERT_EQ(got.size(), 500u);
    EXPECT_EQ(got.front(), "payload-0");
    EXPECT_EQ(got.back(), "payload-499");
  }
  {
    TempDir d;
    auto got = after_death(d.path(), [](DiskQueue& q) {
      for (int i = 0; i < 500; ++i) q.push(msg(i));
      DiskQueue::Item it;
      for (int i = 0; i < 100; ++i) {
        if (!q.next(it)) ::_exit(3);
        q.ack(it.seq);
      }
      q.flush(true);  // and the position
      q.push(msg(500));  // not flushed: lost with the process
    });
    ASSERT_EQ(got.size(), 400u);
    EXPECT_EQ(got.front(), "payload-100");
    EXPECT_EQ(got.back(), "payload-499");
  }
}

TEST(DiskQueue, BufferedWritesFlushWhenTheBufferFillsAndAcrossSegments) {
  TempDir d;
  constexpr int kN = 20'000;
  auto got = after_death(d.path(), [](DiskQueue& q) {
    for (int i = 0; i < kN; ++i) q.push(msg(i));  // ~570 KB: many buffer flushes
  });
  // Whatever reached the file is an in-order prefix, missing at most one
  // buffer's worth (64 KiB, < 3000 records).
  ASSERT_GT(got.size(), static_cast<std::size_t>(kN - 3000));
  for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], "payload-" + std::to_string(i));

  TempDir d2;
  auto o = opts(d2.path());
  o.buffered_writes = true;
  o.segment_bytes = 4096;
  {
    DiskQueue q(o);
    for (int i = 0; i < 1000; ++i) q.push(msg(i));
    EXPECT_GT(segments(d2.path()).size(), 5u);
    DiskQueue::Item it;
    for (int i = 0; i < 300; ++i) {
      ASSERT_TRUE(q.next(it));
      ASSERT_EQ(it.msg.payload, "payload-" + std::to_string(i));
      q.ack(it.seq);
    }
    q.rewind();
    ASSERT_TRUE(q.next(it));
    EXPECT_EQ(it.msg.payload, "payload-300");
  }  // the destructor flushes records and position
  DiskQueue q(o);
  auto rest = drain_all(q);
  ASSERT_EQ(rest.size(), 700u);
  EXPECT_EQ(rest.front(), "payload-300");
  EXPECT_EQ(rest.back(), "payload-999");
}

TEST(DiskQueue, SegmentsRollAndAreDeletedWhenAcked) {
  TempDir d;
  auto o = opts(d.path());
  o.segment_bytes = 4096;
  DiskQueue q(o);
  for (int i = 0; i < 1000; ++i) q.push(msg(i));
  EXPECT_GT(segments(d.path()).size(), 5u);
  auto got = drain_all(q);
  ASSERT_EQ(got.size(), 1000u);
  q.push(msg(1000));  // rolls past the last full segment
  DiskQueue::Item it;
  ASSERT_TRUE(q.next(it));
  q.ack(it.seq);
  EXPECT_LE(segments(d.path()).size(), 2u);
  EXPECT_LT(q.counters().disk_bytes, 2u * 4096u);
}

TEST(DiskQueue, DiskSpanStaysBoundedBehindAnOldQos1) {
  TempDir d;
  auto o = opts(d.path());
  o.max_bytes = 8192;
  o.segment_bytes = 4096;
  DiskQueue q(o);
  q.push(msg(0, 1));  // stays unacked at the head
  DiskQueue::Item first;
  ASSERT_TRUE(q.next(first));
  for (int i = 1; i < 5000; ++i) q.push(msg(i, 0));  // QoS 0 flood, dropped behind it
  EXPECT_LE(q.counters().disk_bytes, 2u * 8192u + 2u * 4096u);
  EXPECT_GT(q.counters().dropped_span, 0u);
}

TEST(DiskQueue, LargeVolumeAcrossReopen) {
  TempDir d;
  constexpr int kN = 100'000;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < kN; ++i) q.push(msg(i, i % 3 == 0 ? 0 : 1));
    // Ack the first half in order.
    DiskQueue::Item it;
    for (int i = 0; i < kN / 2; ++i) {
      ASSERT_TRUE(q.next(it));
      ASSERT_EQ(it.msg.payload, "payload-" + std::to_string(i));
      q.ack(it.seq);
    }
    q.sync();
  }
  DiskQueue q(opts(d.path()));
  EXPECT_EQ(q.depth(), static_cast<std::uint64_t>(kN / 2));
  DiskQueue::Item it;
  for (int i = kN / 2; i < kN; ++i) {
    ASSERT_TRUE(q.next(it));
    ASSERT_EQ(it.msg.payload, "payload-" + std::to_string(i));
    ASSERT_EQ(it.msg.qos, i % 3 == 0 ? 0 : 1);
    q.ack(it.seq);
  }
  EXPECT_FALSE(q.next(it));
  EXPECT_EQ(q.depth(), 0u);
  EXPECT_EQ(q.counters().dropped(), 0u);
}

TEST(DiskQueue, RefusesUnusableDirectory) {
  EXPECT_THROW(DiskQueue(opts("/proc/self/no-such-dir/q")), std::system_error);
}

// The record CRC is the standard CRC-32 (boost::crc_32_type's value), so
// queue files written by earlier versions stay readable: checked on records
// of all lengths around the 8-byte steps of the fast implementation.
TEST(DiskQueue, RecordCrcIsStandardCrc32) {
  TempDir dir;
  std::vector<std::string> payloads;
  {
    DiskQueue q(opts(dir.path()));
    for (int n = 0; n < 40; ++n) {
      std::string p;
      for (int i = 0; i < n * 7; ++i) p.push_back(static_cast<char>((i * 131 + n) & 0xFF));
      q.push(QueuedMessage{"t/crc", p, 1, false});
      payloads.push_back(p);
    }
  }
  auto segs = segments(dir.path());
  ASSERT_FALSE(segs.empty());
  std::ifstream f(segs.front(), std::ios::binary);
  std::string data((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  auto le32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= std::uint32_t{static_cast<unsigned char>(data[at + static_cast<std::size_t>(i)])} << (8 * i);
    return v;
  };
  std::size_t at = 0, records = 0;
  while (at + 8 <= data.size()) {
    const std::uint32_t len = le32(at);
    ASSERT_LE(at + 8 + len, data.size());
    boost::crc_32_type c;
    c.process_bytes(data.data() + at + 8, len);
    EXPECT_EQ(le32(at + 4), c.checksum()) << "record " << records;
    at += 8 + len;
    ++records;
  }
  EXPECT_EQ(records, payloads.size());
  DiskQueue q(opts(dir.path()));
  EXPECT_EQ(drain_all(q), payloads);
}

// ---- Corruption (issue 12, item 3) -----------------------------------------

// One flipped byte in the middle of a segment costs that one record, not
// the backlog behind it: replay skips it and resynchronises on the next.
TEST(DiskQueue, FlippedByteInTheMiddleKeepsTheRecordsAfterIt) {
  TempDir d;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < 30; ++i) q.push(msg(i));
  }
  const auto seg = segments(d.path()).at(0);
  const auto offs = record_offsets(seg);
  ASSERT_EQ(offs.size(), 30u);
  const std::size_t topic_byte = offs[10] + 8 + 12;  // header, then seq, qos, flags, topic length
  poke(seg, topic_byte, static_cast<char>(peek_byte(seg, topic_byte) ^ 0x10));
  DiskQueue q(opts(d.path()));
  std::vector<std::string> want;
  for (int i = 0; i < 30; ++i)
    if (i != 10) want.push_back("payload-" + std::to_string(i));
  EXPECT_EQ(drain_all(q), want);
  EXPECT_EQ(q.counters().corrupt_records, 1u);
  EXPECT_EQ(q.counters().corrupt_bytes, offs[11] - offs[10]);
  EXPECT_EQ(q.counters().truncated_bytes, 0u);
  const auto warnings = q.take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("skipped"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("1 messages lost"), std::string::npos) << warnings[0];
  EXPECT_TRUE(q.take_warnings().empty());  // taken once
}

// A damaged length field (the record claims to run past the file, or into
// the next records) is skipped the same way; so is damage in an older
// segment, whose later records and the following segments all survive.
TEST(DiskQueue, DamagedLengthsAndOlderSegmentsResynchronise) {
  TempDir d;
  auto o = opts(d.path());
  o.segment_bytes = 4096;
  {
    DiskQueue q(o);
    for (int i = 0; i < 500; ++i) q.push(msg(i));
  }
  const auto segs = segments(d.path());
  ASSERT_GE(segs.size(), 3u);
  const auto first_offs = record_offsets(segs[0]);
  poke(segs[0], first_offs[5] + 2, '\x7f');  // record 5's length: far too long
  const auto second_offs = record_offsets(segs[1]);
  poke(segs[1], second_offs[3], static_cast<char>(peek_byte(segs[1], second_offs[3]) + 1));  // off by one
  DiskQueue q(o);
  const auto got = drain_all(q);
  EXPECT_EQ(got.size(), 498u);
  EXPECT_EQ(q.counters().corrupt_records, 2u);
  EXPECT_EQ(got.back(), "payload-499");
  for (std::size_t i = 1; i < got.size(); ++i)
    ASSERT_LT(std::stoi(got[i - 1].substr(8)), std::stoi(got[i].substr(8)));  // in order
  EXPECT_EQ(q.take_warnings().size(), 2u);
}

// Names the queue did not write are ignored with a warning, never fatal
// (a 20-digit name over 2^64 stopped start-up with "stoull").
TEST(DiskQueue, StrayNamesAreIgnoredWithAWarning) {
  TempDir d;
  {
    DiskQueue q(opts(d.path()));
    for (int i = 0; i < 5; ++i) q.push(msg(i));
  }
  std::ofstream(d.path() / "foo") << "x";
  std::ofstream(d.path() / "99999999999999999999.seg") << "not a segment";
  std::ofstream(d.path() / "x.seg") << "nor this";
  fs::create_directory(d.path() / "00000000000000000007.seg");
  DiskQueue q(opts(d.path()));
  EXPECT_EQ(q.counters().ignored_files, 4u);
  const auto warnings = q.take_warnings();
  ASSERT_EQ(warnings.size(), 4u);
  for (const char* name : {"'foo'", "'99999999999999999999.seg'", "'x.seg'", "directory '00000000000000000007.seg'"})
    EXPECT_TRUE(std::any_of(warnings.begin(), warnings.end(),
                            [&](const std::string& w) { return w.find(name) != std::string::npos; }))
        << name;
  EXPECT_EQ(drain_all(q), (std::vector<std::string>{"payload-0", "payload-1", "payload-2", "payload-3", "payload-4"}));
  q.push(msg(5));  // and it keeps working
  EXPECT_TRUE(fs::exists(d.path() / "foo"));  // not its to delete

  // A directory holding the very name the next segment needs: that number
  // is skipped, nothing is refused.
  TempDir d2;
  fs::create_directories(d2.path() / "00000000000000000001.seg");
  {
    DiskQueue q2(opts(d2.path()));
    EXPECT_NE(q2.push(msg(0)), 0u);
    EXPECT_FALSE(q2.storage_error());
  }
  DiskQueue q2(opts(d2.path()));
  EXPECT_EQ(drain_all(q2), (std::vector<std::string>{"payload-0"}));
}

// ---- Syncing (issue 12, item 1) --------------------------------------------

// fdatasync only for durable records: a queue that only holds non-durable
// ones (spilled `outage` messages) never syncs; a durable one is synced
// once, and the position once the head passed it.
TEST(DiskQueue, SyncsOnlyDurableData) {
  TempDir d;
  DiskQueue q(opts(d.path()));
  for (int i = 0; i < 100; ++i) q.push(msg(i, 0), false);
  q.sync();
  drain_all(q);
  q.sync();
  EXPECT_EQ(q.counters().syncs, 0u);
  EXPECT_GT(q.counters().storage_bytes, 0u);  // written, though

  q.push(msg(100, 1), true);
  q.sync();
  EXPECT_EQ(q.counters().syncs, 1u);
  q.sync();
  EXPECT_EQ(q.counters().syncs, 1u);  // nothing new
  drain_all(q);
  q.sync();
  EXPECT_EQ(q.counters().syncs, 2u);  // the position, moved over a durable record
}

// ---- A full file system (issue 12, item 2) ---------------------------------

namespace {

// A tmpfs of `size` mounted on a fresh directory (needs root, as in CI).
class SmallFs {
 public:
  explicit SmallFs(const std::string& options) {
    if (::mount("tmpfs", dir_.path().c_str(), "tmpfs", 0, options.c_str()) != 0)
      error_ = std::string("cannot mount a tmpfs (") + std::strerror(errno) + "; needs root)";
  }
  ~SmallFs() {
    if (error_.empty()) ::umount2(dir_.path().c_str(), MNT_DETACH);
  }
  const std::string& error() const { return error_; }
  fs::path path() const { return dir_.path(); }
  // Fills the file system with a file of zeros until a write fails.
  void fill() {
    std::FILE* f = std::fopen((dir_.path() / "filler").c_str(), "wb");
    static const char block[4096] = {};
    while (std::fwrite(block, 1, sizeof block, f) == sizeof block) {
    }
    std::fclose(f);
  }

 private:
  TempDir dir_;
  std::string error_;
};

}  // namespace

// The queue fills the disk: no exception, the backlog is kept, new messages
// that cannot be stored are refused (counted), and once acked space is
// freed the queue writes again by itself.
TEST(DiskQueue, FullDiskRefusesNewMessagesKeepsTheBacklogAndRecovers) {
  for (bool buffered : {false, true}) {
    SCOPED_TRACE(buffered ? "buffered" : "write-through");
    SmallFs small("size=128k");
    if (!small.error().empty()) GTEST_SKIP() << small.error();
    auto o = opts(small.path() / "q");
    o.segment_bytes = 16384;
    o.buffered_writes = buffered;
    o.write_buffer_bytes = 4096;
    std::vector<std::string> accepted;
    {
      DiskQueue q(o);
      int i = 0;
      for (; i < 20000; ++i) {
        const std::string payload(200, static_cast<char>('a' + i % 26));
        if (q.push(QueuedMessage{"t/" + std::to_string(i), payload, 1, false}) != 0) accepted.push_back("t/" + std::to_string(i));
        if (buffered) q.flush();
        if (q.counters().dropped_full >= 100) break;
      }
      ASSERT_GE(q.counters().dropped_full, 100u) << "the disk never filled";
      EXPECT_TRUE(q.storage_error());
      EXPECT_EQ(q.storage_error(), std::errc::no_space_on_device);
      EXPECT_GT(q.counters().write_errors, 0u);
      // Everything accepted is there, in order (unwritten records from memory).
      DiskQueue::Item it;
      std::vector<std::string> got;
      while (q.next(it)) {
        got.push_back(it.msg.topic);
        q.ack(it.seq);
      }
      EXPECT_EQ(got, accepted);
      // All acked: the segments are deleted even though the disk was full,
      // and the queue writes again; the episode ends with the first write.
      q.sync();
      EXPECT_LE(segments(o.dir).size(), 1u);
      const std::uint64_t refused = q.counters().dropped_full;
      for (int j = 0; j < 50; ++j) ASSERT_NE(q.push(QueuedMessage{"after", std::to_string(j), 1, false}), 0u);
      q.sync();
      EXPECT_EQ(q.counters().dropped_full, refused);
      EXPECT_FALSE(q.storage_error()) << q.storage_error().message();
    }
    DiskQueue q(o);  // and what it wrote after the episode is there
    EXPECT_EQ(q.depth(), 50u);
  }
}

// Acked segments are freed even while the position cannot be written (the
// disk was full when the queue opened, so the position file has no block);
// nothing acked comes back after a reopen once it could be written.
TEST(DiskQueue, AckedSegmentsAreFreedWhenThePositionCannotBeWritten) {
  SmallFs small("size=256k");
  if (!small.error().empty()) GTEST_SKIP() << small.error();
  auto o = opts(small.path() / "q");
  o.segment_bytes = 8192;
  fs::create_directories(o.dir);
  small.fill();
  DiskQueue q(o);  // its position file gets no block
  // Room for segments only: 64 KiB of the filler go.
  fs::resize_file(small.path() / "filler", fs::file_size(small.path() / "filler") - (64u << 10));
  int pushed = 0;
  while (q.push(QueuedMessage{"t", std::string(100, 'p'), 1, false}) != 0) ++pushed;
  ASSERT_GT(pushed, 100);
  const auto segs_full = segments(o.dir).size();
  ASSERT_GE(segs_full, 4u);
  const auto errors = q.counters().write_errors;
  DiskQueue::Item it;
  while (q.next(it)) q.ack(it.seq);  // the position write fails: no room
  EXPECT_GT(q.counters().write_errors, errors);
  EXPECT_TRUE(q.storage_error());
  EXPECT_LE(segments(o.dir).size(), 1u) << "fully acked segments must go even though the position could not be written";
  EXPECT_NE(q.push(QueuedMessage{"t", "after", 1, false}), 0u);  // room again
  q.sync();
  EXPECT_FALSE(q.storage_error()) << q.storage_error().message();
  DiskQueue::Item last;
  ASSERT_TRUE(q.next(last));
  EXPECT_EQ(last.msg.payload, "after");
}

// Creating a new segment fails (no inodes left): the push is refused, the
// queue goes on, and once the old segment is acked and deleted, creating
// works again.
TEST(DiskQueue, SegmentCreationFailureIsNotFatal) {
  SmallFs small("size=1m,nr_inodes=16");
  if (!small.error().empty()) GTEST_SKIP() << small.error();
  auto o = opts(small.path() / "q");
  o.segment_bytes = 4096;
  DiskQueue q(o);
  ASSERT_NE(q.push(msg(0)), 0u);  // the first segment exists
  for (int i = 0; i < 16; ++i) std::ofstream(small.path() / ("spare" + std::to_string(i))) << "x";  // no inode left
  int pushed = 1;
  while (q.push(msg(pushed)) != 0) ++pushed;
  EXPECT_GT(pushed, 10);
  EXPECT_TRUE(q.storage_error());
  EXPECT_EQ(q.counters().dropped_full, 1u);
  EXPECT_EQ(drain_all(q).size(), static_cast<std::size_t>(pushed));
  EXPECT_NE(q.push(msg(1000)), 0u);  // the acked segment made way
  q.sync();
  EXPECT_FALSE(q.storage_error()) << q.storage_error().message();
}
