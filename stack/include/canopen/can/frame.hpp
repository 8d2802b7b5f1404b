// CAN and CAN FD frame value type, plus the text form used by can-utils
// (cansend/candump -L: "123#DEADBEEF", "12345678#R", "123##5AABB").
//
// A Frame is a plain value: copy it freely, no thread affinity.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace canopen::can {

inline constexpr std::uint32_t kMaxStandardId = 0x7FF;
inline constexpr std::uint32_t kMaxExtendedId = 0x1FFFFFFF;
inline constexpr std::size_t kMaxClassicLength = 8;
inline constexpr std::size_t kMaxFdLength = 64;

enum class FrameFlag : std::uint8_t {
  Extended = 1U << 0,     // 29-bit identifier
  Remote = 1U << 1,       // RTR (classic CAN only)
  Fd = 1U << 2,           // CAN FD frame
  BitRateSwitch = 1U << 3, // FD: data phase at the second bit rate
  ErrorStateIndicator = 1U << 4, // FD: transmitter was error passive
};

// Smallest valid CAN FD payload length >= len (FD lengths are 0..8,12,16,20,24,32,48,64).
std::size_t fd_round_up_length(std::size_t len);
// True when len is a length a CAN FD frame can carry.
bool is_valid_fd_length(std::size_t len);

struct Frame {
  using Clock = std::chrono::system_clock;

  std::uint32_t id = 0;  // 11-bit or 29-bit identifier, without flag bits
  std::uint8_t flags = 0;
  // Payload length in bytes; for a remote frame, the requested length (DLC).
  std::uint8_t len = 0;
  std::array<std::uint8_t, kMaxFdLength> data{};
  // Kernel receive time (CLOCK_REALTIME) when the frame came from SocketCAN;
  // the epoch for frames that never crossed a socket.
  Clock::time_point timestamp{};

  bool has(FrameFlag f) const { return (flags & static_cast<std::uint8_t>(f)) != 0; }
  void set(FrameFlag f, bool on = true) {
    if (on) flags = static_cast<std::uint8_t>(flags | static_cast<std::uint8_t>(f));
    else flags = static_cast<std::uint8_t>(flags & ~static_cast<std::uint8_t>(f));
  }
  bool extended() const { return has(FrameFlag::Extended); }
  bool remote() const { return has(FrameFlag::Remote); }
  bool fd() const { return has(FrameFlag::Fd); }

  std::span<const std::uint8_t> payload() const { return {data.data(), remote() ? 0U : len}; }

  // Checks id range, length (8 classic, FD lengths for FD), RTR not combined with FD.
  bool valid() const;

  // Equality ignores the timestamp: two frames are the same bytes on the wire.
  friend bool operator==(const Frame& a, const Frame& b);

  // Builders for the common cases. Payloads longer than 8 (classic) are cut at
  // construction by the caller's choice of length; valid() reports misuse.
  static Frame standard(std::uint32_t id, std::span<const std::uint8_t> bytes);
  static Frame standard(std::uint32_t id, std::initializer_list<std::uint8_t> bytes);
  static Frame extended_id(std::uint32_t id, std::span<const std::uint8_t> bytes);
  static Frame rtr(std::uint32_t id, std::uint8_t dlc, bool extended = false);
};

// Text form as accepted by cansend and printed by candump -L:
//   <id>#<hex data>         classic (3 hex digits = 11-bit, 8 = 29-bit)
//   <id>#R[<len>]           remote frame
//   <id>##<flags><hex data> CAN FD, flags is one hex digit: 1 = BRS, 2 = ESI,
//                           4 = FDF; printed with FDF set, as candump does,
//                           and accepted with or without it, as cansend does
std::string to_string(const Frame& f);

// Parses the text form above; returns nullopt for anything malformed
// (bad hex, odd digit count, id out of range, too long, invalid FD length).
std::optional<Frame> parse_frame(std::string_view text);

}  // namespace canopen::can
