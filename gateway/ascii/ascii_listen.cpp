#include "ascii/ascii_listen.hpp"

#include <arpa/inet.h>
#include <sys/un.h>

#include <cstring>

#include "cli.hpp"

namespace gateway::ascii {

bool ListenAddress::local() const {
  if (unix_socket) return true;
  unsigned char a[16];
  if (::inet_pton(AF_INET, host.c_str(), a) == 1) return a[0] == 127;
  static constexpr unsigned char kLoop6[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  return ::inet_pton(AF_INET6, host.c_str(), a) == 1 && std::memcmp(a, kLoop6, 16) == 0;
}

std::optional<ListenAddress> parse_listen_address(std::string_view text) {
  ListenAddress l;
  if (text.starts_with("unix:")) {
    l.unix_socket = true;
    l.path = std::string(text.substr(5));
    if (l.path.empty() || l.path.size() >= sizeof(sockaddr_un::sun_path)) return std::nullopt;
    return l;
  }
  std::string host;
  unsigned short port = 0;
  if (!split_host_port(std::string(text), host, port)) return std::nullopt;
  if (host == "localhost") host = "127.0.0.1";
  unsigned char a[16];
  if (::inet_pton(AF_INET, host.c_str(), a) != 1 && ::inet_pton(AF_INET6, host.c_str(), a) != 1) return std::nullopt;
  l.host = host;
  l.port = port;
  return l;
}

}  // namespace gateway::ascii
