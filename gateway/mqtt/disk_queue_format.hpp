// Internal to DiskQueue (disk_queue.cpp, disk_queue_replay.cpp): the
// on-disk format the header describes (record and position-slot sizes, the
// CRC-32, little-endian fields, segment file names) and whole positional
// reads and writes. Not for use outside gateway/mqtt/. Pure functions
// (pread_all/pwrite_all: the caller's file descriptor).
#pragma once

#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace gateway::mqtt::disk_format {

constexpr std::size_t kHeader = 8;             // u32 length + u32 CRC
constexpr std::size_t kBodyFixed = 12;         // seq, qos, flags, topic length
constexpr std::uint32_t kMaxBody = 256u << 20; // sanity bound when reading
constexpr std::size_t kSlot = 24;

// CRC-32 (IEEE, reflected 0xEDB88320: the same value as boost::crc_32_type,
// so existing files stay readable), 8 bytes per step with 8 tables: every
// message is checksummed on push, the byte-wise loop cost ~10 instructions
// a byte on the publish path.
struct Crc32Tables {
  std::uint32_t t[8][256];
  constexpr Crc32Tables() : t{} {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
      t[0][i] = c;
    }
    for (std::uint32_t i = 0; i < 256; ++i)
      for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  }
};
inline constexpr Crc32Tables kCrc;

inline std::uint32_t crc32(const char* data, std::size_t n) {
  const auto* p = reinterpret_cast<const unsigned char*>(data);
  std::uint32_t c = 0xFFFFFFFFu;
  for (; n >= 8; n -= 8, p += 8) {
    const std::uint32_t lo = c ^ (std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
                                  std::uint32_t{p[3]} << 24);
    const std::uint32_t hi = std::uint32_t{p[4]} | std::uint32_t{p[5]} << 8 | std::uint32_t{p[6]} << 16 |
                             std::uint32_t{p[7]} << 24;
    c = kCrc.t[7][lo & 0xFF] ^ kCrc.t[6][(lo >> 8) & 0xFF] ^ kCrc.t[5][(lo >> 16) & 0xFF] ^ kCrc.t[4][lo >> 24] ^
        kCrc.t[3][hi & 0xFF] ^ kCrc.t[2][(hi >> 8) & 0xFF] ^ kCrc.t[1][(hi >> 16) & 0xFF] ^ kCrc.t[0][hi >> 24];
  }
  for (; n > 0; --n, ++p) c = (c >> 8) ^ kCrc.t[0][(c ^ *p) & 0xFF];
  return c ^ 0xFFFFFFFFu;
}

inline void put_le(char* p, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) p[i] = static_cast<char>((v >> (8 * i)) & 0xff);
}
inline std::uint64_t get_le(const char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= std::uint64_t{static_cast<unsigned char>(p[i])} << (8 * i);
  return v;
}

// Repeats a positional read or write until all n bytes are done (short
// transfers, EINTR); false on an error or end of file.
template <typename Ptr, typename Syscall>
bool all_at(Syscall call, int fd, Ptr p, std::size_t n, std::uint64_t off) {
  while (n > 0) {
    ssize_t r = call(fd, p, n, static_cast<off_t>(off));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    n -= static_cast<std::size_t>(r);
    off += static_cast<std::uint64_t>(r);
  }
  return true;
}
inline bool pread_all(int fd, char* p, std::size_t n, std::uint64_t off) { return all_at(::pread, fd, p, n, off); }
inline bool pwrite_all(int fd, const char* p, std::size_t n, std::uint64_t off) { return all_at(::pwrite, fd, p, n, off); }

inline std::string segment_name(std::uint64_t first) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%020llu.seg", static_cast<unsigned long long>(first));
  return buf;
}

}  // namespace gateway::mqtt::disk_format
