// Static files of the dashboard, served from one directory (web/):
//   GET /               -> <root>/index.html
//   GET /favicon.ico    -> <root>/favicon.ico
//   GET /static/<path>  -> <root>/<path>
// Refused (404): any decoded segment that is empty, ".", "..", or contains
// '/', '\\' or NUL; hidden files (".x"); anything that resolves (through
// symlinks) outside <root>; directories; files over max_bytes.
//
// Thread safety: stateless functions; reads the file system synchronously
// (dashboard files are small and local).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace gateway::http {

// True when `segments` (decoded path, see Router::match) is a static path.
bool is_static_path(const std::vector<std::string>& segments);

// Content type by file extension, e.g. "text/html; charset=utf-8";
// "application/octet-stream" when unknown.
std::string_view content_type_for(const std::filesystem::path& file);

enum class StaticResult { Ok, NotFound };

// Reads the file for a static path into `body` and sets `content_type`.
StaticResult load_static_file(const std::filesystem::path& root, const std::vector<std::string>& segments,
                              std::size_t max_bytes, std::string& body, std::string& content_type);

}  // namespace gateway::http
