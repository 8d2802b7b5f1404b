// What every REST route file (rest_api, trace_routes, history_routes) checks
// and writes the same way: the network and node of the path with their
// 400/404 texts, the 406 of a JSON-only answer, problem responses and
// timestamps. One place, so a route added in its own file cannot word them
// differently.
//
// Thread safety: none needed (pure functions; App read on its thread).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "app.hpp"
#include "http_server.hpp"
#include "request_codec.hpp"

namespace gateway {

inline constexpr std::string_view kProtobuf = "application/x-protobuf";

bool header_contains(std::optional<std::string_view> header, std::string_view what);
// Only protobuf is acceptable to the client (no JSON, no wildcard): a route
// that has no protobuf message answers 406 rather than JSON it cannot read.
bool accepts_only_protobuf(const http::Request& r);
// That 406.
http::Response json_only_refusal();

// An encoded reply (request_codec.hpp) as the HTTP response, Retry-After included.
http::Response from_reply(Reply reply);
// problem+json (or the protobuf Problem) with `status` and `detail`.
http::Response problem_response(int status, std::string_view detail, bool protobuf = false);

// The network of the path, or the detail of its 400 (not a number).
std::optional<std::uint32_t> path_network(const http::Request& req, std::string& error);
// The node of the path, or the detail of its 400.
std::optional<std::uint8_t> path_node(const http::Request& req, bool allow_zero, std::string& error);
// Network and node from the path for the routes the request core does not
// serve: nullopt when fine, else the error response (400, or 404 for a
// network that is not configured).
std::optional<http::Response> check_net(const App& app, const http::Request& req, std::uint32_t& net,
                                        bool protobuf = false);
std::optional<http::Response> check_node(const http::Request& req, std::uint8_t& node, bool allow_zero,
                                         bool protobuf = false);

// RFC 3339 UTC with nanoseconds, as the events write it, without quotes.
std::string timestamp_text(WallTime t);

}  // namespace gateway
