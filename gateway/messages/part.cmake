# JSON a front end reads or writes that needs no protobuf: problem+json
# (RFC 9457) of a core::Problem, and the one-object client messages
# (WebSocket filters). The core itself writes no wire format.
add_library(gateway_json_wire STATIC ${CMAKE_CURRENT_LIST_DIR}/problem_json.cpp ${CMAKE_CURRENT_LIST_DIR}/json_input.cpp)
target_include_directories(gateway_json_wire PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_json_wire PUBLIC gateway_core_types gateway_lib Boost::json PRIVATE canopen_options)

# Stack events -> MQTT/WebSocket messages, and request/reply bodies
# (proto/canopen_gateway.proto). Links the generated code as a separate
# library so its headers are SYSTEM and not held to our warnings.
if(TARGET canopen_proto)
  add_library(gateway_messages STATIC
    ${CMAKE_CURRENT_LIST_DIR}/event_encoder.cpp
    ${CMAKE_CURRENT_LIST_DIR}/request_codec.cpp
    ${CMAKE_CURRENT_LIST_DIR}/json_text.cpp
    ${CMAKE_CURRENT_LIST_DIR}/proto_value.cpp)
  target_include_directories(gateway_messages PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
  target_link_libraries(gateway_messages PUBLIC canopen_proto canopen_json gateway_lib gateway_core_types gateway_json_wire PRIVATE canopen_options)
endif()
