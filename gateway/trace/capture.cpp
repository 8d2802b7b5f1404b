#include "trace/capture.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace gateway::trace {

namespace {

using canopen::can::Frame;

std::int64_t to_ns(WallTime t) { return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count(); }

}  // namespace

std::size_t CaptureRing::record_bytes(const Frame& f) { return sizeof(Record) + (f.len > 8 ? 64 : 0); }

void CaptureRing::add(const Traced& t) {
  if (limits_.ring.count() <= 0) return;
  const Frame& f = t.frame;
  Record r{to_ns(f.timestamp), f.id, f.flags, f.len, t.dir, {}};
  std::memcpy(r.data.data(), f.data.data(), 8);
  const std::size_t cost = record_bytes(f);
  if (cost > limits_.max_bytes) return;
  while (!records_.empty() && bytes_ + cost > limits_.max_bytes) {
    drop_oldest();
    ++dropped_for_bytes_;
  }
  records_.push_back(r);
  if (f.len > 8) {
    fd_.emplace_back();
    std::memcpy(fd_.back().data(), f.data.data(), 64);
  }
  bytes_ += cost;
  const std::int64_t oldest = r.t_ns - std::chrono::duration_cast<std::chrono::nanoseconds>(limits_.ring).count();
  while (!records_.empty() && records_.front().t_ns < oldest) drop_oldest();
}

void CaptureRing::drop_oldest() {
  const Record& r = records_.front();
  bytes_ -= sizeof(Record);
  if (r.len > 8) {
    bytes_ -= 64;
    fd_.pop_front();
  }
  records_.pop_front();
}

Traced CaptureRing::expand(const Record& r, const std::array<std::uint8_t, 64>* fd) const {
  Traced t;
  t.frame.id = r.id;
  t.frame.flags = r.flags;
  t.frame.len = r.len;
  if (fd) std::memcpy(t.frame.data.data(), fd->data(), 64);
  else std::memcpy(t.frame.data.data(), r.data.data(), 8);
  t.frame.timestamp = WallTime(std::chrono::duration_cast<WallTime::duration>(std::chrono::nanoseconds(r.t_ns)));
  t.dir = r.dir;
  return t;
}

std::vector<Traced> CaptureRing::since(WallTime since) const {
  const std::int64_t from = to_ns(since);
  // Timestamps are nearly ordered (rx kernel times vs tx send times may
  // interleave by microseconds): scan all, the ring is bounded.
  std::vector<Traced> out;
  std::size_t fd_at = 0;
  for (const auto& r : records_) {
    const std::array<std::uint8_t, 64>* fd = r.len > 8 ? &fd_[fd_at++] : nullptr;
    if (r.t_ns >= from) out.push_back(expand(r, fd));
  }
  return out;
}

std::string candump_line(const Traced& t, std::string_view interface) {
  const std::int64_t us = std::chrono::duration_cast<std::chrono::microseconds>(t.frame.timestamp.time_since_epoch()).count();
  char head[48];
  std::snprintf(head, sizeof head, "(%010lld.%06lld) ", static_cast<long long>(us / 1000000),
                static_cast<long long>(us % 1000000));
  std::string line = head;
  line.append(interface);
  line += ' ';
  line += canopen::can::to_string(t.frame);
  line += '\n';
  return line;
}

namespace pcapng {

namespace {

// Little-endian on every host; the byte-order magic of the SHB says so.
void u16(std::string& s, std::uint16_t v) {
  s.push_back(static_cast<char>(v & 0xFF));
  s.push_back(static_cast<char>(v >> 8));
}
void u32(std::string& s, std::uint32_t v) {
  u16(s, static_cast<std::uint16_t>(v & 0xFFFF));
  u16(s, static_cast<std::uint16_t>(v >> 16));
}
void pad4(std::string& s) {
  while (s.size() % 4 != 0) s.push_back('\0');
}
void option(std::string& s, std::uint16_t code, std::string_view value) {
  u16(s, code);
  u16(s, static_cast<std::uint16_t>(value.size()));
  s.append(value);
  pad4(s);
}
// type, total length, body, total length again.
std::string block(std::uint32_t type, const std::string& body) {
  std::string s;
  const auto total = static_cast<std::uint32_t>(12 + body.size());
  u32(s, type);
  u32(s, total);
  s += body;
  u32(s, total);
  return s;
}

}  // namespace

std::string section_header(std::string_view application) {
  std::string b;
  u32(b, 0x1A2B3C4D);  // byte-order magic
  u16(b, 1);           // major
  u16(b, 0);           // minor
  u32(b, 0xFFFFFFFF);  // section length: not given (-1)
  u32(b, 0xFFFFFFFF);
  if (!application.empty()) option(b, 4, application);  // shb_userappl
  u32(b, 0);                                              // opt_endofopt
  return block(0x0A0D0D0A, b);
}

std::string interface_description(std::string_view name) {
  std::string b;
  u16(b, kLinkTypeCanSocketCan);
  u16(b, 0);   // reserved
  u32(b, 72);  // snaplen: a CAN FD frame
  option(b, 2, name);                     // if_name
  option(b, 9, std::string_view("\x09", 1));  // if_tsresol: 10^-9 s
  u32(b, 0);
  return block(0x00000001, b);
}

std::string enhanced_packet(const Traced& t, std::uint32_t interface_id) {
  const Frame& f = t.frame;
  // struct can_frame / canfd_frame as LINKTYPE_CAN_SOCKETCAN carries it.
  std::string pkt;
  std::uint32_t can_id = f.id | (f.extended() ? 0x80000000u : 0) | (f.remote() ? 0x40000000u : 0);
  pkt.push_back(static_cast<char>(can_id >> 24));
  pkt.push_back(static_cast<char>(can_id >> 16));
  pkt.push_back(static_cast<char>(can_id >> 8));
  pkt.push_back(static_cast<char>(can_id));
  pkt.push_back(static_cast<char>(f.len));
  std::uint8_t fd_flags = 0;
  if (f.fd()) {
    fd_flags = 0x04;  // CANFD_FDF
    if (f.has(canopen::can::FrameFlag::BitRateSwitch)) fd_flags |= 0x01;
    if (f.has(canopen::can::FrameFlag::ErrorStateIndicator)) fd_flags |= 0x02;
  }
  pkt.push_back(static_cast<char>(fd_flags));
  pkt.push_back('\0');
  pkt.push_back('\0');
  const std::size_t room = f.fd() ? 64 : 8;
  for (std::size_t i = 0; i < room; ++i) pkt.push_back(static_cast<char>(!f.remote() && i < f.len ? f.data[i] : 0));

  const auto ns = static_cast<std::uint64_t>(to_ns(f.timestamp));
  std::string b;
  u32(b, interface_id);
  u32(b, static_cast<std::uint32_t>(ns >> 32));
  u32(b, static_cast<std::uint32_t>(ns));
  u32(b, static_cast<std::uint32_t>(pkt.size()));  // captured
  u32(b, static_cast<std::uint32_t>(pkt.size()));  // original
  b += pkt;
  pad4(b);
  u16(b, 2);  // epb_flags
  u16(b, 4);
  u32(b, t.dir == Direction::Rx ? 1u : 2u);  // bits 0-1: 01 inbound, 10 outbound
  u32(b, 0);
  return block(0x00000006, b);
}

std::string interface_statistics(WallTime at, std::uint64_t received, std::uint64_t dropped, std::string_view comment,
                                 std::uint32_t interface_id) {
  auto u64 = [](std::uint64_t v) {
    std::string s;
    u32(s, static_cast<std::uint32_t>(v));
    u32(s, static_cast<std::uint32_t>(v >> 32));
    return s;
  };
  const auto ns = static_cast<std::uint64_t>(to_ns(at));
  std::string b;
  u32(b, interface_id);
  u32(b, static_cast<std::uint32_t>(ns >> 32));
  u32(b, static_cast<std::uint32_t>(ns));
  if (!comment.empty()) option(b, 1, comment);  // opt_comment
  option(b, 4, u64(received));                  // isb_ifrecv
  option(b, 5, u64(dropped));                   // isb_ifdrop
  option(b, 8, u64(received - dropped));        // isb_usrdeliv
  u32(b, 0);
  return block(0x00000005, b);
}

std::string file(const std::vector<Traced>& frames, std::string_view interface, std::string_view application) {
  std::string out = section_header(application) + interface_description(interface);
  out.reserve(out.size() + frames.size() * 108);
  for (const auto& t : frames) out += enhanced_packet(t);
  return out;
}

}  // namespace pcapng

}  // namespace gateway::trace
