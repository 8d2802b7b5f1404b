#include "canopen/can/frame.hpp"

#include <algorithm>
#include <cstring>

namespace canopen::can {
namespace {

constexpr std::array<std::uint8_t, 8> kFdLengthsAbove8{12, 16, 20, 24, 32, 48, 64, 64};
constexpr char kHex[] = "0123456789ABCDEF";

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::optional<std::uint32_t> parse_hex_u32(std::string_view s) {
  if (s.empty() || s.size() > 8) return std::nullopt;
  std::uint32_t v = 0;
  for (char c : s) {
    int d = hex_value(c);
    if (d < 0) return std::nullopt;
    v = (v << 4) | static_cast<std::uint32_t>(d);
  }
  return v;
}

// Parses "AABB.CC" style payloads (candump allows '.' separators).
bool parse_payload(std::string_view s, Frame& f, std::size_t max_len) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < s.size();) {
    if (s[i] == '.') { ++i; continue; }
    if (i + 1 >= s.size()) return false;
    int hi = hex_value(s[i]);
    int lo = hex_value(s[i + 1]);
    if (hi < 0 || lo < 0 || n >= max_len) return false;
    f.data[n++] = static_cast<std::uint8_t>((hi << 4) | lo);
    i += 2;
  }
  f.len = static_cast<std::uint8_t>(n);
  return true;
}

Frame make(std::uint32_t id, std::span<const std::uint8_t> bytes, bool ext) {
  Frame f;
  f.id = id;
  f.set(FrameFlag::Extended, ext);
  const std::size_t n = std::min(bytes.size(), kMaxFdLength);
  if (n > kMaxClassicLength) f.set(FrameFlag::Fd);
  std::copy_n(bytes.begin(), n, f.data.begin());
  f.len = static_cast<std::uint8_t>(n);
  return f;
}

}  // namespace

std::size_t fd_round_up_length(std::size_t len) {
  if (len <= 8) return len;
  for (std::uint8_t l : kFdLengthsAbove8) {
    if (len <= l) return l;
  }
  return kMaxFdLength;
}

bool is_valid_fd_length(std::size_t len) { return len <= kMaxFdLength && fd_round_up_length(len) == len; }

bool Frame::valid() const {
  if (id > (extended() ? kMaxExtendedId : kMaxStandardId)) return false;
  if (fd()) return !remote() && is_valid_fd_length(len);
  if (has(FrameFlag::BitRateSwitch) || has(FrameFlag::ErrorStateIndicator)) return false;
  return len <= kMaxClassicLength;
}

bool operator==(const Frame& a, const Frame& b) {
  if (a.id != b.id || a.flags != b.flags || a.len != b.len) return false;
  if (a.remote()) return true;
  return std::memcmp(a.data.data(), b.data.data(), a.len) == 0;
}

Frame Frame::standard(std::uint32_t id, std::span<const std::uint8_t> bytes) { return make(id, bytes, false); }
Frame Frame::standard(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  return make(id, {bytes.begin(), bytes.size()}, false);
}
Frame Frame::extended_id(std::uint32_t id, std::span<const std::uint8_t> bytes) { return make(id, bytes, true); }
Frame Frame::rtr(std::uint32_t id, std::uint8_t dlc, bool extended) {
  Frame f;
  f.id = id;
  f.set(FrameFlag::Extended, extended);
  f.set(FrameFlag::Remote);
  f.len = dlc;
  return f;
}

std::string to_string(const Frame& f) {
  std::string s;
  s.reserve(16 + 2 * f.len);
  const int id_digits = f.extended() ? 8 : 3;
  for (int i = id_digits - 1; i >= 0; --i) s.push_back(kHex[(f.id >> (4 * i)) & 0xF]);
  s.push_back('#');
  if (f.remote()) {
    s.push_back('R');
    // candump -L prints the DLC of remote frames only when it is non-zero.
    if (f.len != 0) s.push_back(kHex[f.len & 0xF]);
    return s;
  }
  if (f.fd()) {
    s.push_back('#');
    // Same nibble as candump -L: CANFD_FDF (4) | CANFD_ESI (2) | CANFD_BRS (1).
    unsigned fl = 4U | (f.has(FrameFlag::BitRateSwitch) ? 1U : 0U) | (f.has(FrameFlag::ErrorStateIndicator) ? 2U : 0U);
    s.push_back(kHex[fl]);
  }
  for (std::size_t i = 0; i < f.len; ++i) {
    s.push_back(kHex[f.data[i] >> 4]);
    s.push_back(kHex[f.data[i] & 0xF]);
  }
  return s;
}

std::optional<Frame> parse_frame(std::string_view text) {
  const auto hash = text.find('#');
  if (hash == std::string_view::npos) return std::nullopt;
  const std::string_view id_text = text.substr(0, hash);
  if (id_text.size() != 3 && id_text.size() != 8) return std::nullopt;
  auto id = parse_hex_u32(id_text);
  if (!id) return std::nullopt;
  Frame f;
  f.id = *id;
  f.set(FrameFlag::Extended, id_text.size() == 8);
  std::string_view rest = text.substr(hash + 1);
  if (!rest.empty() && (rest[0] == 'R' || rest[0] == 'r')) {
    f.set(FrameFlag::Remote);
    rest.remove_prefix(1);
    if (rest.size() > 1) return std::nullopt;
    if (rest.size() == 1) {
      int d = hex_value(rest[0]);
      if (d < 0 || d > 8) return std::nullopt;
      f.len = static_cast<std::uint8_t>(d);
    }
  } else if (!rest.empty() && rest[0] == '#') {
    f.set(FrameFlag::Fd);
    if (rest.size() < 2) return std::nullopt;
    int fl = hex_value(rest[1]);
    // cansend accepts the nibble with or without the FDF bit (4).
    if (fl < 0 || fl > 7) return std::nullopt;
    f.set(FrameFlag::BitRateSwitch, (fl & 1) != 0);
    f.set(FrameFlag::ErrorStateIndicator, (fl & 2) != 0);
    if (!parse_payload(rest.substr(2), f, kMaxFdLength)) return std::nullopt;
  } else if (!parse_payload(rest, f, kMaxClassicLength)) {
    return std::nullopt;
  }
  if (!f.valid()) return std::nullopt;
  return f;
}

}  // namespace canopen::can
