// problem+json (RFC 9457), the JSON form of a core::Problem: a wire codec,
// so it lives with the codecs, not in the core.
//
// Pure function; thread-safe.
#pragma once

#include <string>
#include <string_view>

#include "core/request.hpp"

namespace gateway {

// The problem+json document of `p` (RFC 9457): type ("about:blank" unless
// given), title (the status' reason phrase unless given), status, detail,
// abortCode ("0x06020000") when set, correlationId when not empty; text
// that is not UTF-8 is read as Latin-1. The one JSON problem builder: REST,
// MQTT and the HTTP server's own errors (http::Response::problem) use it;
// the protobuf Problem (request_codec.hpp) has the same fields.
std::string problem_json(const core::Problem& p, std::string_view correlation_id = {});

}  // namespace gateway
