// canopen::Value <-> google.protobuf.Value with json_value.hpp's shapes
// (internal to gateway_messages). Pure functions, thread-safe.
#pragma once

#include <boost/json/value.hpp>

#include "canopen/types.hpp"
#include "canopen_gateway.pb.h"

namespace gateway::detail {

// Precondition: holds_its_type(v).
void set_proto_value(google::protobuf::Value& out, const canopen::Value& v);
// The JSON the Value stands for; a struct or list becomes an empty object or
// array (no typed value has that shape, so value_from_json rejects it).
boost::json::value proto_value_to_json(const google::protobuf::Value& v);

}  // namespace gateway::detail
