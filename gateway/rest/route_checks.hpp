// What every REST route file (rest_api, trace_routes, history_routes) checks
// and writes the same way: the network and node of the path with their
// 400/404 texts, the 406 of a JSON-only answer, problem responses and
// timestamps; and how a route hands a request to the request core and
// answers with its result. One place, so a route added in its own file
// cannot word them differently.
//
// Thread safety: none needed (pure functions; the status view read on its thread).
#pragma once

#include <boost/json/value.hpp>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "core/request_core.hpp"
#include "http/http_server.hpp"
#include "messages/request_codec.hpp"
#include "status/view.hpp"

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
std::optional<http::Response> check_net(const status::View& status, const http::Request& req, std::uint32_t& net,
                                        bool protobuf = false);
std::optional<http::Response> check_node(const http::Request& req, std::uint8_t& node, bool allow_zero,
                                         bool protobuf = false);

// RFC 3339 UTC with nanoseconds, as the events write it, without quotes.
std::string timestamp_text(WallTime t);

// `v` serialized as an application/json response.
http::Response json_response(const boost::json::value& v, int status = 200);
// Bytes as the API writes them (core/format.hpp).
std::string hex_text(std::span<const std::uint8_t> bytes);

// ---- requests for the request core -------------------------------------------
// The path and body decode into one core::Request; the core answers it
// (ranges, roles, limits, audit) and the result is encoded by the route.

// The caller as the HTTP authorizer established it. Without an authorizer
// the server is open, and the request is too.
core::Caller rest_caller(const http::Request& req);
// The network of the path: its number (the core checks that it exists), or
// the 400 for one that is not a number (answered through `respond`).
std::optional<std::uint32_t> path_network(const http::Request& req, http::Responder& respond, bool protobuf = false);
// A request of the REST caller on network `net`; checks the bus (503 while it is off or down).
core::Request core_request(const http::Request& req, std::uint32_t net, core::Command command);
core::Undecodable undecodable(core::Operation op, std::uint8_t node, std::string detail, bool in_address);

// The result of a JSON-only command: `ok` writes the success.
template <typename Success, typename Ok>
core::RequestCore::Done json_result(http::Responder respond, Ok ok) {
  return [respond, ok](core::Result result) {
    if (const auto* s = std::get_if<Success>(&result)) return respond(json_response(ok(*s)));
    if (const auto* p = std::get_if<core::Problem>(&result)) return respond(from_reply(encode_problem(*p)));
    respond(problem_response(500, "unexpected result"));
  };
}

}  // namespace gateway
