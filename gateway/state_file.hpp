// Small numbers kept in state-dir across restarts and crashes (the event
// sequence, seq_store.hpp; the Sparkplug bdSeq, sparkplug/bdseq_store.hpp):
// one decimal number and a newline per file.
//
// Thread safety: free functions without shared state; blocking file I/O on
// the caller's thread.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string_view>
#include <system_error>

namespace gateway {

// Writes `text` to `file` so that after a crash or power loss the file holds
// either the old content or the new one, never a mix: a temp file beside it,
// fsync, rename, fsync of the directory.
std::error_code write_durably(const std::filesystem::path& file, std::string_view text);

enum class NumberFile : std::uint8_t { Ok, Missing, Unreadable };

// The file's number: decimal digits and a newline, nothing else (at most 31
// bytes). Missing when the file does not exist; Unreadable when it cannot be
// read or holds anything else. Callers apply their own range.
NumberFile read_number_file(const std::filesystem::path& file, std::uint64_t& value);

}  // namespace gateway
