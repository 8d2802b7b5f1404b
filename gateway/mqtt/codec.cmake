# The MQTT codec alone (no I/O, no dependencies): part of gateway_mqtt, and
# the library of the fuzz target (built without the rest of the gateway).
# Topic filters (topic_filter.hpp) too: the config checks mqtt.reply-topics.
add_library(gateway_mqtt_codec STATIC ${CMAKE_CURRENT_LIST_DIR}/mqtt_codec.cpp ${CMAKE_CURRENT_LIST_DIR}/mqtt_encode.cpp
                                      ${CMAKE_CURRENT_LIST_DIR}/mqtt_decode.cpp ${CMAKE_CURRENT_LIST_DIR}/topic_filter.cpp)
target_include_directories(gateway_mqtt_codec PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_mqtt_codec PRIVATE canopen_options)
