// SDO server (CiA 301 7.2.4): serves an ObjectDictionary on one SDO channel
// with every transfer mode: expedited, segmented, block download and block
// upload (with CRC, block size negotiation and the protocol switch
// threshold).
//
// Sans-I/O: the caller feeds received frames and the current time, and the
// server emits frames through the sink. The caller MUST
//   - pass every received frame to on_frame() (frames for other COB-IDs are
//     ignored, so handing it the whole bus is fine), and
//   - call on_time(now) when now >= next_deadline(), so the transfer timeout
//     (05040000h) fires.
//
// Behaviour the standard leaves open, as chosen here:
//   - A new initiate request (any of the four) while a transfer is in
//     progress ends the old transfer without an abort frame and starts the
//     new one (7.2.4.3.2 / 7.2.4.3.5: "a new initiate indicates that the
//     previous sequence was not completed"). The OD is untouched by the old
//     transfer because downloads are written only when complete. Exception:
//     during a block download (sub-blocks and the end phase) byte 0 of a
//     segment can look like any command, so there only an abort (exactly
//     80h) ends the transfer; other frames are segments, or ignored in the
//     end phase (late resends).
//   - A frame byte-identical to the previous one received is a duplicate
//     and ignored (7.2.4.3.2: a segment whose toggle bit did not alternate
//     is ignored). A segment with a wrong toggle bit that is NOT a repeat is
//     aborted with 05030000h. Where identical consecutive frames are
//     legitimate they are processed: acks of successive full block-upload
//     sub-blocks (ackseq == blksize), block download segments with blksize
//     1, and a repeated initiate when idle (a new request).
//   - A block download segment out of sequence is dropped; at the end of
//     the sub-block (seqno == blksize or c = 1) the server acknowledges the
//     last segment received in sequence, so the client resends the rest
//     (go-back-n). It never sends two equal partial acks in a row (it
//     varies blksize, see distinct_ack_blksize()), and a late copy of the
//     segment that ended the previous sub-block does not end a new one. A
//     segment with seqno 0 or above blksize is aborted with 05040003h.
//   - Block upload acks: ackseq above the segments sent is aborted with
//     05040003h, blksize 0 or above 127 with 05040002h (also in the
//     initiate); an ack that arrives after the end was sent is ignored.
//   - Frames that are not exactly 8 bytes long (SDO frames always are) are
//     answered with abort 05040001h.
//   - Segmented and block downloads write the OD once, when complete.
//   - Uploads read the OD once, at the initiate (a consistent snapshot).
//
// Thread safety: none; use from one thread (the io_context's or the test's).
// The sink is called synchronously from on_frame()/on_time()/abort() and
// must not call back into the server.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <system_error>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/sdo/abort.hpp"
#include "canopen/sdo/protocol.hpp"
#include "canopen/types.hpp"

namespace canopen::sdo {

struct ServerConfig {
  std::uint8_t node_id = 1;  // 1..127
  // COB-IDs of the channel; 0 selects the default 600h + node-ID (request,
  // client -> server) and 580h + node-ID (response, server -> client).
  std::uint32_t rx_cob_id = 0;
  std::uint32_t tx_cob_id = 0;
  // Longest the server waits for the client's next frame of a transfer
  // before aborting it with 05040000h.
  Duration timeout = std::chrono::seconds(1);
  // Segments per sub-block the server accepts in a block download (1..127).
  std::uint8_t max_block_size = kMaxBlockSize;
  // Largest download accepted; a larger indicated size (or more data
  // without size indication) is aborted with 05040005h (out of memory).
  std::size_t max_download_size = std::size_t{16} << 20;
  // Whether the server offers CRC in block transfers (sc bit).
  bool crc = true;
};

class SdoServer {
 public:
  // The protocol step the server waits in.
  enum class State : std::uint8_t {
    Idle,
    DownloadSegment,        // expects a download segment request
    UploadSegment,          // expects an upload segment request
    BlockDownloadSubBlock,  // expects sub-block segments
    BlockDownloadEnd,       // acknowledged the last segment, expects the end request
    BlockUploadStart,       // answered the initiate, expects the start command
    BlockUploadSubBlock,    // sent a sub-block, expects its acknowledgement
    BlockUploadEnd,         // sent the end, expects the end response
  };

  // The dictionary must outlive the server.
  SdoServer(od::ObjectDictionary& dictionary, ServerConfig config, FrameSink sink);

  // Handles one received frame. Returns false when the frame is not for
  // this server (other COB-ID, remote or extended frame).
  bool on_frame(const can::Frame& frame, TimePoint now);
  // TimePoint::max() when idle.
  TimePoint next_deadline() const { return state_ == State::Idle ? TimePoint::max() : deadline_; }
  // Aborts the transfer with 05040000h when its deadline has passed.
  void on_time(TimePoint now);
  // Ends the transfer in progress with an abort frame carrying `code`
  // (e.g. when the node is reset); no-op when idle.
  void abort(std::error_code code);

  State state() const { return state_; }
  std::uint32_t rx_cob_id() const { return rx_id_; }
  std::uint32_t tx_cob_id() const { return tx_id_; }
  const ServerConfig& config() const { return cfg_; }

 private:
  void send(const Payload& p);
  void fail(Multiplexer m, std::error_code code);
  void finish();
  bool is_duplicate(PayloadView p) const;
  void handle(PayloadView p);
  bool handle_initiate(PayloadView p);
  std::error_code check_writable(Multiplexer m, std::optional<std::uint32_t> size) const;

  void initiate_download(PayloadView p);
  void download_segment(PayloadView p);
  void initiate_upload(Multiplexer m);
  void upload_segment(PayloadView p);
  void block_download_initiate(PayloadView p);
  void block_download_segment(PayloadView p);
  void block_download_end(PayloadView p);
  void send_block_download_ack(PayloadView trigger);
  bool is_ack_trigger(PayloadView p) const;
  void block_upload_initiate(PayloadView p);
  void send_sub_block();
  void block_upload_ack(PayloadView p);
  void start_upload_response();

  od::ObjectDictionary& od_;
  ServerConfig cfg_;
  FrameSink sink_;
  std::uint32_t rx_id_;
  std::uint32_t tx_id_;

  State state_ = State::Idle;
  TimePoint deadline_{};
  Multiplexer mux_;
  std::optional<Payload> last_rx_;  // previous frame received, for duplicate detection
  Bytes buf_;                       // download: data so far; upload: the object's bytes
  std::optional<std::uint32_t> size_;  // download: size indicated by the client
  std::size_t offset_ = 0;          // upload: first byte not yet confirmed
  bool toggle_ = false;             // segmented: toggle bit expected next
  bool crc_ = false;                // block: both sides support CRC
  std::uint8_t blksize_ = 0;        // block: segments per sub-block
  std::uint8_t seq_ = 0;            // block download: last seqno received in order;
                                    // block upload: segments sent in this sub-block
  std::optional<BlockAck> last_ack_;    // block download: the previous ack sent
  std::optional<Payload> ack_trigger_;  // block download: the segment that caused it
};

}  // namespace canopen::sdo
