// http: (gateway::HttpConfig): listener, TLS, browser checks, tokens,
// rate limit.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>

#include "config/config_yaml.hpp"
#include "http/request_checks.hpp"

namespace gateway::config_yaml {

namespace fs = std::filesystem;

void parse_http(const At& a, HttpConfig& h, const std::string& dir) {
  a.expect_map({"listen", "tls", "host-names", "allowed-origins", "tokens", "auth", "plain-http", "rate-limit",
                "web-root", "max-connections", "max-connections-per-address", "max-program-bytes"});
  if (auto v = a.get("listen")) {
    if (!split_host_port(v->str(), h.address, h.port)) v->fail("'" + v->str() + "' is not ADDR:PORT");
    h.listen_origin = v->where() + " " + v->str();
  }
  if (auto t = a.get("tls")) {
    t->expect_map({"cert", "key"});
    auto cert = t->get("cert");
    auto key = t->get("key");
    if (!cert || !key) t->fail("needs both cert and key");
    h.tls_origin = t->where();
    h.cert_file = resolve(dir, cert->str());
    h.key_file = resolve(dir, key->str());
    std::error_code ec;
    if (!fs::is_regular_file(h.cert_file, ec)) cert->fail("file '" + h.cert_file.string() + "' not found");
    if (!fs::is_regular_file(h.key_file, ec)) key->fail("file '" + h.key_file.string() + "' not found");
  }
  if (auto n = a.get("host-names")) {
    for (const auto& item : n->items()) {
      const auto name = item.str();
      if (auto hp = http::parse_host(name); !hp || hp->port)
        item.fail("'" + name + "' is not a host name or IP address (without a port)");
      h.host_names.push_back(name);
    }
  }
  if (auto o = a.get("allowed-origins")) {
    for (const auto& item : o->items()) {
      const auto origin = item.str();
      if (origin != "*" && !http::parse_origin(origin))
        item.fail("'" + origin + "' is not an origin like https://host:port (or *)");
      h.allowed_origins.push_back(origin);
    }
  }
  if (auto v = a.get("max-connections")) h.max_connections = v->integer(1, 100'000);
  if (auto v = a.get("max-connections-per-address")) h.max_connections_per_address = v->integer(0, 100'000);
  if (auto v = a.get("max-program-bytes"))
    h.max_program_bytes = static_cast<std::size_t>(v->integer(1024, 1024ULL * 1024 * 1024));
  if (auto v = a.get("auth")) h.auth = v->boolean();
  if (auto v = a.get("plain-http")) h.plain_http = v->boolean();
  if (auto r = a.get("rate-limit")) {
    r->expect_map({"requests-per-second", "burst"});
    if (auto v = r->get("requests-per-second")) h.rate_limit = static_cast<double>(v->integer(0, 1'000'000));
    if (auto v = r->get("burst")) h.rate_burst = static_cast<double>(v->integer(1, 1'000'000));
    h.rate_burst = std::max(h.rate_burst, h.rate_limit);
  }
  if (auto v = a.get("web-root")) h.static_dir = resolve(dir, v->str());
  if (auto t = a.get("tokens")) {
    std::set<std::string> names;
    for (const auto& item : t->items()) {
      item.expect_map({"name", "role", "sha256"});
      TokenConfig tc;
      auto name = item.get("name");
      auto role = item.get("role");
      auto hash = item.get("sha256");
      if (!name || !role || !hash) item.fail("a token needs name, role and sha256");
      tc.name = name->str();
      if (!names.insert(tc.name).second) name->fail("token name '" + tc.name + "' is used twice");
      tc.role = parse_role(*role);
      tc.sha256 = hash->str();
      std::transform(tc.sha256.begin(), tc.sha256.end(), tc.sha256.begin(),
                     [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); });
      if (tc.sha256.size() != 64 || tc.sha256.find_first_not_of("0123456789abcdef") != std::string::npos)
        hash->fail("not a hex SHA-256 (64 hex digits; store the hash, never the token)");
      h.tokens.push_back(std::move(tc));
    }
  }
}

}  // namespace gateway::config_yaml
