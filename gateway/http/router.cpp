#include "http/router.hpp"

#include <stdexcept>

namespace gateway::http {

void Router::add(std::string method, std::string_view pattern, Handler handler, RouteOptions options) {
  if (pattern.empty() || pattern.front() != '/') throw std::invalid_argument("route pattern must start with '/'");
  Route r;
  r.method = std::move(method);
  r.pattern = std::string(pattern);
  std::string_view rest = pattern.substr(1);
  while (!rest.empty()) {
    auto slash = rest.find('/');
    std::string_view seg = rest.substr(0, slash);
    rest = slash == std::string_view::npos ? std::string_view{} : rest.substr(slash + 1);
    Segment s;
    if (!seg.empty() && seg.front() == '{') {
      if (seg.size() < 3 || seg.back() != '}') throw std::invalid_argument("bad route parameter in " + r.pattern);
      s.param = true;
      s.text = std::string(seg.substr(1, seg.size() - 2));
    } else {
      if (seg.find_first_of("{}") != std::string_view::npos)
        throw std::invalid_argument("bad route segment in " + r.pattern);
      s.text = std::string(seg);
    }
    r.segments.push_back(std::move(s));
  }
  for (const auto& o : routes_)
    if (o.method == r.method && o.pattern == r.pattern) throw std::invalid_argument("duplicate route " + r.pattern);
  r.handler = std::move(handler);
  r.options = std::move(options);
  routes_.push_back(std::move(r));
}

bool Router::matches(const Route& r, const std::vector<std::string>& segs) {
  if (r.segments.size() != segs.size()) return false;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const auto& s = r.segments[i];
    if (s.param ? segs[i].empty() : s.text != segs[i]) return false;
  }
  return true;
}

bool Router::more_specific(const Route& a, const Route& b) {
  for (std::size_t i = 0; i < a.segments.size() && i < b.segments.size(); ++i) {
    if (a.segments[i].param != b.segments[i].param) return !a.segments[i].param;
  }
  return false;
}

Router::Match Router::match(std::string_view method, const std::vector<std::string>& segments) const {
  Match m;
  const Route* best = nullptr;
  auto pick = [&](std::string_view want) {
    for (const auto& r : routes_)
      if (r.method == want && matches(r, segments) && (!best || more_specific(r, *best))) best = &r;
  };
  pick(method);
  if (!best && method == "HEAD") pick("GET");
  if (best) {
    m.kind = Match::Kind::Found;
    m.handler = &best->handler;
    m.options = &best->options;
    m.pattern = best->pattern;
    for (std::size_t i = 0; i < segments.size(); ++i)
      if (best->segments[i].param) m.params.emplace(best->segments[i].text, segments[i]);
    return m;
  }
  // The path is known under other methods: 405 listing them.
  std::vector<std::string_view> allow;
  for (const auto& r : routes_) {
    if (!matches(r, segments)) continue;
    bool seen = false;
    for (auto a : allow) seen = seen || a == r.method;
    if (!seen) allow.push_back(r.method);
    if (r.method == "GET" && !seen) allow.push_back("HEAD");
  }
  if (allow.empty()) return m;
  m.kind = Match::Kind::MethodNotAllowed;
  for (auto a : allow) {
    if (!m.allow.empty()) m.allow += ", ";
    m.allow += a;
  }
  return m;
}

std::vector<std::pair<std::string, std::string>> Router::list() const {
  std::vector<std::pair<std::string, std::string>> out;
  out.reserve(routes_.size());
  for (const auto& r : routes_) out.emplace_back(r.method, r.pattern);
  return out;
}

}  // namespace gateway::http
