// The bus trace and capture routes (../shared/api-contract.md, "Bus trace
// and capture"; role viewer), answered from each network's frame tap
// (trace/network_trace.hpp):
//
//   GET /api/v1/networks/{net}/trace    WebSocket: one JSON message per frame
//                                       received or sent (trace/trace_stream.hpp),
//                                       filter {"ids": [[from, to], ...]},
//                                       {"lost": N} after frames a slow client lost;
//                                       at most kMaxTraceClients per network (503)
//   GET /api/v1/networks/{net}/capture  ?last=S (from the ring) or ?seconds=S (the
//                                       next S seconds, streamed as the frames
//                                       come, up to kMaxCaptureSeconds),
//                                       &format=pcapng (default) | candump
//
// Thread safety: io_context thread, as the server and the status view.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/json/object.hpp>
#include <cstddef>
#include <cstdint>

#include "trace/network_trace.hpp"
#include "http/http_server.hpp"
#include "status/view.hpp"

namespace gateway {

inline constexpr std::size_t kMaxTraceClients = 8;
// capture?seconds=: the longest live capture, and what of it may wait for a
// client that does not read before frames are dropped (and counted).
inline constexpr std::uint32_t kMaxCaptureSeconds = 3600;
inline constexpr std::size_t kCaptureStreamBuffer = 1u << 20;

// Adds the two routes; live captures time themselves on `io`. `status` and
// `io` MUST outlive the server's use of them; trace sessions that outlive
// the gateway find its networks gone and end quietly.
void register_trace_routes(http::HttpServer& server, const status::View& status, boost::asio::io_context& io);

// GET /api/v1/networks/{net}'s "busLoad": {"percent1s", "percent10s",
// "bitrate"}, the percents rounded to 0.1 and null with "reason" when no
// bit rate is configured; and "capture": the ring's settings and content.
boost::json::object bus_load_json(const trace::NetworkTrace& tap);
boost::json::object capture_json(const trace::NetworkTrace& tap);

}  // namespace gateway
