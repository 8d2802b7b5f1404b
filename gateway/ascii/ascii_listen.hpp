// Where the CiA 309-3 ASCII server listens (contract: `--ascii ADDR`,
// `ascii.listen`): "unix:/path" or an IP literal with a port
// ("127.0.0.1:60000", "[::1]:60000"; "localhost" is 127.0.0.1).
// Pure functions; thread-safe.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace gateway::ascii {

struct ListenAddress {
  bool unix_socket = false;
  std::string path;  // unix socket
  std::string host;  // IP literal
  std::uint16_t port = 0;
  // A unix socket or a loopback address: reachable from this machine only.
  bool local() const;
};

// nullopt when malformed (no port, a host name, an empty or too long path).
std::optional<ListenAddress> parse_listen_address(std::string_view text);

}  // namespace gateway::ascii
