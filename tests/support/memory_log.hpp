// A FILE* whose text a test can read: hand `file` to a Logger, then check
// text(). Not thread safe; read it after the logging thread is done.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

struct MemoryLog {
  MemoryLog() : file(open_memstream(&buf, &len)) {}
  ~MemoryLog() {
    std::fclose(file);
    std::free(buf);
  }
  MemoryLog(const MemoryLog&) = delete;
  MemoryLog& operator=(const MemoryLog&) = delete;
  std::string text() {
    std::fflush(file);
    return std::string(buf, len);
  }
  char* buf = nullptr;
  std::size_t len = 0;
  std::FILE* file;
};
