// SDO client (CiA 301 7.2.4) for one CAN network: uploads and downloads to
// many server nodes, every transfer mode, one transfer per node at a time
// with a bounded FIFO queue per node.
//
// Sans-I/O: the caller feeds received frames and the current time; the
// client emits frames through the sink. The caller MUST
//   - pass every received frame to on_frame() (frames that are not SDO
//     responses of a node with a transfer in progress are ignored), and
//   - call on_time(now) when now >= next_deadline(), re-reading it after
//     its own on_frame() and on_time() calls. upload(), download() and
//     cancel() report the new deadline to the on_deadline_change()
//     observer (canopen/deadline.hpp).
//
// Modes (Mode):
//   - Auto, download: expedited for 1..4 bytes; block for more than
//     block_threshold bytes unless the node refused a block initiate
//     recently (see below); segmented otherwise (including 0 bytes).
//   - Auto, upload: when Request::expected_size is at most block_threshold,
//     a normal (expedited/segmented) initiate goes out. Callers that know
//     the object's size (fixed-size data types from the EDS) MUST pass it:
//     a device without block transfer then costs nothing extra on ordinary
//     reads. Otherwise (large or unknown size) a block upload initiate goes
//     out with the protocol switch threshold pst = min(block_threshold,
//     255): the server answers objects up to pst bytes with a normal upload
//     (7.2.4.3.13). A normal initiate goes out too while the node counts as
//     refusing block transfer.
//   - Auto, fallback: a server answering a block initiate with abort
//     05040001h for the very index/sub-index of the request refuses block
//     transfer: the request is restarted at once with a normal initiate, and
//     the node's Auto transfers go the normal way for
//     ClientConfig::block_retry_interval, then block is tried again (the
//     node may have been replaced or updated meanwhile). Some servers
//     (CANopenNode built without block support) send that refusal with the
//     index/sub-index of their previous transfer instead; such an abort is
//     stray (below), but when the server then stays silent until the
//     timeout, the silence confirms the refusal: the node is treated as
//     refusing, and the request restarts with a normal initiate instead of
//     failing. (A server that stays silent without any refusal gets a
//     timeout.) forget_block_support() clears what was learned at once.
//   - Expedited / Segmented download: forced; Expedited needs 1..4 bytes.
//   - Expedited / Segmented upload: the client sends the normal initiate;
//     the server chooses expedited or segmented, and both are accepted.
//   - Block: forced block transfer (upload with pst = 0); no fallback.
//
// Checks on every response: the multiplexer of every initiate response must
// be the requested one (otherwise abort 06040043h "general parameter
// incompatibility", local — never taken as the next frame); unknown or
// unexpected command specifiers abort with 05040001h, a toggle bit that
// did not alternate with 05030000h, frames not exactly 8 bytes long with
// 05040001h, sizes that do not match the indicated size with 06070010h, an
// upload above max_upload_size with 05040005h, block seqno/blksize errors
// with 05040003h/05040002h, CRC mismatch with 05040004h. An abort frame
// from the server completes the request with its code, origin Remote (code
// 0, which is no abort code, as 08000000h).
//
// Stray aborts: an abort frame whose index/sub-index is not the transfer's
// (7.2.4.3.17: m is the multiplexer of the aborted transfer) does not end
// the transfer, does not restart its timeout and does not count as a
// refusal of block transfer; it is only counted (stray_aborts()). Devices
// send them, e.g. late for a transfer the client already gave up on.
//
// Duplicates (a frame repeated on the bus): a response byte-identical to the
// previous one of the transfer is ignored, except where equal consecutive
// frames are legitimate: acks of successive full sub-blocks (ackseq ==
// blksize) and block segments with blksize 1. As a block receiver the
// client never sends two equal partial acks in a row (it varies blksize,
// see distinct_ack_blksize()), and it does not take a late copy of the
// segment that ended the previous sub-block for the end of a new one.
// Lost frames: a lost block segment is recovered by go-back-n (ackseq);
// anything else lost ends in a timeout. Confusion that gets past these rules
// (e.g. a duplicate full-sub-block ack, which looks legitimate) is caught by
// the size and CRC checks at the end: a block transfer delivers exactly the
// bytes sent or fails.
//
// Timeouts: a transfer's timeout is the longest wait for the server's next
// frame; every frame that advances the transfer restarts it. It starts when
// the transfer starts (queued time does not count). On expiry the client
// sends abort 05040000h and completes with Timeout (origin Local).
//
// Cancel: a queued request is removed; a running one is aborted on the bus
// with 08000000h (general error: the client gave up, it did not time out).
// Either way the completion handler runs (inside cancel()) with
// GeneralError, origin Local and cancelled = true.
//
// Queue: at most queue_limit requests wait per node behind the running one;
// submitting more returns SdoAbort::NoSdoConnection (060A0023h, "resource
// not available: SDO connection") from upload()/download() itself — never
// through the handler — which the REST layer maps to HTTP 429.
//
// Thread safety: none; use from one thread. Completion and progress
// handlers are called synchronously from on_frame(), on_time() and
// cancel() (never from upload()/download()); they may call upload(),
// download() and cancel() re-entrantly. The sink is called synchronously
// and must not call back into the client.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/deadline.hpp"
#include "canopen/result.hpp"
#include "canopen/sdo/abort.hpp"
#include "canopen/sdo/protocol.hpp"
#include "canopen/types.hpp"

namespace canopen::sdo {

enum class Mode : std::uint8_t { Auto, Expedited, Segmented, Block };

// Where the error of a failed transfer came from.
enum class Origin : std::uint8_t {
  None,    // success
  Remote,  // the server sent an abort frame
  Local,   // the client aborted: timeout, malformed or unexpected response, cancel
};

using RequestId = std::uint64_t;

struct TransferResult {
  RequestId id = 0;
  std::uint8_t node = 0;
  Multiplexer mux;
  bool upload = false;
  // Empty on success. Otherwise in the SdoAbort category: value() is the
  // CiA abort code, message() the standard's text.
  std::error_code error;
  Origin origin = Origin::None;
  bool cancelled = false;
  std::string detail;  // one line of context for local errors, e.g. the wrong multiplexer
  Bytes data;          // upload: the bytes received
  bool ok() const { return !error; }
};

using CompletionHandler = std::function<void(TransferResult&&)>;
// Bytes transferred so far and the total when known (always for downloads;
// for uploads when the server indicated the size).
using ProgressHandler = std::function<void(std::size_t done, std::optional<std::size_t> total)>;

struct Request {
  std::uint8_t node = 0;  // 1..127
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  Mode mode = Mode::Auto;
  std::optional<Duration> timeout;  // overrides the node's default
  // Upload, Auto: the size the caller expects (e.g. from the EDS data type).
  // Up to block_threshold bytes a normal initiate goes out directly instead
  // of a block initiate with protocol switch.
  std::optional<std::size_t> expected_size;
  CompletionHandler on_done;        // called exactly once, unless submit failed
  ProgressHandler on_progress;      // optional
};

struct ClientConfig {
  Duration default_timeout = std::chrono::seconds(1);
  std::size_t queue_limit = 32;      // requests waiting per node behind the running one
  std::size_t block_threshold = 64;  // Auto: block transfer above this many bytes
  std::uint8_t block_size = kMaxBlockSize;  // segments per sub-block offered in block upload
  bool crc = true;                          // request CRC in block transfers
  std::size_t max_upload_size = std::size_t{16} << 20;  // larger uploads abort with 05040005h
  // Progress is reported when at least this many more bytes are done, and
  // at the end of the data phase.
  std::size_t progress_step = 4096;
  // After a node refused a block initiate, Auto transfers to it use normal
  // transfers for this long, then try block again. Zero: try block every
  // time (each refusal costs a round trip, or a timeout, see Auto fallback).
  Duration block_retry_interval = std::chrono::minutes(10);
};

class SdoClient : public DeadlineSource {
 public:
  SdoClient(ClientConfig config, FrameSink sink);

  // Queue a request; it starts at once when the node is idle (the initiate
  // is sent from inside this call). Errors: std::errc::invalid_argument
  // (node not 1..127, Expedited download of 0 or more than 4 bytes, data
  // above 4 GiB), SdoAbort::NoSdoConnection (queue full).
  Result<RequestId> upload(Request request, TimePoint now);
  Result<RequestId> download(Request request, Bytes data, TimePoint now);

  // Cancels a queued or running request (see the header comment). Returns
  // false when the id is unknown or already completed.
  bool cancel(RequestId id, TimePoint now);

  // Returns true when the frame was a response of a node with a transfer in
  // progress (a stray abort included).
  bool on_frame(const can::Frame& frame, TimePoint now);
  // Earliest deadline of the running transfers; TimePoint::max() when none.
  TimePoint next_deadline() const;
  void on_time(TimePoint now);

  // Per-node settings. COB-IDs default to 600h + node (request) and 580h +
  // node (response). Changing them while the node has a transfer running
  // affects the next transfer.
  void set_node_timeout(std::uint8_t node, Duration timeout);
  void set_node_cob_ids(std::uint8_t node, std::uint32_t request_id, std::uint32_t response_id);
  void forget_block_support(std::uint8_t node);
  // Whether Auto transfers to the node would start with a block initiate at
  // `now` (false while it counts as refusing block transfer).
  bool block_allowed(std::uint8_t node, TimePoint now) const;

  // Called after every successful download, before its completion handler,
  // with the node, the object and the bytes written: lets a service follow
  // what this client changed on a node (Network: the PDO decoder follows a
  // node's PDO parameters). One observer; it must not call back into the
  // client.
  using DownloadObserver =
      std::function<void(std::uint8_t node, const Multiplexer& mux, const Bytes& data)>;
  void set_download_observer(DownloadObserver observer) { download_observer_ = std::move(observer); }

  // Requests of the node: waiting plus running.
  std::size_t pending(std::uint8_t node) const;
  bool busy(std::uint8_t node) const;
  // Abort frames ignored because their index/sub-index was not the
  // transfer's, all nodes, since construction.
  std::uint64_t stray_aborts() const { return stray_aborts_; }

 private:
  // The protocol step a running transfer waits in.
  enum class Step : std::uint8_t {
    ExpeditedDownload,      // sent an expedited initiate, expects its response
    InitiateDownload,       // sent a normal initiate, expects its response
    DownloadSegment,        // sent a segment, expects its response
    InitiateUpload,         // sent an initiate, expects expedited data or the size
    UploadSegment,          // sent a segment request, expects the segment
    BlockDownloadInitiate,  // sent a block initiate, expects blksize
    BlockDownloadSubBlock,  // sent a sub-block, expects its acknowledgement
    BlockDownloadEnd,       // sent the end, expects the end response
    BlockUploadInitiate,    // sent a block initiate, expects size (or a normal upload response)
    BlockUploadSubBlock,    // sent start or ack, receives segments
    BlockUploadEnd,         // acknowledged the last segment, expects the end
  };
  struct Job {
    RequestId id = 0;
    bool upload = false;
    Request req;
    Bytes data;  // download: the data to send
  };
  struct Transfer {
    Job job;
    Step step = Step::InitiateUpload;
    Multiplexer mux;
    Duration timeout{};
    TimePoint deadline{};
    std::optional<Payload> last_rx;
    Bytes data;                          // upload: bytes received so far
    std::optional<std::uint32_t> size;   // upload: indicated size
    std::size_t offset = 0;              // download: bytes sent (segmented) / confirmed (block)
    std::size_t last_progress = 0;      // bytes at the last progress report
    // A progress report to deliver once the frame is handled.
    std::optional<std::pair<std::size_t, std::optional<std::size_t>>> progress_due;
    bool toggle = false;   // segmented: toggle bit of the frame in flight
    bool crc = false;      // block: both sides use CRC
    std::uint8_t blksize = 0;
    std::uint8_t seq = 0;  // block download: segments sent in this sub-block;
                           // block upload: last seqno received in order
    std::optional<BlockAck> last_ack;    // block upload: the previous ack sent
    std::optional<Payload> ack_trigger;  // block upload: the segment that caused it
    // Block initiate unanswered: a stray 05040001h came meanwhile (the
    // multiplexer it carried), possibly a refusal with a stale multiplexer.
    std::optional<Multiplexer> stray_refusal;
  };
  struct Node {
    std::uint32_t request_id = 0;
    std::uint32_t response_id = 0;
    std::optional<Duration> timeout;
    TimePoint no_block_until{};  // refused a block initiate: Auto stays normal until then
    std::deque<Job> queue;
    std::optional<Transfer> active;
  };

  Result<RequestId> submit(Job job, TimePoint now);
  void pump(std::uint8_t node, TimePoint now);
  void start(std::uint8_t node, Job job, TimePoint now);
  void send_initiate(std::uint8_t node, Transfer& t, TimePoint now);
  void refuse_block(std::uint8_t node, TimePoint now);
  bool is_abort(const Transfer& t, PayloadView p) const;
  void stray_abort(Transfer& t, PayloadView p);
  void send(const Node& n, const Payload& p);
  void complete(std::uint8_t node, std::error_code ec, Origin origin, std::string detail, TimePoint now,
                bool cancelled = false);
  void fail_local(std::uint8_t node, std::error_code ec, std::string detail, TimePoint now);
  void handle(std::uint8_t node, PayloadView p, TimePoint now);
  void remote_abort(std::uint8_t node, PayloadView p, TimePoint now);
  bool is_duplicate(const Transfer& t, PayloadView p) const;
  void progress(Transfer& t, std::size_t done, std::optional<std::size_t> total);
  bool check_mux(std::uint8_t node, PayloadView p, TimePoint now);

  void send_download_segment(std::uint8_t node, Transfer& t);
  void on_download_segment_response(std::uint8_t node, PayloadView p, TimePoint now);
  void on_upload_initiate_response(std::uint8_t node, PayloadView p, TimePoint now);
  void on_upload_segment(std::uint8_t node, PayloadView p, TimePoint now);
  void send_sub_block(std::uint8_t node, Transfer& t);
  void on_block_download_ack(std::uint8_t node, PayloadView p, TimePoint now);
  void on_block_upload_initiate_response(std::uint8_t node, PayloadView p, TimePoint now);
  void on_block_upload_segment(std::uint8_t node, PayloadView p, TimePoint now);
  void send_block_upload_ack(std::uint8_t node, Transfer& t, PayloadView trigger);
  void on_block_upload_end(std::uint8_t node, PayloadView p, TimePoint now);

  Duration timeout_for(std::uint8_t node, const Request& r) const;

  ClientConfig cfg_;
  FrameSink sink_;
  std::array<Node, 128> nodes_;       // index = node-ID; [0] unused
  std::vector<std::uint8_t> running_; // nodes with an active transfer
  RequestId next_id_ = 1;
  std::uint64_t stray_aborts_ = 0;
  DownloadObserver download_observer_;
};

}  // namespace canopen::sdo
