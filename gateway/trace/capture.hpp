// The capture side of the bus trace: the ring of the last seconds of one
// network's frames, and the two file forms a capture is written in:
// pcapng (Wireshark, LINKTYPE_CAN_SOCKETCAN) and candump -L lines
// (canplayer replays them).
//
// Thread safety: none; one ring per network, used on the io thread. The
// writers are pure functions.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/can/frame.hpp"

namespace gateway::trace {

using WallTime = std::chrono::system_clock::time_point;

enum class Direction : std::uint8_t { Rx, Tx };

// A frame as the trace saw it: frame.timestamp is the kernel receive time
// (rx on SocketCAN), else the time the gateway received or sent it.
struct Traced {
  canopen::can::Frame frame;
  Direction dir = Direction::Rx;
};

struct CaptureLimits {
  std::chrono::seconds ring{60};      // 0: no ring (capture?last= answers nothing)
  std::size_t max_bytes = 16u << 20;  // records' memory (record_bytes), oldest dropped first
};

class CaptureRing {
 public:
  explicit CaptureRing(CaptureLimits limits) : limits_(limits) {}

  // Adds `t` (its frame.timestamp the capture time) and drops what is older
  // than the ring's seconds before it, or over max_bytes, oldest first.
  void add(const Traced& t);
  // Frames with a timestamp at or after `since`, oldest first.
  std::vector<Traced> since(WallTime since) const;

  std::size_t size() const { return records_.size(); }
  std::size_t bytes() const { return bytes_; }
  std::uint64_t dropped_for_bytes() const { return dropped_for_bytes_; }
  const CaptureLimits& limits() const { return limits_; }
  // What one frame costs the ring: a fixed record, plus its payload beyond
  // 8 bytes (CAN FD) stored on the side.
  static std::size_t record_bytes(const canopen::can::Frame& f);

 private:
  struct Record {
    std::int64_t t_ns;
    std::uint32_t id;
    std::uint8_t flags, len;
    Direction dir;
    std::array<std::uint8_t, 8> data;
  };
  void drop_oldest();
  Traced expand(const Record& r, const std::array<std::uint8_t, 64>* fd) const;

  CaptureLimits limits_;
  std::deque<Record> records_;
  std::deque<std::array<std::uint8_t, 64>> fd_;  // payloads of the records with len > 8, in the same order
  std::size_t bytes_ = 0;
  std::uint64_t dropped_for_bytes_ = 0;
};

// candump -L form, one line with its newline:
//   "(1700000000.123456) vcan0 123#DEADBEEF\n"
// seconds and microseconds of frame.timestamp; the frame as
// canopen::can::to_string writes it (3 or 8 hex id digits, R[dlc], ##<flags>).
std::string candump_line(const Traced& t, std::string_view interface);

// pcapng (draft-ietf-opsawg-pcapng): a Section Header Block, one Interface
// Description Block per interface (LINKTYPE_CAN_SOCKETCAN = 227,
// if_tsresol 9: nanoseconds), then one Enhanced Packet Block per frame with
// epb_flags inbound (rx) or outbound (tx). The packet is the SocketCAN
// frame: can_id big-endian with CAN_EFF_FLAG/CAN_RTR_FLAG, payload length,
// FD flags (CANFD_FDF|BRS|ESI; 0 for classic), two reserved bytes, data
// (8 bytes for a classic frame, 64 for FD, zero-padded; the length byte
// says how many count).
namespace pcapng {
inline constexpr std::uint16_t kLinkTypeCanSocketCan = 227;
std::string section_header(std::string_view application);
std::string interface_description(std::string_view name);
std::string enhanced_packet(const Traced& t, std::uint32_t interface_id = 0);
// An Interface Statistics Block: a capture's closing counts (isb_ifrecv:
// frames seen, isb_ifdrop: of those dropped, isb_usrdeliv: written; Wireshark
// shows the drops in the capture file properties) at `at`, with `comment`.
std::string interface_statistics(WallTime at, std::uint64_t received, std::uint64_t dropped,
                                 std::string_view comment = {}, std::uint32_t interface_id = 0);
// SHB + one IDB + the frames.
std::string file(const std::vector<Traced>& frames, std::string_view interface, std::string_view application);
}  // namespace pcapng

}  // namespace gateway::trace
