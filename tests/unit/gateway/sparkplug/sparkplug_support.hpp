// Helpers of the Sparkplug unit tests: a temp state dir, and decoding with
// the generated parser (independent of the hand-written writer).
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <string>
#include <string_view>

#include "sparkplug_b.pb.h"

namespace sparkplug_test {

namespace pb = org::eclipse::tahu::protobuf;

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "spb-test-XXXXXX").string();
    path_ = ::mkdtemp(tmpl.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Parses `bytes` as a Payload; an empty Payload with seq 9999 marks a
// parse failure (no real payload has it).
inline pb::Payload parse(std::string_view bytes) {
  pb::Payload p;
  if (!p.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
    p.Clear();
    p.set_seq(9999);
  }
  return p;
}

inline const pb::Payload::Metric* metric(const pb::Payload& p, std::string_view name) {
  for (const auto& m : p.metrics())
    if (m.name() == name) return &m;
  return nullptr;
}
// The metric would point into a destroyed temporary.
const pb::Payload::Metric* metric(const pb::Payload&&, std::string_view) = delete;

}  // namespace sparkplug_test
