// A bounded, crash-safe FIFO of outgoing MQTT messages kept in a directory.
//
// Layout: segment files "<first seq, 20 digits>.seg" holding append-only
// records [u32 body length][u32 CRC-32 of body][body], body = [u64 seq]
// [u8 qos][u8 flags][u16 topic length][topic][payload]; and "acked", two
// alternating 24-byte slots [u64 generation][u64 head seq][u32 CRC][pad], the
// head being the first sequence number not yet acknowledged (or dropped).
// Any other name in the directory is ignored (with a warning, see
// take_warnings()), as is a file or directory whose name only looks like a
// segment (not 20 digits, or more than 2^64 - 1).
//
// Durability: by default (write-through) push() hands each record to the
// kernel with one write() before it returns, so a kill -9 of the process
// loses nothing (the data is in the page cache). With
// DiskQueueOptions::buffered_writes, push() only appends the record to an
// in-memory write buffer, and ack() only notes the new position; flush()
// then writes all buffered records with one write(), and sync() or
// flush(true) writes the position. The owner must call flush() soon
// (MqttPublisher: once per io loop turn, from a handler posted by the first
// publish of the turn, before the messages go to the socket), and push()
// flushes by itself before the buffer would exceed write_buffer_bytes. So a
// kill -9 loses at most the records pushed since the last flush(); a
// position not yet written only makes already acked messages come again
// after a crash.
//
// Syncing: sync() (the owner's timer; MqttPublisher: every 100 ms by
// default) fdatasyncs only what holds records pushed as `durable` since the
// last sync, and the position file only when the head moved over durable
// records. Records pushed with durable = false (MqttPublisher: messages of
// the `outage` storage mode, spilled while the broker is away) are written
// but never synced on their own: the kernel writes them back in its own
// time (a power loss may lose them; a kill -9 does not). So a queue that
// only ever sees non-durable records costs no fdatasync at all.
//
// Replay: on open, records from the head on are replayed. A record whose
// length, CRC or sequence number does not check out is skipped: replay
// scans forward, byte by byte, for the next offset where a whole record
// validates (length within the file, CRC, a sequence number above the last
// good one and plausible for the bytes left) and goes on from there; the
// skipped bytes and the sequence numbers missing between the two good
// records are counted (Counters::corrupt_bytes, corrupt_records) and
// reported in take_warnings(). Bytes after the last good record of the last
// segment are a torn write of a crash: they are cut so appends continue
// from a clean record (Counters::truncated_bytes).
//
// Reading: next() serves records of the segment being appended to from
// memory (the last segment's bytes appended in this run, up to about
// segment_bytes, are kept) and older ones with 256 KiB read-ahead, so
// handing out costs no read() per message. A record that cannot be read
// back is dropped (counted in corrupt_records), never thrown.
//
// Delivery is at least once: acks are recorded per message, but the head
// only moves over a contiguous acked prefix, so after a crash messages acked
// out of order, or acked while the position write was lost, are sent again.
//
// Drop policy, when a push would exceed max_messages or max_bytes (counted
// over messages not yet acked): drop the OLDEST QoS 0 message first; only
// when none is left, the oldest QoS 1 message (never the one being pushed
// unless it alone exceeds max_bytes: then it is refused, dropped_too_big).
// Space of a QoS 0 message dropped behind an older QoS 1 one stays on disk
// until the head passes its segment; so that disk use stays bounded even
// then, whenever the files span more than 2 x max_bytes + one segment, the
// oldest messages are dropped whatever their QoS (dropped_span). A QoS 0
// message dropped in the middle of the queue may be sent once more after a
// crash (drops are not persisted; QoS 0 is at most once anyway, and a QoS 1
// message is never lost to this). Retained messages are not coalesced.
//
// Storage errors (ENOSPC, EDQUOT, EIO ...) never throw and never stop the
// queue. What is queued stays queued and is still handed out (records not
// yet written stay in the write buffer, in memory, and are written when
// storage works again). While a write fails, storage_error() is set (the
// owner logs it once per episode) and:
//  - new messages go into the write buffer (buffered_writes) as long as it
//    has room (write_buffer_bytes); beyond that, or at once in write-through
//    mode, a new message that cannot be stored is refused: push() returns 0
//    and counts it in dropped_full. So on a full disk the NEWEST messages
//    are dropped, the backlog is kept.
//  - space is freed where it can be: fully acked segments are deleted even
//    when the position cannot be written (safe: replay skips a missing
//    prefix; the position only ever needs to be <= the first record still
//    in the files), and once every message is acked or dropped the last
//    segment and the unwritten buffer go too.
//  - flush() and sync() retry (a buffered push() does not, so a full disk
//    costs no write() per message); storage_error() clears once records
//    were written again and nothing is pending.
//  - a directory (ignored at open) holding the name a new segment needs
//    makes the queue skip that sequence number.
// Segment creation, appends, the position write and truncation may all fail
// this way; a failed truncation is ignored (appends are positional, so a
// stale tail is overwritten or skipped on the next replay).
//
// Thread safety: none; one owner thread (the io thread in the gateway).
// Errors: the constructor throws std::system_error when the directory cannot
// be created or read, or the position file cannot be opened (for another
// reason than a full disk); nothing else throws.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace gateway::mqtt {

struct QueuedMessage {
  std::string topic;
  std::string payload;
  std::uint8_t qos = 1;  // 0 or 1 (2 is stored and treated as 1)
  bool retained = false;
};

struct DiskQueueOptions {
  std::filesystem::path dir;                  // created if missing
  std::uint64_t max_bytes = 64ull << 20;      // record bytes not yet acked
  std::uint64_t max_messages = 1'000'000;     // messages not yet acked
  std::uint64_t segment_bytes = 4ull << 20;   // roll to a new file after this
  // Batch writes: see "Durability" above; flush() must then be called.
  bool buffered_writes = false;
  std::size_t write_buffer_bytes = 64u << 10;  // push() flushes beyond this
};

class DiskQueue {
 public:
  struct Counters {
    std::uint64_t depth = 0;            // messages not yet acked or dropped
    std::uint64_t bytes = 0;            // their record bytes
    std::uint64_t disk_bytes = 0;       // bytes in segment files (and the write buffer)
    std::uint64_t written = 0;          // pushed since open
    std::uint64_t acked = 0;            // acked since open
    std::uint64_t dropped_qos0 = 0;     // oldest QoS 0 dropped for space
    std::uint64_t dropped_qos1 = 0;     // oldest QoS 1 dropped for space
    std::uint64_t dropped_span = 0;     // dropped because files spanned too much
    std::uint64_t dropped_too_big = 0;  // refused: larger than max_bytes
    std::uint64_t dropped_full = 0;     // refused: storage full (or failing)
    std::uint64_t replayed = 0;         // messages found on open
    std::uint64_t truncated_bytes = 0;  // torn tail bytes cut on open
    std::uint64_t corrupt_bytes = 0;    // bytes skipped as corrupt on open
    std::uint64_t corrupt_records = 0;  // records lost to corruption (skipped or unreadable)
    std::uint64_t ignored_files = 0;    // unknown names in the directory on open
    std::uint64_t write_errors = 0;     // failed writes (appends, position, segment creation)
    std::uint64_t storage_bytes = 0;    // bytes handed to the kernel (records + position)
    std::uint64_t syncs = 0;            // fdatasync calls
    std::uint64_t dropped() const {
      return dropped_qos0 + dropped_qos1 + dropped_span + dropped_too_big + dropped_full;
    }
  };

  // One message handed out for sending; ack(seq) when the broker confirmed.
  struct Item {
    std::uint64_t seq = 0;
    QueuedMessage msg;
  };

  explicit DiskQueue(DiskQueueOptions opts);
  ~DiskQueue();
  DiskQueue(const DiskQueue&) = delete;
  DiskQueue& operator=(const DiskQueue&) = delete;

  // Appends (dropping older messages per the policy if full). Returns the
  // message's sequence number, or 0 when refused (too big, or storage
  // failing and no room in the write buffer: see the counters). durable:
  // sync() fdatasyncs it (see "Syncing").
  std::uint64_t push(const QueuedMessage& m, bool durable = true);
  // The same without building a QueuedMessage (the publisher's hot path).
  std::uint64_t push(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained,
                     bool durable = true);

  // The next message not yet handed out since open or the last rewind(), in
  // order; false when there is none.
  bool next(Item& out);
  // The sequence number next() would hand out, or 0 when none.
  std::uint64_t peek();
  // Hand out again from the oldest unacked message (after a reconnect).
  void rewind();
  // Hand out again from seq on (a send that did not happen).
  void rewind_to(std::uint64_t seq);
  // The broker confirmed seq. Idempotent; unknown or old seqs are ignored.
  // Returns true if it was a pending message.
  bool ack(std::uint64_t seq);
  // Writes buffered records (buffered_writes; a no-op when nothing is
  // pending), and with_position the ack position if it moved. False when a
  // write failed (storage_error() says why); the records then stay buffered
  // (still handed out by next()) and the next flush() tries again.
  bool flush(bool with_position = false);
  // True when flush() has something to write.
  bool flush_pending() const;
  // flush(true), then fdatasync what holds durable data written since the
  // last call (the timer's job). Failures are kept for the next call.
  void sync();

  std::uint64_t depth() const { return live_; }
  // Messages pending but not handed out by next() since the last rewind()
  // (counts them: O(pending)).
  std::uint64_t unsent() const;
  // unsent() > 0, without counting.
  bool has_unsent() const;
  std::uint64_t head_seq() const { return head_; }
  // The sequence number the next push() gets.
  std::uint64_t next_seq() const { return next_seq_; }
  // Set while writes fail (the first failure's error); cleared once all
  // that was pending is written.
  std::error_code storage_error() const { return storage_error_; }
  const Counters& counters() const { return counters_; }
  // What open found worth telling (ignored names, skipped corruption), one
  // line each; the owner logs them. Empties the list.
  std::vector<std::string> take_warnings();

 private:
  enum class State : std::uint8_t { Live, Acked, Dropped };
  struct Entry {
    std::uint64_t segment;  // first seq of its segment
    std::uint64_t offset;   // of the record header
    std::uint32_t size;     // header + body
    std::uint8_t qos;
    State state;
    bool durable;
  };
  struct Segment {
    int fd = -1;
    std::uint64_t size = 0;     // bytes appended (written + buffered)
    std::uint64_t written = 0;  // bytes handed to the kernel
    bool unsynced = false;      // holds durable bytes not yet fdatasync'ed
  };

  void open_existing();
  void replay_segment(std::uint64_t first, Segment& seg, bool last, std::uint64_t limit);
  void read_head();
  void write_head();
  bool persist_head();
  bool flush_segment(Segment& seg);
  const char* record(const Entry& e);
  Segment* writable_segment(std::uint64_t need);
  void drop(std::uint64_t seq, std::uint64_t& reason);
  void enforce_bounds(std::uint64_t incoming_bytes);
  void advance_head();
  void delete_consumed_segments(bool including_last);
  void delete_segment(std::map<std::uint64_t, Segment>::iterator it);
  bool free_space();
  std::uint64_t refuse();
  void failed(int err);
  void update_error_state();
  Entry* entry(std::uint64_t seq);
  bool oldest_live(std::deque<std::uint64_t>& fifo, std::uint64_t& seq);

  DiskQueueOptions opts_;
  int head_fd_ = -1;
  std::uint64_t head_generation_ = 0;
  bool head_sync_needed_ = false;  // moved over durable records since the last sync
  bool head_unwritten_ = false;    // head_ moved, not yet written
  bool append_failed_ = false;     // the last record write failed: push() does not retry
  // Bytes [tail_base_, size) of the last segment: the write buffer (from its
  // `written` on) and a read cache for next().
  std::string tail_;
  std::uint64_t tail_base_ = 0;
  // Read-ahead for records in older segments (or before tail_base_).
  std::string rd_buf_;
  std::uint64_t rd_segment_ = 0, rd_offset_ = 0;
  bool rd_valid_ = false;
  std::uint64_t head_ = 1;        // first seq not acked/dropped (persisted)
  std::uint64_t next_seq_ = 1;    // seq of the next push
  std::uint64_t cursor_ = 1;      // next seq next() hands out
  std::uint64_t live_ = 0;
  std::uint64_t live_bytes_ = 0;
  std::deque<Entry> entries_;     // entries_[i] is seq head_ + i
  std::deque<std::uint64_t> live_qos0_, live_qos1_;  // seqs, lazily pruned
  std::map<std::uint64_t, Segment> segments_;        // by first seq
  std::error_code storage_error_;
  std::vector<std::string> warnings_;
  Counters counters_;
};

}  // namespace gateway::mqtt
