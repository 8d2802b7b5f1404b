#include "http/request_checks.hpp"

#include <boost/asio/ip/address.hpp>
#include <stdexcept>

namespace gateway::http {

namespace {

char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (lower(a[i]) != lower(b[i])) return false;
  return true;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

// Port digits ("" = none, as RFC 3986 allows "host:").
bool parse_port(std::string_view s, std::optional<std::uint16_t>& out) {
  if (s.empty()) return true;
  if (!all_digits(s) || s.size() > 5) return false;
  unsigned v = 0;
  for (char c : s) v = v * 10 + static_cast<unsigned>(c - '0');
  if (v > 65535) return false;
  out = static_cast<std::uint16_t>(v);
  return true;
}

bool name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '.' ||
         c == '_' || c == '~';
}

std::string canonical_ip(const boost::asio::ip::address& a) {
  return a.is_v6() ? "[" + a.to_string() + "]" : a.to_string();
}

std::uint16_t default_port(std::string_view scheme) { return scheme == "https" ? 443 : 80; }

}  // namespace

std::optional<HostPort> parse_host(std::string_view value) {
  namespace ip = boost::asio::ip;
  value = trim(value);
  if (value.empty()) return std::nullopt;
  HostPort out;
  boost::system::error_code ec;
  if (value.front() == '[') {
    const auto close = value.find(']');
    if (close == std::string_view::npos) return std::nullopt;
    const auto inside = value.substr(1, close - 1);
    // No zone identifiers: they have no meaning in a Host header.
    if (inside.empty() || inside.find('%') != std::string_view::npos) return std::nullopt;
    const auto v6 = ip::make_address_v6(std::string(inside), ec);
    if (ec) return std::nullopt;
    const auto rest = value.substr(close + 1);
    if (!rest.empty() && (rest.front() != ':' || !parse_port(rest.substr(1), out.port))) return std::nullopt;
    out.host = canonical_ip(ip::address(v6));
    out.ip_literal = true;
    return out;
  }
  auto name = value;
  if (const auto colon = value.find(':'); colon != std::string_view::npos) {
    name = value.substr(0, colon);
    if (!parse_port(value.substr(colon + 1), out.port)) return std::nullopt;  // also a second ':'
  }
  if (name.size() > 1 && name.back() == '.') name.remove_suffix(1);  // "localhost." is "localhost"
  if (name.empty() || name.size() > 253) return std::nullopt;
  for (char c : name)
    if (!name_char(c)) return std::nullopt;
  const auto v4 = ip::make_address_v4(std::string(name), ec);
  if (!ec) {
    out.host = v4.to_string();
    out.ip_literal = true;
    return out;
  }
  out.host.reserve(name.size());
  for (char c : name) out.host.push_back(lower(c));
  return out;
}

std::optional<Origin> parse_origin(std::string_view value) {
  value = trim(value);
  const auto sep = value.find("://");
  if (sep == std::string_view::npos) return std::nullopt;
  Origin o;
  for (char c : value.substr(0, sep)) o.scheme.push_back(lower(c));
  if (o.scheme != "http" && o.scheme != "https") return std::nullopt;
  const auto authority = value.substr(sep + 3);
  if (authority.find_first_of("/?#@") != std::string_view::npos) return std::nullopt;
  auto h = parse_host(authority);
  if (!h) return std::nullopt;
  o.host = std::move(h->host);
  o.port = h->port.value_or(default_port(o.scheme));
  return o;
}

std::optional<std::string> framing_error(const HeaderFields& fields, unsigned version) {
  int hosts = 0, authorizations = 0, encodings = 0;
  std::optional<std::string_view> encoding;
  std::optional<std::string_view> length;
  for (const auto& [name, value] : fields) {
    if (iequals(name, "host")) {
      ++hosts;
    } else if (iequals(name, "authorization")) {
      ++authorizations;
    } else if (iequals(name, "transfer-encoding")) {
      ++encodings;
      encoding = value;
    } else if (iequals(name, "content-length")) {
      // Each field may itself be a list ("5, 5"): every element must be
      // the same number.
      std::string_view rest = value;
      while (true) {
        const auto comma = rest.find(',');
        const auto item = trim(rest.substr(0, comma));
        if (!all_digits(item)) return "Content-Length '" + std::string(value) + "' is not a number";
        if (length && *length != item) return "conflicting Content-Length values";
        length = item;
        if (comma == std::string_view::npos) break;
        rest.remove_prefix(comma + 1);
      }
    }
  }
  if (hosts > 1) return std::string("more than one Host header field");
  if (authorizations > 1) return std::string("more than one Authorization header field");
  if (encodings > 0) {
    if (encodings > 1 || !iequals(trim(*encoding), "chunked"))
      return std::string("Transfer-Encoding other than 'chunked' is not supported");
    if (length) return std::string("both Transfer-Encoding and Content-Length");
    if (version < 11) return std::string("Transfer-Encoding in an HTTP/1.0 request");
  }
  return std::nullopt;
}

bool is_state_changing(std::string_view method) { return method != "GET" && method != "HEAD" && method != "OPTIONS"; }

bool acceptable_body_type(std::optional<std::string_view> content_type, bool has_body,
                          const std::vector<std::string>& extra) {
  if (!content_type) return !has_body;
  const auto media = trim(content_type->substr(0, content_type->find(';')));
  if (iequals(media, "application/json") || iequals(media, "application/x-protobuf")) return true;
  for (const auto& e : extra)
    if (iequals(media, e)) return true;
  return false;
}

OriginPolicy::OriginPolicy(Settings s) {
  namespace ip = boost::asio::ip;
  if (s.listen_address == "localhost") {
    ips_ = {"127.0.0.1", "[::1]"};
    names_.insert("localhost");
  } else {
    boost::system::error_code ec;
    const auto a = ip::make_address(s.listen_address, ec);
    if (ec) throw std::invalid_argument("listen address '" + s.listen_address + "' is not an IP address");
    if (a.is_unspecified()) {
      any_ip_ = true;
      names_.insert("localhost");
      if (auto m = parse_host(s.machine_name); m && !m->ip_literal && !m->port) names_.insert(m->host);
    } else {
      ips_.insert(canonical_ip(a));
      if (a.is_loopback()) {
        ips_.insert("127.0.0.1");
        ips_.insert("[::1]");
        names_.insert("localhost");
      }
    }
  }
  for (const auto& n : s.host_names) {
    auto h = parse_host(n);
    if (!h || h->port) throw std::invalid_argument("http.host-names: '" + n + "' is not a host name or IP address");
    (h->ip_literal ? ips_ : names_).insert(h->host);
  }
  for (const auto& o : s.allowed_origins) {
    if (o == "*") {
      any_origin_ = true;
      continue;
    }
    auto p = parse_origin(o);
    if (!p) throw std::invalid_argument("http.allowed-origins: '" + o + "' is not an origin like https://host:port");
    origins_.insert(p->canonical());
  }
}

OriginPolicy::HostVerdict OriginPolicy::check_host(std::optional<std::string_view> host, unsigned version) const {
  if (!host) return version >= 11 ? HostVerdict::Missing : HostVerdict::Own;
  const auto h = parse_host(*host);
  if (!h) return HostVerdict::Malformed;
  if (h->ip_literal) return any_ip_ || ips_.contains(h->host) ? HostVerdict::Own : HostVerdict::Foreign;
  return names_.contains(h->host) ? HostVerdict::Own : HostVerdict::Foreign;
}

bool OriginPolicy::origin_allowed(std::string_view origin, std::optional<std::string_view> host, bool tls) const {
  if (any_origin_) return true;
  const auto o = parse_origin(origin);
  if (!o) return false;  // "null" (sandboxed frames, files), other schemes, garbage
  if (origins_.contains(o->canonical())) return true;
  if (!host) return false;
  const auto h = parse_host(*host);
  if (!h) return false;
  const std::string_view scheme = tls ? "https" : "http";
  return o->scheme == scheme && o->host == h->host && o->port == h->port.value_or(default_port(scheme));
}

}  // namespace gateway::http
