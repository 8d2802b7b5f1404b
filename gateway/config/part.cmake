find_package(yaml-cpp REQUIRED)
add_library(gateway_config STATIC ${CMAKE_CURRENT_LIST_DIR}/config.cpp ${CMAKE_CURRENT_LIST_DIR}/state_dirs.cpp)
target_include_directories(gateway_config PUBLIC ${CMAKE_CURRENT_LIST_DIR})
# gateway_mqtt_codec: topic filters (mqtt.reply-topics); gateway_http_core: the Host/origin syntax
# (request_checks.hpp) for http.host-names and allowed-origins; gateway_messages: object
# indexes as the API writes them (parse_index_text) for sparkplug-metrics.
target_link_libraries(gateway_config PUBLIC gateway_lib canopen_lss Boost::json PRIVATE gateway_ascii_codec gateway_mqtt_codec gateway_messages yaml-cpp gateway_http_core canopen_options)
