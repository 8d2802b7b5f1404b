// Tests for stack/src/can/tx_queue.cpp: the bounded, order-preserving
// transmit queue, in particular its behaviour when the device queue is full
// (ENOBUFS), the socket would block (EAGAIN) or the link is down.
#include "canopen/can/tx_queue.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <algorithm>
#include <deque>
#include <span>
#include <functional>
#include <vector>

namespace canopen::can {
namespace {

using std::chrono::milliseconds;

Frame numbered(std::uint16_t n) {
  return Frame::standard(0x180U + (n % 0x80U), {static_cast<std::uint8_t>(n & 0xFF), static_cast<std::uint8_t>(n >> 8)});
}

std::uint16_t number_of(const Frame& f) {
  return static_cast<std::uint16_t>(f.data[0] | (f.data[1] << 8));
}

// A writer scripted with results; after the script it accepts everything.
// Records every frame it accepted, in order, and every attempt.
struct FakeWriter {
  std::deque<WriteResult> script;
  std::vector<Frame> accepted;
  std::vector<Frame> attempts;

  WriteResult operator()(const Frame& f) {
    attempts.push_back(f);
    WriteResult r = WriteResult::Written;
    if (!script.empty()) {
      r = script.front();
      script.pop_front();
    }
    if (r == WriteResult::Written) accepted.push_back(f);
    return r;
  }

  void then(WriteResult r, int times = 1) {
    for (int i = 0; i < times; ++i) script.push_back(r);
  }

  std::vector<std::uint16_t> accepted_numbers() const {
    std::vector<std::uint16_t> v;
    for (const auto& f : accepted) v.push_back(number_of(f));
    return v;
  }
};

std::vector<std::uint16_t> range(std::uint16_t from, std::uint16_t to) {
  std::vector<std::uint16_t> v;
  for (std::uint16_t i = from; i < to; ++i) v.push_back(i);
  return v;
}

TEST(TxQueue, EmptyQueueFlushesAsDrainedWithoutCallingWriter) {
  TxQueue q(8);
  FakeWriter w;
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_TRUE(w.attempts.empty());
  EXPECT_TRUE(q.empty());
}

TEST(TxQueue, FlushWritesAllFramesInOrder) {
  TxQueue q(16);
  for (std::uint16_t i = 0; i < 10; ++i) ASSERT_TRUE(q.push(numbered(i)));
  EXPECT_EQ(q.size(), 10U);
  FakeWriter w;
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_EQ(w.accepted_numbers(), range(0, 10));
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.written(), 10U);
  EXPECT_EQ(q.dropped(), 0U);
  EXPECT_EQ(q.failed(), 0U);
  EXPECT_EQ(q.retries(), 0U);
}

TEST(TxQueue, FramesArePassedToWriterUnchanged) {
  TxQueue q(4);
  std::vector<std::uint8_t> bytes(64, 0x5A);
  Frame fd = Frame::extended_id(0x1FFFFFFF, bytes);
  fd.set(FrameFlag::BitRateSwitch);
  q.push(fd);
  q.push(Frame::rtr(0x123, 8));
  FakeWriter w;
  q.flush(std::ref(w));
  ASSERT_EQ(w.accepted.size(), 2U);
  EXPECT_EQ(w.accepted[0], fd);
  EXPECT_EQ(w.accepted[1], Frame::rtr(0x123, 8));
}

// The scenario: the device queue is full for a while (ENOBUFS), then
// drains. Every frame must go out exactly once and in order.
TEST(TxQueue, NoBuffersThenAcceptPreservesOrderAndLosesNothing) {
  TxQueue q(64);
  for (std::uint16_t i = 0; i < 20; ++i) ASSERT_TRUE(q.push(numbered(i)));
  FakeWriter w;
  w.then(WriteResult::Written, 5);
  w.then(WriteResult::NoBuffers, 4);

  int flushes = 0;
  FlushResult r = FlushResult::NoBuffers;
  while ((r = q.flush(std::ref(w))) == FlushResult::NoBuffers) {
    ++flushes;
    ASSERT_LT(flushes, 100);
    EXPECT_EQ(q.size(), 20U - 5U) << "a refused frame must stay queued";
    EXPECT_EQ(number_of(w.attempts.back()), 5) << "retry starts at the refused frame";
  }
  EXPECT_EQ(r, FlushResult::Drained);
  EXPECT_EQ(flushes, 4);
  EXPECT_EQ(w.accepted_numbers(), range(0, 20));
  EXPECT_EQ(q.written(), 20U);
  EXPECT_EQ(q.dropped(), 0U);
  EXPECT_EQ(q.failed(), 0U);
  EXPECT_EQ(q.retries(), 4U);
  EXPECT_TRUE(q.empty());
}

TEST(TxQueue, NoBuffersStopsFlushAndKeepsFrameAtHead) {
  TxQueue q(8);
  q.push(numbered(1));
  q.push(numbered(2));
  FakeWriter w;
  w.then(WriteResult::NoBuffers);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::NoBuffers);
  EXPECT_EQ(w.attempts.size(), 1U) << "flush must stop at the first NoBuffers";
  EXPECT_EQ(q.size(), 2U);
  q.flush(std::ref(w));
  EXPECT_EQ(w.accepted_numbers(), (std::vector<std::uint16_t>{1, 2}));
}

TEST(TxQueue, RetryDelayStartsAtFirstRetry) {
  TxQueue q(8);
  EXPECT_EQ(q.retry_delay(), milliseconds(1));
  q.push(numbered(0));
  FakeWriter w;
  w.then(WriteResult::NoBuffers);
  q.flush(std::ref(w));
  EXPECT_EQ(q.retry_delay(), milliseconds(1));
}

TEST(TxQueue, RetryDelayDoublesOnConsecutiveNoBuffersUpToMax) {
  TxQueue q(8, milliseconds(1), milliseconds(32));
  q.push(numbered(0));
  FakeWriter w;
  w.then(WriteResult::NoBuffers, 9);
  std::vector<milliseconds> delays;
  for (int i = 0; i < 9; ++i) {
    ASSERT_EQ(q.flush(std::ref(w)), FlushResult::NoBuffers);
    delays.push_back(std::chrono::duration_cast<milliseconds>(q.retry_delay()));
  }
  const std::vector<milliseconds> want{milliseconds(1),  milliseconds(2),  milliseconds(4),
                                       milliseconds(8),  milliseconds(16), milliseconds(32),
                                       milliseconds(32), milliseconds(32), milliseconds(32)};
  EXPECT_EQ(delays, want);
  EXPECT_EQ(q.retries(), 9U);
}

TEST(TxQueue, RetryDelayIsCappedAtMaxThatIsNotAPowerOfTwoMultiple) {
  TxQueue q(8, milliseconds(1), milliseconds(5));
  q.push(numbered(0));
  FakeWriter w;
  w.then(WriteResult::NoBuffers, 5);
  std::vector<milliseconds> delays;
  for (int i = 0; i < 5; ++i) {
    q.flush(std::ref(w));
    delays.push_back(std::chrono::duration_cast<milliseconds>(q.retry_delay()));
  }
  EXPECT_EQ(delays, (std::vector<milliseconds>{milliseconds(1), milliseconds(2), milliseconds(4), milliseconds(5),
                                               milliseconds(5)}));
}

TEST(TxQueue, RetryDelayStaysCappedAfterManyNoBuffers) {
  TxQueue q(8, milliseconds(1), milliseconds(32));
  q.push(numbered(0));
  FakeWriter w;
  w.then(WriteResult::NoBuffers, 200);
  for (int i = 0; i < 200; ++i) q.flush(std::ref(w));
  EXPECT_EQ(q.retry_delay(), milliseconds(32));
}

TEST(TxQueue, SuccessfulWriteResetsBackOff) {
  TxQueue q(8, milliseconds(1), milliseconds(32));
  for (std::uint16_t i = 0; i < 3; ++i) q.push(numbered(i));
  FakeWriter w;
  w.then(WriteResult::NoBuffers, 3);  // 1, 2, 4 ms
  w.then(WriteResult::Written);       // frame 0 goes out
  w.then(WriteResult::NoBuffers);     // frame 1 refused: back to 1 ms
  for (int i = 0; i < 3; ++i) q.flush(std::ref(w));
  EXPECT_EQ(q.retry_delay(), milliseconds(4));
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::NoBuffers);
  EXPECT_EQ(q.retry_delay(), milliseconds(1));
  w.then(WriteResult::NoBuffers);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::NoBuffers);
  EXPECT_EQ(q.retry_delay(), milliseconds(2));
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_EQ(w.accepted_numbers(), (std::vector<std::uint16_t>{0, 1, 2}));
}

TEST(TxQueue, CustomFirstRetryIsHonoured) {
  TxQueue q(8, milliseconds(3), milliseconds(20));
  EXPECT_EQ(q.retry_delay(), milliseconds(3));
  q.push(numbered(0));
  FakeWriter w;
  w.then(WriteResult::NoBuffers, 4);
  std::vector<milliseconds> delays;
  for (int i = 0; i < 4; ++i) {
    q.flush(std::ref(w));
    delays.push_back(std::chrono::duration_cast<milliseconds>(q.retry_delay()));
  }
  EXPECT_EQ(delays, (std::vector<milliseconds>{milliseconds(3), milliseconds(6), milliseconds(12), milliseconds(20)}));
}

TEST(TxQueue, BoundedCapacityRejectsAndCountsDrops) {
  TxQueue q(3);
  EXPECT_EQ(q.capacity(), 3U);
  EXPECT_TRUE(q.push(numbered(0)));
  EXPECT_TRUE(q.push(numbered(1)));
  EXPECT_TRUE(q.push(numbered(2)));
  EXPECT_FALSE(q.push(numbered(3)));
  EXPECT_FALSE(q.push(numbered(4)));
  EXPECT_EQ(q.size(), 3U);
  EXPECT_EQ(q.dropped(), 2U);
  FakeWriter w;
  q.flush(std::ref(w));
  EXPECT_EQ(w.accepted_numbers(), (std::vector<std::uint16_t>{0, 1, 2})) << "rejected frames never go out";
}

TEST(TxQueue, FullQueueAcceptsAgainAfterFlush) {
  TxQueue q(2);
  q.push(numbered(0));
  q.push(numbered(1));
  EXPECT_FALSE(q.push(numbered(2)));
  FakeWriter w;
  q.flush(std::ref(w));
  EXPECT_TRUE(q.push(numbered(3)));
  q.flush(std::ref(w));
  EXPECT_EQ(w.accepted_numbers(), (std::vector<std::uint16_t>{0, 1, 3}));
}

TEST(TxQueue, QueueFillsWhileDeviceRefusesThenDrainsInOrder) {
  TxQueue q(5);
  FakeWriter w;
  w.then(WriteResult::NoBuffers, 3);
  std::uint16_t next = 0;
  std::vector<std::uint16_t> pushed;
  // The application keeps sending while the device queue is full.
  for (int round = 0; round < 3; ++round) {
    for (int k = 0; k < 3; ++k) {
      if (q.push(numbered(next))) pushed.push_back(next);
      ++next;
    }
    EXPECT_EQ(q.flush(std::ref(w)), FlushResult::NoBuffers);
  }
  EXPECT_EQ(q.size(), 5U);
  EXPECT_EQ(q.dropped(), 4U);
  EXPECT_EQ(q.high_water(), 5U);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_EQ(w.accepted_numbers(), pushed);
  EXPECT_EQ(pushed, range(0, 5));
}

TEST(TxQueue, HighWaterTracksDeepestQueue) {
  TxQueue q(10);
  for (std::uint16_t i = 0; i < 4; ++i) q.push(numbered(i));
  FakeWriter w;
  q.flush(std::ref(w));
  q.push(numbered(9));
  EXPECT_EQ(q.size(), 1U);
  EXPECT_EQ(q.high_water(), 4U);
}

TEST(TxQueue, WouldBlockKeepsFrameAtHead) {
  TxQueue q(8);
  q.push(numbered(0));
  q.push(numbered(1));
  q.push(numbered(2));
  FakeWriter w;
  w.then(WriteResult::Written);
  w.then(WriteResult::WouldBlock);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::WouldBlock);
  EXPECT_EQ(q.size(), 2U);
  EXPECT_EQ(q.retries(), 1U);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_EQ(w.accepted_numbers(), (std::vector<std::uint16_t>{0, 1, 2}));
  ASSERT_EQ(w.attempts.size(), 4U);
  EXPECT_EQ(number_of(w.attempts[1]), 1);
  EXPECT_EQ(number_of(w.attempts[2]), 1);
}

TEST(TxQueue, WouldBlockDoesNotChangeNoBuffersBackOff) {
  TxQueue q(8);
  q.push(numbered(0));
  FakeWriter w;
  w.then(WriteResult::NoBuffers);
  w.then(WriteResult::WouldBlock);
  w.then(WriteResult::NoBuffers);
  q.flush(std::ref(w));
  q.flush(std::ref(w));
  q.flush(std::ref(w));
  EXPECT_EQ(q.retry_delay(), milliseconds(2)) << "WouldBlock is not a successful write";
}

TEST(TxQueue, LinkDownKeepsFrameAtHead) {
  TxQueue q(8);
  q.push(numbered(0));
  q.push(numbered(1));
  FakeWriter w;
  w.then(WriteResult::LinkDown, 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(q.flush(std::ref(w)), FlushResult::LinkDown);
    EXPECT_EQ(q.size(), 2U);
  }
  EXPECT_EQ(q.written(), 0U);
  EXPECT_EQ(q.dropped(), 0U);
  EXPECT_EQ(q.failed(), 0U);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_EQ(w.accepted_numbers(), (std::vector<std::uint16_t>{0, 1}));
}

TEST(TxQueue, FailedDropsOnlyThatFrameAndContinues) {
  TxQueue q(8);
  for (std::uint16_t i = 0; i < 4; ++i) q.push(numbered(i));
  FakeWriter w;
  w.then(WriteResult::Written);
  w.then(WriteResult::Failed);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_EQ(w.accepted_numbers(), (std::vector<std::uint16_t>{0, 2, 3}));
  EXPECT_EQ(q.failed(), 1U);
  EXPECT_EQ(q.written(), 3U);
  EXPECT_EQ(q.dropped(), 0U);
  EXPECT_EQ(w.attempts.size(), 4U) << "a failed frame is not retried";
}

TEST(TxQueue, EveryFrameFailingEmptiesQueue) {
  TxQueue q(8);
  for (std::uint16_t i = 0; i < 5; ++i) q.push(numbered(i));
  FakeWriter w;
  w.then(WriteResult::Failed, 5);
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.failed(), 5U);
  EXPECT_EQ(q.written(), 0U);
}

TEST(TxQueue, ClearDiscardsAndCountsAsDropped) {
  TxQueue q(8);
  for (std::uint16_t i = 0; i < 3; ++i) q.push(numbered(i));
  q.push(numbered(3));
  q.clear();
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.dropped(), 4U);
  FakeWriter w;
  EXPECT_EQ(q.flush(std::ref(w)), FlushResult::Drained);
  EXPECT_TRUE(w.attempts.empty());
}

TEST(TxQueue, MixedResultsLongRunLosesNothingAndKeepsOrder) {
  TxQueue q(1000);
  for (std::uint16_t i = 0; i < 500; ++i) ASSERT_TRUE(q.push(numbered(i)));
  FakeWriter w;
  // A repeating pattern of temporary refusals between successful writes.
  const WriteResult pattern[] = {WriteResult::Written,   WriteResult::NoBuffers, WriteResult::Written,
                                 WriteResult::WouldBlock, WriteResult::Written,   WriteResult::NoBuffers,
                                 WriteResult::NoBuffers, WriteResult::LinkDown,  WriteResult::Written};
  for (int k = 0; k < 200; ++k) {
    for (WriteResult r : pattern) w.then(r);
  }
  int flushes = 0;
  while (q.flush(std::ref(w)) != FlushResult::Drained) ASSERT_LT(++flushes, 10000);
  EXPECT_EQ(w.accepted_numbers(), range(0, 500));
  EXPECT_EQ(q.written(), 500U);
  EXPECT_EQ(q.dropped(), 0U);
  EXPECT_EQ(q.failed(), 0U);
}

TEST(TxQueue, WriterCanBeALambda) {
  TxQueue q(4);
  q.push(numbered(1));
  int calls = 0;
  EXPECT_EQ(q.flush([&](const Frame&) {
    ++calls;
    return WriteResult::Written;
  }),
            FlushResult::Drained);
  EXPECT_EQ(calls, 1);
}

TEST(TxQueue, ReportedRetryDelayResetsAfterSuccessfulWrite) {
  TxQueue q(8, milliseconds(1), milliseconds(32));
  FakeWriter w;
  w.then(WriteResult::NoBuffers, 3);
  q.push(numbered(0));
  q.push(numbered(1));
  for (int i = 0; i < 3; ++i) ASSERT_EQ(q.flush(w), FlushResult::NoBuffers);
  EXPECT_EQ(q.retry_delay(), milliseconds(4));
  ASSERT_EQ(q.flush(w), FlushResult::Drained);
  EXPECT_EQ(q.retry_delay(), milliseconds(1));
}

// ---- flush_batch: runs of frames for sendmmsg ---------------------------------

// A batch writer scripted with (how many it takes, why it stops).
struct FakeBatchWriter {
  std::deque<BatchWrite> script;
  std::vector<std::uint16_t> accepted;
  std::vector<std::size_t> offered_sizes;

  BatchWrite operator()(std::span<const Frame> run) {
    offered_sizes.push_back(run.size());
    BatchWrite r{run.size(), WriteResult::Written};
    if (!script.empty()) {
      r = script.front();
      script.pop_front();
      r.written = std::min(r.written, run.size());
    }
    for (std::size_t i = 0; i < r.written; ++i) accepted.push_back(number_of(run[i]));
    return r;
  }
};

TEST(TxQueueBatch, RunsAreContiguousAndRespectMaxBatch) {
  TxQueue q(100);
  for (std::uint16_t i = 0; i < 10; ++i) q.push(numbered(i));
  FakeBatchWriter w;
  EXPECT_EQ(q.flush_batch(w, 4), FlushResult::Drained);
  EXPECT_EQ(w.accepted, range(0, 10));
  EXPECT_EQ(w.offered_sizes, (std::vector<std::size_t>{4, 4, 2}));
  EXPECT_EQ(q.written(), 10U);
}

TEST(TxQueueBatch, RingWrapAroundKeepsOrder) {
  TxQueue q(8);
  FakeBatchWriter w;
  for (std::uint16_t i = 0; i < 6; ++i) q.push(numbered(i));
  // Four go out, then the device is full: frames 4 and 5 stay at slots 4-5.
  w.script.push_back({4, WriteResult::Written});
  w.script.push_back({0, WriteResult::NoBuffers});
  ASSERT_EQ(q.flush_batch(w, 64), FlushResult::NoBuffers);
  // Six more fill slots 6-7 and wrap around to 0-3.
  for (std::uint16_t i = 6; i < 12; ++i) ASSERT_TRUE(q.push(numbered(i)));
  EXPECT_FALSE(q.push(numbered(99))) << "capacity is still 8";
  w.offered_sizes.clear();
  ASSERT_EQ(q.flush_batch(w, 64), FlushResult::Drained);
  EXPECT_EQ(w.accepted, range(0, 12));
  EXPECT_EQ(w.offered_sizes, (std::vector<std::size_t>{4, 4})) << "slots 4-7, then 0-3 after the wrap";
}

TEST(TxQueueBatch, PartialWriteOffersTheRestAgain) {
  TxQueue q(16);
  for (std::uint16_t i = 0; i < 10; ++i) q.push(numbered(i));
  FakeBatchWriter w;
  w.script.push_back({3, WriteResult::Written});  // sendmmsg sent 3, no error reported
  EXPECT_EQ(q.flush_batch(w, 64), FlushResult::Drained);
  EXPECT_EQ(w.accepted, range(0, 10));
}

TEST(TxQueueBatch, NoBuffersMidRunKeepsUnsentFramesInOrder) {
  TxQueue q(16, milliseconds(1), milliseconds(32));
  for (std::uint16_t i = 0; i < 10; ++i) q.push(numbered(i));
  FakeBatchWriter w;
  w.script.push_back({4, WriteResult::Written});
  w.script.push_back({0, WriteResult::NoBuffers});
  EXPECT_EQ(q.flush_batch(w, 64), FlushResult::NoBuffers);
  EXPECT_EQ(q.size(), 6U);
  EXPECT_EQ(q.retry_delay(), milliseconds(1));
  EXPECT_EQ(q.flush_batch(w, 64), FlushResult::Drained);
  EXPECT_EQ(w.accepted, range(0, 10)) << "nothing lost, nothing reordered";
  EXPECT_EQ(q.dropped(), 0U);
}

TEST(TxQueueBatch, FailedDropsOnlyTheFrameThatFailed) {
  TxQueue q(16);
  for (std::uint16_t i = 0; i < 5; ++i) q.push(numbered(i));
  FakeBatchWriter w;
  w.script.push_back({2, WriteResult::Failed});  // frame 2 can never be sent
  EXPECT_EQ(q.flush_batch(w, 64), FlushResult::Drained);
  EXPECT_EQ(w.accepted, (std::vector<std::uint16_t>{0, 1, 3, 4}));
  EXPECT_EQ(q.failed(), 1U);
}

TEST(TxQueueBatch, WriterTakingNothingWithoutErrorIsTreatedAsBlocked) {
  TxQueue q(4);
  q.push(numbered(0));
  FakeBatchWriter w;
  w.script.push_back({0, WriteResult::Written});
  EXPECT_EQ(q.flush_batch(w, 64), FlushResult::WouldBlock);
  EXPECT_EQ(q.size(), 1U);
}

TEST(TxQueueBatch, LinkDownStopsWithFramesKept) {
  TxQueue q(4);
  q.push(numbered(0));
  q.push(numbered(1));
  FakeBatchWriter w;
  w.script.push_back({0, WriteResult::LinkDown});
  EXPECT_EQ(q.flush_batch(w, 64), FlushResult::LinkDown);
  EXPECT_EQ(q.size(), 2U);
}

}  // namespace
}  // namespace canopen::can
