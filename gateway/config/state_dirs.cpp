// check_state_dirs() (config.hpp): the directories the gateway writes are
// checked at start-up, so a wrong or read-only one is a configuration error
// (exit 2, one line) before anything listens, not a failure later.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <system_error>

#include "config/config.hpp"

namespace gateway {

namespace {

namespace fs = std::filesystem;

// Out of space is not a configuration error: the gateway runs on a full
// disk and drops by its policy until space returns.
bool full(const std::error_code& ec) { return ec == std::errc::no_space_on_device || ec.value() == EDQUOT; }

std::error_code probe(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return ec;
  if (!fs::is_directory(dir, ec)) return ec ? ec : std::make_error_code(std::errc::not_a_directory);
  // Access bits do not tell (root, read-only mounts, ACLs): create a file.
  const fs::path file = dir / (".write-test-" + std::to_string(::getpid()));
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return {errno, std::generic_category()};
  ::close(fd);
  ::unlink(file.c_str());
  return {};
}

void check(const std::string& dir, const std::string& key, const std::string& origin) {
  const auto ec = probe(dir);
  if (!ec || full(ec)) return;
  throw ConfigError((origin.empty() ? key : origin) + ": '" + dir + "' cannot be used: " + ec.message() +
                    " (the gateway keeps its state there; give a writable directory)");
}

}  // namespace

void check_state_dirs(const Config& c) {
  if (c.state_dir.empty()) return;
  check(c.state_dir, "gateway.state-dir", c.state_dir_origin);
  if (c.mqtt.enabled) check(c.mqtt.queue.dir.string(), "mqtt.queue.dir", c.queue_dir_origin);
}

}  // namespace gateway
