// The REST API under /api/v1 (../shared/api-contract.md) as routes on the
// HttpServer: requests go to the request core (core/request_core.hpp), the
// listings read the status view (status/view.hpp); nothing else of the
// gateway is reachable from a route:
//
//   GET  /api/v1/gateway                                 version, uptime, node-ID, networks
//   GET  /api/v1/networks/{net}                          bus state, counters, SYNC/TIME settings
//   GET  /api/v1/networks/{net}/nodes                    every known node (state cache)
//   GET  /api/v1/networks/{net}/nodes/{node}             one node with its latest TPDO values
//   GET  /api/v1/networks/{net}/nodes/{node}/sdo/{i}/{s} SDO upload (?type= overrides the EDS)
//   PUT  /api/v1/networks/{net}/nodes/{node}/sdo/{i}/{s} SDO download {"value":..,"type":..}
//   POST /api/v1/networks/{net}/nodes/{node}/nmt         {"command": ...}; node 0 = all
//   GET  /api/v1/networks/{net}/nodes/{node}/od          the node's EDS/DCF dictionary
//   GET  /api/v1/networks/{net}/nodes/{node}/emcy        recent EMCYs, newest first
//   PUT  /api/v1/networks/{net}/nodes/{node}/rpdo/{n}    {"values":[{index,subIndex,value}]} or {"raw":"hex"}
//   GET  /api/v1/networks/{net}/nodes/{node}/pdo         the node's PDO configuration in effect and its source
//   POST /api/v1/networks/{net}/nodes/{node}/pdo/read    read it from the device by SDO, then as GET
//   POST /api/v1/networks/{net}/sync                     one SYNC, optionally {"counter": n}
//   POST /api/v1/networks/{net}/lss/fastscan             LSS (CiA 305, role admin): find one unconfigured device
//   POST /api/v1/networks/{net}/lss/configure            {"identity", "nodeId", "bitrate"?, "store"}
//   POST /api/v1/networks/{net}/lss/assign-all           {"firstNodeId", "store"}: every unconfigured device
//   GET  /api/v1/networks/{net}/lss/devices              what the last scan found
//   GET  /api/v1/networks/{net}/nodes/{node}/dcf         DCF read-back (text/plain node<N>.dcf; JSON with Accept)
//   POST /api/v1/networks/{net}/nodes/{node}/dcf         DCF apply (octet-stream body, ?store=&reset=; or JSON)
//   POST /api/v1/networks/{net}/nodes/{node}/store       1010h sub 1 "save" (operator)
//   POST /api/v1/networks/{net}/nodes/{node}/restore     1011h sub 1 "load", then NMT reset node (operator)
//   PUT  /api/v1/networks/{net}/nodes/{node}/program/{n} CiA 302-3 program download (octet-stream image,
//                                                         up to http.max-program-bytes); answers when it runs
//
// Errors are application/problem+json (400 malformed, 404 unknown network /
// node EDS / object / RPDO or no unconfigured device (LSS fastscan), 409
// another LSS operation runs (or another DCF transfer, store/restore or
// program download for the node), 413 a body over the route's limit, 422 SDO abort or LSS slave error, 503 bus-off
// or down, 504 SDO or LSS timeout). Protobuf: SDO and NMT requests take `Content-Type:
// application/x-protobuf` bodies, and SDO replies (and their problems) are
// binary protobuf with `Accept: application/x-protobuf`; NMT replies are
// protobuf when the request was. The listings (gateway, network, nodes,
// node, od, emcy, pdo), RPDO, PDO read, SYNC and LSS answer JSON only.
//
// The same routes, /metrics and /api/v1/openapi.json are described in
// gateway/rest/openapi.json (built into the binary, served as is).
//
// Thread safety: handlers run on the io_context thread of the server, the
// core and the status view.
#pragma once

#include <string_view>

#include <boost/asio/io_context.hpp>

#include "core/request_core.hpp"
#include "http/http_server.hpp"
#include "status/view.hpp"

namespace gateway {

// Adds the routes above. `core` and `status` MUST outlive the server's use of them.
void register_rest_routes(http::HttpServer& server, core::RequestCore& core, const status::View& status);

// GET /metrics: status.metrics_text(). The server's families and the uptime
// are the composition's to register (app/front_ends.hpp). `status` MUST
// outlive the server's use of the route.
void register_metrics_route(http::HttpServer& server, const status::View& status);
// GET /api/v1/openapi.json: openapi_document() as application/json.
void register_openapi_route(http::HttpServer& server);

// Every route of the gateway's API: the REST routes above, the trace and
// history routes, /metrics and /api/v1/openapi.json. (/api/v1/events is the
// server's own WebSocket path; "/" and the dashboard's files are its static
// directory.) `io` is the one everything runs on (timers of live captures).
// All three MUST outlive the server's use of the routes.
void register_api_routes(http::HttpServer& server, core::RequestCore& core, const status::View& status,
                         boost::asio::io_context& io);

// The OpenAPI 3.0 document of the API (gateway/rest/openapi.json).
std::string_view openapi_document();

}  // namespace gateway
