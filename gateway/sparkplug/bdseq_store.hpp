// The Sparkplug birth/death sequence number (bdSeq) kept in state-dir, so
// that it goes up by one with every MQTT CONNECT across restarts and kill -9
// (contract "Sparkplug B"; facts A.5: hosts and the TCK pair NDEATH with
// NBIRTH by bdSeq and flag a restarted edge node that begins at 0 again).
//
// File <state-dir>/sparkplug-bdseq: the bdSeq of the latest CONNECT, 0..255
// in decimal, and a newline. next() writes the new value durably (temp file,
// fsync, rename, fsync of the directory: gateway/state_file.hpp)
// before it returns, i.e. before the CONNECT that carries it in its Will is
// sent: a crash at any point leaves either the old or the new value, so the
// next run never reuses a bdSeq a broker may already hold as a Will.
//
// A missing file starts at 0; an unreadable one (not a number in 0..255)
// also starts at 0 and says so in `note`, for the log.
//
// Thread safety: none; one owner thread. Blocking file I/O on the caller's
// thread: one small write and two fsyncs per CONNECT.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>

namespace gateway::sparkplug {

class BdSeqStore {
 public:
  // dir "": nothing is kept (tests, tools); every run starts at 0.
  explicit BdSeqStore(std::filesystem::path dir);

  struct Next {
    std::uint8_t bd_seq = 0;
    std::string note;       // why the stored value was not used ("" if it was, or none existed)
    std::error_code error;  // it could not be stored: it is used all the same (in memory)
  };
  // The bdSeq for the CONNECT about to be sent: the stored one + 1 (255
  // wraps to 0), or 0 on the first CONNECT ever. Call once per CONNECT
  // attempt, before sending it.
  Next next();

  // The bdSeq of the latest next(), if any in this run.
  std::optional<std::uint8_t> current() const { return current_; }
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  std::optional<std::uint8_t> current_;
  bool read_ = false;
};

}  // namespace gateway::sparkplug
