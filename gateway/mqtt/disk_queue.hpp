// A bounded, crash-safe FIFO of outgoing MQTT messages kept in a directory.
//
// Layout: segment files "<first seq, 20 digits>.seg" holding append-only
// records [u32 body length][u32 CRC-32 of body][body], body = [u64 seq]
// [u8 qos][u8 flags][u16 topic length][topic][payload]; and "acked", two
// alternating 24-byte slots [u64 generation][u64 head seq][u32 CRC][pad], the
// head being the first sequence number not yet acknowledged (or dropped).
//
// Durability: by default (write-through) push() hands each record to the
// kernel with one write() before it returns, so a kill -9 of the process
// loses nothing (the data is in the page cache). With
// DiskQueueOptions::buffered_writes, push() only appends the record to an
// in-memory write buffer, and ack() only notes the new position; flush()
// then writes all buffered records with one write(), and sync() or
// flush(true) writes the position (as does deleting a fully acked segment,
// and the destructor). The owner must call flush() soon (MqttPublisher:
// once per io loop turn, from a handler posted by the first publish of the
// turn, before the messages go to the socket), and push() flushes by itself
// before the buffer would exceed write_buffer_bytes. So a kill -9 loses at
// most the records pushed since the last flush(); a position not yet
// written only makes already acked messages come again after a crash.
// There is no fsync per message: the owner calls sync() on a timer
// (MqttPublisher: every 100 ms by default), so a power loss loses at most
// the last interval. On open, records from the head on are replayed; a
// torn or corrupt record (bad length or CRC) ends its segment, which is
// truncated there (counted in Counters::truncated_bytes).
//
// Reading: next() serves records of the segment being appended to from
// memory (the last segment's bytes appended in this run, up to about
// segment_bytes, are kept) and older ones with 256 KiB read-ahead, so
// handing out costs no read() per message.
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
// Thread safety: none; one owner thread (the io thread in the gateway).
// Errors: the constructor throws std::system_error when the directory cannot
// be created or read; push() throws std::system_error when the write fails
// (disk full): the message is then not queued (buffered_writes: when the
// flush it needs first fails; flush() reports later failures).
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>

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
    std::uint64_t disk_bytes = 0;       // bytes in segment files
    std::uint64_t written = 0;          // pushed since open
    std::uint64_t acked = 0;            // acked since open
    std::uint64_t dropped_qos0 = 0;     // oldest QoS 0 dropped for space
    std::uint64_t dropped_qos1 = 0;     // oldest QoS 1 dropped for space
    std::uint64_t dropped_span = 0;     // dropped because files spanned too much
    std::uint64_t dropped_too_big = 0;  // refused: larger than max_bytes
    std::uint64_t replayed = 0;         // messages found on open
    std::uint64_t truncated_bytes = 0;  // torn/corrupt tail bytes cut on open
    std::uint64_t dropped() const { return dropped_qos0 + dropped_qos1 + dropped_span + dropped_too_big; }
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
  // message's sequence number, or 0 when refused as too big.
  std::uint64_t push(const QueuedMessage& m);
  // The same without building a QueuedMessage (the publisher's hot path).
  std::uint64_t push(std::string_view topic, std::string_view payload, std::uint8_t qos, bool retained);

  // The next message not yet handed out since open or the last rewind(), in
  // order; false when there is none. Reads the record back from the file.
  bool next(Item& out);
  // Hand out again from the oldest unacked message (after a reconnect).
  void rewind();
  // Hand out again from seq on (a send that did not happen).
  void rewind_to(std::uint64_t seq);
  // The broker confirmed seq. Idempotent; unknown or old seqs are ignored.
  // Returns true if it was a pending message.
  bool ack(std::uint64_t seq);
  // Writes buffered records (buffered_writes; a no-op when nothing is
  // pending), and with_position the ack position if it moved. Throws
  // std::system_error when a write fails; the records then stay buffered
  // (still handed out by next()) and the next flush() tries again.
  void flush(bool with_position = false);
  // True when flush() has something to write.
  bool flush_pending() const;
  // flush() and write the ack position, errors ignored (retried later),
  // then fdatasync the files written since the last call (the timer's job).
  void sync();

  std::uint64_t depth() const { return live_; }
  // Messages pending but not handed out by next() since the last rewind().
  std::uint64_t unsent() const;
  std::uint64_t head_seq() const { return head_; }
  const Counters& counters() const { return counters_; }

 private:
  enum class State : std::uint8_t { Live, Acked, Dropped };
  struct Entry {
    std::uint64_t segment;  // first seq of its segment
    std::uint64_t offset;   // of the record header
    std::uint32_t size;     // header + body
    std::uint8_t qos;
    State state;
  };
  struct Segment {
    int fd = -1;
    std::uint64_t size = 0;     // bytes appended (written + buffered)
    std::uint64_t written = 0;  // bytes handed to the kernel
    bool dirty = false;
  };

  void open_existing();
  void replay_segment(std::uint64_t first, Segment& seg, bool last);
  void read_head();
  void write_head();
  void persist_head();
  void flush_segment(Segment& seg);
  const char* record(const Entry& e);
  Segment& writable_segment(std::uint64_t seq, std::uint64_t need);
  void drop(std::uint64_t seq, std::uint64_t& reason);
  void enforce_bounds(std::uint64_t incoming_bytes);
  void advance_head();
  void delete_consumed_segments();
  Entry* entry(std::uint64_t seq);
  bool oldest_live(std::deque<std::uint64_t>& fifo, std::uint64_t& seq);

  DiskQueueOptions opts_;
  int head_fd_ = -1;
  std::uint64_t head_generation_ = 0;
  bool head_dirty_ = false;
  bool head_unwritten_ = false;   // head_ moved, not yet written (buffered)
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
  Counters counters_;
};

}  // namespace gateway::mqtt
