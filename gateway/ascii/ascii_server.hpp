// The CiA 309-3 ASCII server (contract "CiA 309-3 ASCII interface"): TCP
// (loopback unless allowed otherwise) or a unix socket, many clients at
// once. Each connection has its own defaults (`set network`, `set node`,
// `set sdo_timeout`, `set sdo_block`) and runs its commands one after the
// other, so its answers come in the order of its requests; other clients
// are not held up by it. SDO and NMT commands are decoded once into a
// core::Request (transport ascii, the configured role, one caller key per
// connection) and executed by the request core: the same SDO queue per
// node, roles, limits and audit as REST and MQTT.
//
// Limits: a line longer than max_line is answered ERROR:600 and the rest of
// it discarded; at most max_clients connections (more are closed at once);
// a connection idle (nothing read or written, no command running) for
// idle_timeout (checked every eighth of it) is closed; output is bounded: a large value read is printed
// piece by piece while the client takes it, and a client that stops
// reading is no longer read from (its commands wait), and is closed when
// its output has not moved for idle_timeout. Others are served meanwhile.
//
// LSS commands (lss_*, _lss_fastscan, lss_allnodes) are parsed here and
// handed to the LSS handler; without one they are answered ERROR:100
// (request not supported).
//
// Thread safety: one io thread. Construct, start(), stop() and the setters
// on it (or before it runs). The handler runs on it and MUST call its reply
// exactly once, at once or later, on the io thread.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include <boost/asio/io_context.hpp>

#include "ascii/ascii_command.hpp"
#include "core/request.hpp"
#include "role.hpp"

namespace gateway {
class Logger;
}

namespace gateway::core {
class RequestCore;
}

namespace gateway::ascii {

struct ServerConfig {
  // "unix:/path" (removed and created again at start, mode 0660) or an IP
  // literal and port ("127.0.0.1:60000", "[::1]:60000"; port 0: any free one).
  std::string listen = "127.0.0.1:60000";
  Role role = Role::Operator;  // what every client may do (no authentication on the socket)
  std::chrono::milliseconds idle_timeout{std::chrono::minutes(5)};  // 0 = none
  std::size_t max_clients = 16;
  std::size_t max_line = 64 * 1024;     // bytes per command line, its end excluded
  std::size_t max_output = 256 * 1024;  // buffered answer bytes per client before it is no longer read
  std::uint32_t networks = 1;           // the gateway's networks are 1..networks
};

// An LSS command for the handler: the network it is for (1..networks),
// its sequence number and who asked (for roles and the audit log).
struct LssRequest {
  std::uint32_t network = 1;
  std::uint32_t seq = 0;
  core::Caller caller;
  LssCommand command;
};
// The whole answer text, lines ended as CiA 309-3 says (build it with the
// response functions of ascii_command.hpp: ok_response, error_response,
// lss_identity_response, lss_assigned_line ...).
using LssReply = std::function<void(std::string text)>;
using LssHandler = std::function<void(const LssRequest&, LssReply)>;

class Server {
 public:
  // `core` MUST outlive the server (and the requests it started).
  Server(boost::asio::io_context& io, ServerConfig config, core::RequestCore& core, Logger* log = nullptr);
  ~Server();  // stop()
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Opens the listener. Throws std::system_error (address in use, a unix
  // path that cannot be created ...) or std::invalid_argument (a malformed
  // listen address).
  void start();
  // Closes the listener and every connection (a unix socket file is removed).
  void stop();

  void set_lss_handler(LssHandler handler);

  // Where it listens: "127.0.0.1:40123" (the bound port) or "unix:/path".
  std::string local_address() const;
  std::uint16_t bound_port() const;  // 0 for a unix socket
  std::size_t clients() const;
  // The most answer bytes one connection holds now (waiting for its client
  // to read them): at most about max_output plus one piece of an answer.
  std::size_t buffered_output() const;

  struct Impl;  // internal (the connections refer to it)

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace gateway::ascii
