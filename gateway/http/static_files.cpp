#include "http/static_files.hpp"

#include <algorithm>
#include <fstream>
#include <system_error>

namespace gateway::http {

namespace fs = std::filesystem;

bool is_static_path(const std::vector<std::string>& segments) {
  if (segments.empty()) return true;
  if (segments.size() == 1 && segments[0] == "favicon.ico") return true;
  return segments.size() >= 2 && segments[0] == "static";
}

std::string_view content_type_for(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html" || ext == ".htm") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".gif") return "image/gif";
  if (ext == ".ico") return "image/x-icon";
  if (ext == ".webp") return "image/webp";
  if (ext == ".woff2") return "font/woff2";
  if (ext == ".woff") return "font/woff";
  if (ext == ".txt") return "text/plain; charset=utf-8";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".proto") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

StaticResult load_static_file(const fs::path& root, const std::vector<std::string>& segments, std::size_t max_bytes,
                              std::string& body, std::string& content_type) {
  if (!is_static_path(segments) || root.empty()) return StaticResult::NotFound;
  fs::path rel;
  if (segments.empty()) {
    rel = "index.html";
  } else {
    std::size_t first = segments[0] == "static" ? 1 : 0;
    for (std::size_t i = first; i < segments.size(); ++i) {
      const std::string& s = segments[i];
      // Checked on the decoded segment so "%2e%2e" and "%2F" are caught too.
      if (s.empty() || s.front() == '.' || s.find_first_of(std::string_view("/\\\0", 3)) != std::string::npos)
        return StaticResult::NotFound;
      rel /= s;
    }
  }
  std::error_code ec;
  const fs::path base = fs::canonical(root, ec);
  if (ec) return StaticResult::NotFound;
  const fs::path file = fs::canonical(base / rel, ec);
  if (ec) return StaticResult::NotFound;
  // A symlink may still point outside the root.
  auto [b, f] = std::mismatch(base.begin(), base.end(), file.begin(), file.end());
  if (b != base.end()) return StaticResult::NotFound;
  if (!fs::is_regular_file(file, ec)) return StaticResult::NotFound;
  const auto size = fs::file_size(file, ec);
  if (ec || size > max_bytes) return StaticResult::NotFound;
  std::ifstream in(file, std::ios::binary);
  if (!in) return StaticResult::NotFound;
  body.resize(static_cast<std::size_t>(size));
  in.read(body.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) return StaticResult::NotFound;
  content_type = std::string(content_type_for(file));
  return StaticResult::Ok;
}

}  // namespace gateway::http
