// Small JSON texts a client sends that must be one object (the WebSocket
// filter messages of the event stream and the bus trace): one parse and one
// wording of its two refusals for both.
//
// Thread safety: none needed (pure function).
#pragma once

#include <boost/json/object.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace gateway {

// The object in `text`; otherwise nullopt and `error` is
// "<what> is not valid JSON: <reason>" or "<what> must be a JSON object<shape>"
// (`shape` e.g. ": {\"ids\": [[from, to], ...]}", or empty).
std::optional<boost::json::object> parse_json_object(std::string_view text, std::string_view what,
                                                     std::string_view shape, std::string& error);

}  // namespace gateway
