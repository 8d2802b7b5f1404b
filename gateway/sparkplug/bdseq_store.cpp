#include "sparkplug/bdseq_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <string_view>

namespace gateway::sparkplug {

namespace {

std::error_code last_error() { return {errno, std::generic_category()}; }

// After a crash or power loss the file holds the old content or the new
// one, never a mix. (The same steps as gateway/app/seq_store.cpp; a shared
// helper is for the wiring session, which may touch gateway/app.)
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
  const int dir = ::open(file.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) return last_error();
  if (::fsync(dir) != 0) ec = last_error();
  ::close(dir);
  return ec;
}

enum class Read : std::uint8_t { Ok, Missing, Unreadable };

Read read_bdseq(const std::filesystem::path& file, std::uint8_t& value) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return errno == ENOENT ? Read::Missing : Read::Unreadable;
  char buf[16];
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
  if (text.empty() || text.back() != '\n') return Read::Unreadable;
  text.remove_suffix(1);
  unsigned v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v > 255) return Read::Unreadable;
  value = static_cast<std::uint8_t>(v);
  return Read::Ok;
}

}  // namespace

BdSeqStore::BdSeqStore(std::filesystem::path dir)
    : file_(dir.empty() ? std::filesystem::path() : dir / "sparkplug-bdseq") {}

BdSeqStore::Next BdSeqStore::next() {
  Next out;
  if (!read_) {
    read_ = true;
    std::uint8_t stored = 0;
    const Read r = file_.empty() ? Read::Missing : read_bdseq(file_, stored);
    if (r == Read::Ok) current_ = stored;
    if (r == Read::Unreadable)
      out.note = "stored Sparkplug bdSeq unreadable in " + file_.string() + ": starting at 0";
  }
  // uint8_t arithmetic: 255 + 1 wraps to 0 (spec ch4 bdseq-increment).
  out.bd_seq = current_ ? static_cast<std::uint8_t>(*current_ + 1) : std::uint8_t{0};
  current_ = out.bd_seq;
  if (!file_.empty()) out.error = write_durably(file_, std::to_string(out.bd_seq) + "\n");
  return out;
}

}  // namespace gateway::sparkplug
