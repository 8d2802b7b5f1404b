// The PDO value history route (issue 18; docs/reference/rest.md "PDO value
// history"; role viewer), answered from the status view's history
// (history/value_history.hpp):
//
//   GET /api/v1/networks/{net}/nodes/{node}/history?window=S[&objects=6401:01,6000:01]
//
// S = 60..86400 seconds (default 600), served at 1-s resolution up to
// 600 s, 10-s up to 3600 s, 60-s above; objects = comma-separated IIII:SS
// hex (default: every object the node has history for). 400 for a bad
// window or list, 404 for an unknown network or with history off
// (history.max-bytes: 0).
//
// Thread safety: io_context thread, as the server and the status view.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "history/value_history.hpp"
#include "http/http_server.hpp"
#include "status/view.hpp"

namespace gateway {

// Adds the route. `status` MUST outlive the server's use of it.
void register_history_routes(http::HttpServer& server, const status::View& status);

// "6401:01,6000:01" -> the objects; nullopt (and `error` says why) for an
// empty item, a missing colon or other than 4 + 2 hex digits.
std::optional<std::vector<history::ObjectId>> parse_history_objects(std::string_view text, std::string& error);

}  // namespace gateway
