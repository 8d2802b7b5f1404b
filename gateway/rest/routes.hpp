// The REST route handlers by resource, for the route table in rest_api.cpp
// (internal to rest/). Each handler is given the request core (requests)
// and the read-only status view (listings), nothing else of the gateway.
//
// Thread safety: handlers run on the io_context thread of the server.
#pragma once

#include "core/request_core.hpp"
#include "http/http_server.hpp"
#include "status/view.hpp"

namespace gateway::rest {

// What every handler is given. Both MUST outlive the server's use of the routes.
struct Context {
  core::RequestCore& core;
  const status::View& status;
};

// status_routes.cpp: the listings, answered from the status view.
void get_gateway(const Context& ctx, const http::Request& req, http::Responder respond);
void get_network(const Context& ctx, const http::Request& req, http::Responder respond);
void get_nodes(const Context& ctx, const http::Request& req, http::Responder respond);
void get_node(const Context& ctx, const http::Request& req, http::Responder respond);
void get_od(const Context& ctx, const http::Request& req, http::Responder respond);
void get_emcy(const Context& ctx, const http::Request& req, http::Responder respond);

// command_routes.cpp: SDO (JSON or protobuf), NMT, RPDO and SYNC through the core.
void sdo(const Context& ctx, bool write, const http::Request& req, http::Responder respond);
void nmt(const Context& ctx, const http::Request& req, http::Responder respond);
void rpdo(const Context& ctx, const http::Request& req, http::Responder respond);
void sync(const Context& ctx, const http::Request& req, http::Responder respond);

// pdo_routes.cpp: the PDO configuration in effect (issue 11) and its read-back.
void get_pdo(const Context& ctx, const http::Request& req, http::Responder respond);
void read_pdo(const Context& ctx, const http::Request& req, http::Responder respond);

// lss_routes.cpp: LSS (CiA 305, role admin).
void lss_fastscan(const Context& ctx, const http::Request& req, http::Responder respond);
void lss_configure(const Context& ctx, const http::Request& req, http::Responder respond);
void lss_assign_all(const Context& ctx, const http::Request& req, http::Responder respond);
void lss_devices(const Context& ctx, const http::Request& req, http::Responder respond);

// config_routes.cpp: run-time node configuration (issue 17 item 1).
void get_node_config(const Context& ctx, const http::Request& req, http::Responder respond);
void put_node_config(const Context& ctx, const http::Request& req, http::Responder respond);
void delete_node_config(const Context& ctx, const http::Request& req, http::Responder respond);
void put_node_eds(const Context& ctx, const http::Request& req, http::Responder respond);

// maintenance_routes.cpp: PUT .../eds, DCF read-back and apply, store/restore
// and program download, with the route options they need.
void register_maintenance_routes(http::HttpServer& server, const Context& ctx);

}  // namespace gateway::rest
