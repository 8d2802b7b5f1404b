// Internal to the HTTP server (not installed): the HTTP session of an
// accepted connection (HttpSession, http_session.cpp).
#pragma once

#include <memory>
#include <string>

#include "http/server_impl.hpp"

namespace gateway::http {

// Serves `socket` (accepted from `peer`, holding `slot`): over TLS when the
// server has a TLS context, else plain TCP.
void start_http_session(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, tcp::socket socket, std::string peer);

}  // namespace gateway::http
