// Fuzzes the MQTT disk queue's replay (issue 27 item 11): the input is a
// segment file as a crash, a bad sector or a wrong tool could leave it
// (its first bytes: where it starts in the sequence), replayed by opening
// a DiskQueue on it. Invariants: nothing crashes or throws; what is handed
// out comes in increasing sequence order, within the segment's sequence
// range, as many as depth() says; the queue then takes a new message,
// hands it out last, and a second open (a restart) finds it again after
// the same replayed ones.
// fuzz-libs: gateway_mqtt
// fuzz-seeds: tests/fuzz/corpus/disk_queue
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "mqtt/disk_queue.hpp"
#include "mqtt/disk_queue_format.hpp"

namespace mq = gateway::mqtt;
namespace fs = std::filesystem;

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "invariant broken: %s\n", what);
    std::abort();
  }
}

struct Seen {
  std::vector<std::uint64_t> seqs;
  std::vector<std::string> topics;
};

Seen drain(mq::DiskQueue& q) {
  Seen s;
  mq::DiskQueue::Item item;
  while (q.next(item)) {
    check(s.seqs.empty() || item.seq > s.seqs.back(), "handed out in increasing sequence order");
    s.seqs.push_back(item.seq);
    s.topics.push_back(item.msg.topic);
  }
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  // The segment's first sequence number: 1..256 (its name says it).
  const std::uint64_t first = 1 + data[0];
  static const fs::path dir = [] {
    char tmpl[] = "/tmp/fuzz-disk-queue-XXXXXX";
    const char* d = ::mkdtemp(tmpl);
    check(d != nullptr, "a scratch directory");
    return fs::path(d);
  }();
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) fs::remove_all(e.path(), ec);
  {
    std::ofstream out(dir / mq::disk_format::segment_name(first), std::ios::binary);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  mq::DiskQueueOptions o;
  o.dir = dir;
  o.max_bytes = 1u << 20;
  o.segment_bytes = 1u << 16;
  try {
    Seen replayed;
    {
      mq::DiskQueue q(o);
      (void)q.take_warnings();
      const std::uint64_t depth = q.depth();
      replayed = drain(q);
      check(replayed.seqs.size() <= depth, "no more handed out than are queued");
      for (auto s : replayed.seqs) check(s >= first, "a replayed message belongs to its segment");
      const std::uint64_t seq = q.push("fuzz/new", "after the replay", 1, false);
      check(seq != 0, "a new message is taken after any replay");
      check(replayed.seqs.empty() || seq > replayed.seqs.back(), "a new message comes after the replayed ones");
      mq::DiskQueue::Item item;
      check(q.next(item) && item.seq == seq && item.msg.topic == "fuzz/new", "the new message handed out last");
      check(q.flush(true), "written");
    }
    mq::DiskQueue again(o);
    (void)again.take_warnings();
    const Seen second = drain(again);
    check(!second.seqs.empty() && second.topics.back() == "fuzz/new", "a restart finds the new message again");
    check(second.seqs.size() == replayed.seqs.size() + 1, "a restart replays the same messages, and the new one");
  } catch (const std::system_error&) {
    // The one documented throw: the directory cannot be used (not the file's content).
  }
  return 0;
}
