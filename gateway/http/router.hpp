// Route table: (method, pattern) -> handler, with path parameters.
//
// A pattern is a path whose segments are literals or "{name}", e.g.
// "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}". A parameter
// matches exactly one non-empty segment. Matching is on the decoded path,
// segment by segment, exact (a trailing slash is a different path). When
// several patterns match, the most specific wins: the one with a literal
// where the other has a parameter, leftmost segment first.
//
// Thread safety: none; the server uses it on the io_context thread.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "http/http_types.hpp"

namespace gateway::http {

class Router {
 public:
  // Throws std::invalid_argument on a malformed pattern (no leading '/',
  // empty or unterminated "{}") or a duplicate (method, pattern).
  void add(std::string method, std::string_view pattern, Handler handler, RouteOptions options = {});

  struct Match {
    enum class Kind { Found, NotFound, MethodNotAllowed } kind = Kind::NotFound;
    const Handler* handler = nullptr;  // Found
    const RouteOptions* options = nullptr;  // Found
    std::string pattern;               // Found: the route's pattern
    std::map<std::string, std::string, std::less<>> params;
    std::string allow;  // MethodNotAllowed: "GET, PUT"
  };
  // `segments` is the decoded path split at '/', without the leading empty
  // segment ("/a/b" -> {"a","b"}; "/" -> {}). HEAD falls back to GET.
  Match match(std::string_view method, const std::vector<std::string>& segments) const;

  bool empty() const { return routes_.empty(); }
  // (method, pattern) of every route, in the order added.
  std::vector<std::pair<std::string, std::string>> list() const;

 private:
  struct Segment {
    std::string text;  // literal text or parameter name
    bool param = false;
  };
  struct Route {
    std::string method;
    std::string pattern;
    std::vector<Segment> segments;
    Handler handler;
    RouteOptions options;
  };
  static bool matches(const Route& r, const std::vector<std::string>& segs);
  static bool more_specific(const Route& a, const Route& b);

  std::vector<Route> routes_;
};

}  // namespace gateway::http
