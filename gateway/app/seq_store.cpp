#include "seq_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <optional>
#include <string_view>

namespace gateway {

namespace {

std::error_code last_error() { return {errno, std::generic_category()}; }

// Writes `text` to `file` so that after a crash or power loss the file holds
// either the old content or the new one, never a mix.
std::error_code write_durably(const std::filesystem::path& file, std::string_view text) {
  const std::string tmp = file.string() + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return last_error();
  std::error_code ec;
  for (std::size_t done = 0; done < text.size() && !ec;) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno != EINTR) ec = last_error();
    if (n > 0) done += static_cast<std::size_t>(n);
  }
  if (!ec && ::fsync(fd) != 0) ec = last_error();
  if (::close(fd) != 0 && !ec) ec = last_error();
  if (!ec && ::rename(tmp.c_str(), file.c_str()) != 0) ec = last_error();
  if (ec) {
    ::unlink(tmp.c_str());
    return ec;
  }
  // The rename is durable once the directory is.
  const int dir = ::open(file.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) return last_error();
  if (::fsync(dir) != 0) ec = last_error();
  ::close(dir);
  return ec;
}

// The file's number: decimal digits and a newline, nothing else; nullopt
// when it cannot be read or holds anything else (0 included: seq starts at 1).
std::optional<std::uint64_t> read_number(const std::filesystem::path& file, bool& missing) {
  missing = false;
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    missing = errno == ENOENT;
    return std::nullopt;
  }
  char buf[32];
  std::size_t len = 0;
  for (;;) {
    const ssize_t n = ::read(fd, buf + len, sizeof buf - len);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    len += static_cast<std::size_t>(n);
    if (len == sizeof buf) break;
  }
  ::close(fd);
  std::string_view text(buf, len);
  if (text.empty() || text.back() != '\n') return std::nullopt;
  text.remove_suffix(1);
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || value == 0) return std::nullopt;
  return value;
}

}  // namespace

SeqStore::SeqStore(std::filesystem::path dir, std::uint32_t network, std::uint64_t block, WallClock wall)
    : file_(dir.empty() ? std::filesystem::path() : dir / ("seq-net" + std::to_string(network))),
      block_(std::max<std::uint64_t>(block, 1)),
      wall_(std::move(wall)) {}

SeqStore::Opened SeqStore::open() {
  Opened out;
  if (file_.empty()) {
    bound_ = UINT64_MAX;  // nothing to reserve
    return out;
  }
  bool missing = false;
  if (auto stored = read_number(file_, missing)) {
    out.first = *stored;
  } else {
    const auto us = std::chrono::duration_cast<std::chrono::microseconds>(wall_().time_since_epoch()).count();
    out.first = std::max<std::uint64_t>(1, us > 0 ? static_cast<std::uint64_t>(us) : 0);
    out.corrupt = !missing;
    out.note = std::string(missing ? "no stored seq in " : "stored seq unreadable in ") + file_.string() +
               ": starting at the wall-clock time in microseconds, " + std::to_string(out.first) +
               ", above any number an earlier run used";
  }
  bound_ = out.first + block_;
  out.error = store(bound_);
  return out;
}

std::error_code SeqStore::use(std::uint64_t seq) {
  if (file_.empty() || seq < bound_) return {};
  bound_ = seq + block_;
  return store(bound_);
}

std::error_code SeqStore::close(std::uint64_t next) {
  if (file_.empty()) return {};
  bound_ = next;
  return store(next);
}

std::error_code SeqStore::store(std::uint64_t value) { return write_durably(file_, std::to_string(value) + "\n"); }

}  // namespace gateway
