// ascii: (AsciiConfig), the CiA 309-3 ASCII server.
#include "ascii/ascii_listen.hpp"
#include "config/config_yaml.hpp"

namespace gateway::config_yaml {

void parse_ascii(const At& a, AsciiConfig& ac) {
  a.expect_map({"listen", "allow-remote", "role", "idle-timeout-s", "max-clients"});
  ac.enabled = true;
  ac.listen_origin = a.where() + " (ascii.listen not set, default " + ac.listen + ")";
  if (auto v = a.get("listen")) {
    ac.listen = v->str();
    if (!ascii::parse_listen_address(ac.listen))
      v->fail("'" + ac.listen + "' is not ADDR:PORT (an IP address) or unix:/path");
    ac.listen_origin = v->where() + " " + ac.listen;
  }
  if (auto v = a.get("allow-remote")) ac.allow_remote = v->boolean();
  if (auto v = a.get("role")) ac.role = parse_role(*v);
  if (auto v = a.get("idle-timeout-s")) ac.idle_timeout = std::chrono::seconds(v->integer(0, 86400));
  if (auto v = a.get("max-clients")) ac.max_clients = v->integer(1, 1024);
}

}  // namespace gateway::config_yaml
