// The REST API under /api/v1 (../shared/api-contract.md) as routes on the
// HttpServer, answered by the App:
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
//   POST /api/v1/networks/{net}/sync                     one SYNC, optionally {"counter": n}
//
// Errors are application/problem+json (400 malformed, 404 unknown network /
// node EDS / object / RPDO, 422 SDO abort, 503 bus-off or down, 504 SDO
// timeout). Protobuf: SDO and NMT requests take `Content-Type:
// application/x-protobuf` bodies, and SDO replies (and their problems) are
// binary protobuf with `Accept: application/x-protobuf`; NMT replies are
// protobuf when the request was. The listings (gateway, network, nodes,
// node, od, emcy), RPDO and SYNC answer JSON only.
//
// Thread safety: handlers run on the io_context thread of server and app.
#pragma once

#include "app.hpp"
#include "http_server.hpp"

namespace gateway {

// Adds the routes above. `app` must outlive the server's use of them.
void register_rest_routes(http::HttpServer& server, App& app);

}  // namespace gateway
