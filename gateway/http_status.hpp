// Reason phrases of the HTTP status codes the gateway answers with; used
// for HTTP responses and as the title of problem documents (REST and MQTT
// replies alike). Thread-safe.
#pragma once

#include <string_view>

namespace gateway {

// "Not Found" for 404; "Unknown" for a code not in the table.
std::string_view reason_phrase(int status);

}  // namespace gateway
