#include "canopen/socketcan/codec.hpp"

#include <linux/can/error.h>

#include <cstring>
#include <ctime>

namespace canopen::socketcan {

using can::Frame;
using can::FrameFlag;

can::ErrorFrameInfo decode_error(const canfd_frame& raw) {
  const canid_t cls = raw.can_id & CAN_ERR_MASK;
  can::ErrorFrameInfo e;
  e.bus_off = (cls & CAN_ERR_BUSOFF) != 0;
  e.restarted = (cls & CAN_ERR_RESTARTED) != 0;
  e.protocol_error = (cls & (CAN_ERR_PROT | CAN_ERR_ACK | CAN_ERR_BUSERROR)) != 0;
  if (cls & CAN_ERR_CRTL) {
    const std::uint8_t c = raw.data[1];
    e.controller = true;
    e.rx_overflow = (c & CAN_ERR_CRTL_RX_OVERFLOW) != 0;
    e.tx_overflow = (c & CAN_ERR_CRTL_TX_OVERFLOW) != 0;
    e.rx_warning = (c & CAN_ERR_CRTL_RX_WARNING) != 0;
    e.tx_warning = (c & CAN_ERR_CRTL_TX_WARNING) != 0;
    e.rx_passive = (c & CAN_ERR_CRTL_RX_PASSIVE) != 0;
    e.tx_passive = (c & CAN_ERR_CRTL_TX_PASSIVE) != 0;
    e.back_to_active = (c & CAN_ERR_CRTL_ACTIVE) != 0;
  }
  // Drivers fill the counters when they set CAN_ERR_CNT (Linux >= 6.1).
  if (cls & CAN_ERR_CNT) {
    e.has_counters = true;
    e.tx_error_counter = raw.data[6];
    e.rx_error_counter = raw.data[7];
  }
  return e;
}

Decoded decode(const canfd_frame& raw, std::size_t nbytes) {
  Decoded d;
  if (nbytes != CAN_MTU && nbytes != CANFD_MTU) return d;
  if (raw.can_id & CAN_ERR_FLAG) {
    d.kind = RawKind::Error;
    d.error = decode_error(raw);
    return d;
  }
  Frame& f = d.frame;
  const bool ext = (raw.can_id & CAN_EFF_FLAG) != 0;
  f.id = raw.can_id & (ext ? CAN_EFF_MASK : CAN_SFF_MASK);
  f.set(FrameFlag::Extended, ext);
  if (nbytes == CANFD_MTU) {
    if (raw.len > CANFD_MAX_DLEN) return d;
    f.set(FrameFlag::Fd);
    f.set(FrameFlag::BitRateSwitch, (raw.flags & CANFD_BRS) != 0);
    f.set(FrameFlag::ErrorStateIndicator, (raw.flags & CANFD_ESI) != 0);
  } else {
    if (raw.len > CAN_MAX_DLEN) return d;
    f.set(FrameFlag::Remote, (raw.can_id & CAN_RTR_FLAG) != 0);
  }
  f.len = raw.len;
  if (!f.remote()) std::memcpy(f.data.data(), raw.data, raw.len);
  d.kind = RawKind::Data;
  return d;
}

std::size_t encode(const Frame& f, canfd_frame& raw) {
  std::memset(&raw, 0, sizeof raw);
  raw.can_id = f.id;
  if (f.extended()) raw.can_id |= CAN_EFF_FLAG;
  if (f.remote()) raw.can_id |= CAN_RTR_FLAG;
  raw.len = f.len;
  if (f.fd()) {
    raw.flags = CANFD_FDF;
    if (f.has(FrameFlag::BitRateSwitch)) raw.flags |= CANFD_BRS;
    if (f.has(FrameFlag::ErrorStateIndicator)) raw.flags |= CANFD_ESI;
  }
  if (!f.remote()) std::memcpy(raw.data, f.data.data(), f.len);
  return f.fd() ? CANFD_MTU : CAN_MTU;
}

// CMSG_* are C macros with C casts.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wcast-align"
#pragma GCC diagnostic ignored "-Wsign-conversion"
RxMeta parse_control(const msghdr& msg) {
  RxMeta m;
  // CMSG_NXTHDR takes a non-const msghdr in glibc; it only reads it.
  auto& mm = const_cast<msghdr&>(msg);
  for (cmsghdr* c = CMSG_FIRSTHDR(&mm); c != nullptr; c = CMSG_NXTHDR(&mm, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMPNS && c->cmsg_len >= CMSG_LEN(sizeof(timespec))) {
      timespec ts;
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      m.timestamp = Frame::Clock::time_point(std::chrono::duration_cast<Frame::Clock::duration>(
          std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec)));
    } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
      std::uint32_t v;
      std::memcpy(&v, CMSG_DATA(c), sizeof v);
      m.drop_count = v;
    }
  }
  return m;
}

#pragma GCC diagnostic pop

}  // namespace canopen::socketcan
