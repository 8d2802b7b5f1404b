// Conversion between the kernel's SocketCAN structures and can::Frame, and
// parsing of the ancillary data recvmsg() returns (receive timestamp,
// SO_RXQ_OVFL drop counter). Pure functions: no sockets here, so they are
// unit-tested on machines without CAN support.
#pragma once

#include <linux/can.h>
#include <sys/socket.h>

#include <cstddef>
#include <cstdint>
#include <optional>

#include "canopen/can/bus_state.hpp"
#include "canopen/can/frame.hpp"

namespace canopen::socketcan {

enum class RawKind : std::uint8_t { Data, Error, Invalid };

struct Decoded {
  RawKind kind = RawKind::Invalid;
  can::Frame frame;              // for Data
  can::ErrorFrameInfo error;     // for Error
};

// Decodes `nbytes` (CAN_MTU or CANFD_MTU, as read() returned) of `raw`.
Decoded decode(const canfd_frame& raw, std::size_t nbytes);

// Decodes the payload of an error frame (CAN_ERR_FLAG set).
can::ErrorFrameInfo decode_error(const canfd_frame& raw);

// Fills `raw` for transmission; returns the number of bytes to write
// (CAN_MTU for classic frames, CANFD_MTU for FD frames). The frame must be valid().
std::size_t encode(const can::Frame& f, canfd_frame& raw);

struct RxMeta {
  std::optional<can::Frame::Clock::time_point> timestamp;  // SCM_TIMESTAMPNS
  std::optional<std::uint32_t> drop_count;                 // SO_RXQ_OVFL (cumulative)
};

// Reads the control messages of one received message.
RxMeta parse_control(const msghdr& msg);

// Control buffer size that holds both control messages above.
inline constexpr std::size_t kControlBufferSize =
    CMSG_SPACE(sizeof(struct timespec)) + CMSG_SPACE(sizeof(std::uint32_t));

}  // namespace canopen::socketcan
