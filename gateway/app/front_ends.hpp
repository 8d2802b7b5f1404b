// Where the front ends are made: each from the App's request core
// (App::requests()) and its read-only status view (App::status(),
// status/view.hpp), the same way for HTTP/REST, the WebSocket event stream,
// the MQTT requests, the Sparkplug B edge node and the CiA 309-3 ASCII server. The process (process.cpp) builds them
// here; tests and benchmarks that serve the API call the same functions,
// so they get what canopen-gateway serves.
//
// Thread safety: call on the App's io_context thread, before the App and the
// servers start.
#pragma once

#include <memory>

#include <boost/asio/io_context.hpp>

#include "app/app.hpp"
#include "ascii/ascii_server.hpp"
#include "http/http_server.hpp"
#include "log.hpp"

namespace gateway::sparkplug {
class EdgeNode;
}

namespace gateway {

// The HTTP API on `server`: the App's authorizer (App::http_authorizer()),
// the server's /metrics families and the uptime (after the App's own), and
// every route of rest/ (register_api_routes()). Call once per App and
// server; `app` MUST outlive the server's use of them.
void install_http_api(http::HttpServer& server, App& app);

// The WebSocket event stream (/api/v1/events): every event the App encodes
// goes to the server's clients, and PDO events are encoded as protobuf too
// while one of them wants it. `server` MUST outlive the App's events.
void connect_event_stream(http::HttpServer& server, App& app);

// The MQTT request front end (mqtt_requests/) on the App's MQTT session:
// requests on canopen/<gw>/+/+/{sdo/read,sdo/write,nmt} go to the request
// core, replies to their reply address. Call before app.start(); nothing
// with MQTT off. `app` and `log` MUST outlive the App's MQTT output.
void serve_mqtt_requests(App& app, Logger& log);

// The Sparkplug B edge node (config sparkplug:, contract "Sparkplug B";
// sparkplug/edge_node.hpp) on its own MQTT session, fed the App's stack
// events as a StackOutput (started and stopped by the App), its NCMD/DCMD
// writes and DBIRTH reads through the request core; its /metrics families
// and its GET /api/v1/gateway status. Call before app.start(); nothing
// (nullptr) unless sparkplug.enabled. Throws std::invalid_argument for ids
// or a URI the EdgeClient refuses. The App owns what it returns.
sparkplug::EdgeNode* add_sparkplug(boost::asio::io_context& io, App& app, Logger& log);

// The ASCII server (config ascii:, not started) on the request core, its
// lss_* through the core's LSS commands (role admin). `app` MUST outlive it.
std::unique_ptr<ascii::Server> make_ascii_server(boost::asio::io_context& io, App& app, Logger& log);

}  // namespace gateway
