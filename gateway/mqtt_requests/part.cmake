# The MQTT request front end (mqtt_requests.hpp): request PUBLISHes decoded
# once into core::Request, results encoded as replies. It sees the request
# core's types and the MQTT codec only; the publisher's session carries it
# (the composition root, app/front_ends.hpp, hands it to the App).
add_library(gateway_mqtt_requests STATIC ${CMAKE_CURRENT_LIST_DIR}/mqtt_requests.cpp)
target_include_directories(gateway_mqtt_requests PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_mqtt_requests
  PUBLIC gateway_core_types gateway_mqtt_codec gateway_messages gateway_lib Boost::json
  PRIVATE canopen_json canopen_options)
