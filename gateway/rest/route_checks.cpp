#include "rest/route_checks.hpp"

#include <boost/json/serialize.hpp>

#include "auth/auth.hpp"
#include "core/format.hpp"
#include "messages/json_text.hpp"
#include "messages/request_codec.hpp"
#include "rest/rest_parse.hpp"

namespace gateway {

using http::Request;
using http::Response;

bool header_contains(std::optional<std::string_view> header, std::string_view what) {
  return header && header->find(what) != std::string_view::npos;
}

bool accepts_only_protobuf(const Request& r) {
  const auto accept = r.header("accept");
  return header_contains(accept, kProtobuf) && !header_contains(accept, "json") && !header_contains(accept, "*/*") &&
         !header_contains(accept, "application/*");
}

Response json_only_refusal() {
  return problem_response(406, "this resource is JSON only (application/json); no protobuf message");
}

Response from_reply(Reply reply) {
  Response r;
  r.status = reply.status;
  r.content_type = std::move(reply.content_type);
  r.body = std::move(reply.body);
  if (reply.retry_after > 0) r.headers.emplace_back("Retry-After", std::to_string(reply.retry_after));
  return r;
}

Response problem_response(int status, std::string_view detail, bool protobuf) {
  ReplyOptions opts;
  opts.protobuf = protobuf;
  return from_reply(problem(status, detail, opts));
}

std::optional<std::uint32_t> path_network(const Request& req, std::string& error) {
  auto n = rest::parse_decimal(req.param("net"));
  if (!n) error = "network must be a decimal number, not '" + std::string(req.param("net")) + "'";
  return n;
}

std::optional<std::uint8_t> path_node(const Request& req, bool allow_zero, std::string& error) {
  auto n = rest::parse_decimal(req.param("node"));
  if (!n || *n > 127 || (*n == 0 && !allow_zero)) {
    error = "node-ID must be " + std::string(allow_zero ? "0..127" : "1..127") + ", not '" +
            std::string(req.param("node")) + "'";
    return std::nullopt;
  }
  return static_cast<std::uint8_t>(*n);
}

std::optional<Response> check_net(const status::View& status, const Request& req, std::uint32_t& net, bool protobuf) {
  std::string error;
  auto n = path_network(req, error);
  if (!n) return problem_response(400, error, protobuf);
  if (*n == 0 || *n > status.networks().size())
    return problem_response(404,
                            "network " + std::to_string(*n) + " is not configured (networks are 1.." +
                                std::to_string(status.networks().size()) + ")",
                            protobuf);
  net = *n;
  return std::nullopt;
}

std::optional<Response> check_node(const Request& req, std::uint8_t& node, bool allow_zero, bool protobuf) {
  std::string error;
  auto n = path_node(req, allow_zero, error);
  if (!n) return problem_response(400, error, protobuf);
  node = *n;
  return std::nullopt;
}

std::string timestamp_text(WallTime t) {
  std::string out;
  detail::append_timestamp(out, detail::to_unix_time(t));
  if (out.size() >= 2 && out.front() == '"') out = out.substr(1, out.size() - 2);
  return out;
}

Response json_response(const boost::json::value& v, int status) {
  return Response::json(boost::json::serialize(v), status);
}

std::string hex_text(std::span<const std::uint8_t> bytes) { return core::hex_bytes(bytes); }

core::Caller rest_caller(const Request& req) {
  core::Caller c;
  c.transport = core::Transport::rest;
  c.authenticated = true;
  c.who = req.who;
  c.key = req.caller.empty() ? auth::address_caller(auth::peer_address(req.peer)) : req.caller;
  c.role = req.authorized ? static_cast<Role>(req.role) : Role::Admin;
  return c;
}

std::optional<std::uint32_t> path_network(const Request& req, http::Responder& respond, bool protobuf) {
  std::string error;
  auto n = path_network(req, error);  // the other overload
  if (!n) respond(problem_response(400, error, protobuf));
  return n;
}

core::Request core_request(const Request& req, std::uint32_t net, core::Command command) {
  core::Request r;
  r.caller = rest_caller(req);
  r.network = net;
  r.command = std::move(command);
  r.check_bus = true;  // REST answers 503 while the bus is off or down
  return r;
}

core::Undecodable undecodable(core::Operation op, std::uint8_t node, std::string detail, bool in_address) {
  return core::Undecodable{op, node, std::move(detail), in_address};
}

}  // namespace gateway
