// Internal to the HTTP server (not installed): the WebSocket session an HTTP
// connection becomes (WsSession, websocket_session.cpp), one per stream type.
#pragma once

#include <memory>
#include <string>

#include "http/beast_types.hpp"
#include "http/http_server.hpp"
#include "http/server_impl.hpp"

namespace gateway::http {

// Takes over `stream` for the upgrade request `req` (it passed every check):
// the handshake, then the event stream, or `source` when not null.
void start_websocket_session(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, beast::tcp_stream&& stream,
                             bool binary, std::string peer, BeastRequest&& req, std::shared_ptr<StreamSource> source);
void start_websocket_session(std::shared_ptr<HttpServer::Impl> impl, SlotPtr slot, TlsStream&& stream, bool binary,
                             std::string peer, BeastRequest&& req, std::shared_ptr<StreamSource> source);

}  // namespace gateway::http
