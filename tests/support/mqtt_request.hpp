// Test helper: a request as the MQTT unit decodes it (mqtt_requests.hpp)
// from canopen/<gw>/<net>/<node>/sdo/read|sdo/write|nmt and a JSON body, for
// tests that hand requests to the request core without a broker.
#pragma once

#include <cstdint>
#include <string>

#include "mqtt_requests/mqtt_requests.hpp"

namespace test {

inline gateway::mqtt::DecodedRequest mqtt_request(gateway::core::Operation op, std::uint32_t net, std::uint8_t node,
                                                  const std::string& body, const std::string& token = {},
                                                  const std::string& gateway_id = "test") {
  using gateway::core::Operation;
  const std::string topic = "canopen/" + gateway_id + "/" + std::to_string(net) + "/" + std::to_string(node) + "/" +
                            (op == Operation::sdo_read    ? "sdo/read"
                             : op == Operation::sdo_write ? "sdo/write"
                                                          : "nmt");
  gateway::mqtt::codec::Publish msg;
  msg.topic = topic;
  msg.payload = body;
  gateway::mqtt::codec::UserProperty auth{"authorization", token};
  if (!token.empty()) msg.props.user.push_back(auth);
  return gateway::mqtt::decode_request(msg, gateway_id);  // copies what it keeps
}

}  // namespace test
