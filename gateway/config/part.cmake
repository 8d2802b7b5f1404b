find_package(yaml-cpp REQUIRED)
# config.cpp: the file's top level and the gateway's own keys; one *_yaml.cpp
# per component's section (config_yaml.hpp, internal); merge.cpp: the command
# line over it; state_dirs.cpp: the start-up check of the directories.
add_library(gateway_config STATIC
  ${CMAKE_CURRENT_LIST_DIR}/config.cpp
  ${CMAKE_CURRENT_LIST_DIR}/networks_yaml.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mqtt_yaml.cpp
  ${CMAKE_CURRENT_LIST_DIR}/http_yaml.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sparkplug_yaml.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ascii_yaml.cpp
  ${CMAKE_CURRENT_LIST_DIR}/merge.cpp
  ${CMAKE_CURRENT_LIST_DIR}/state_dirs.cpp)
target_include_directories(gateway_config PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
# gateway_mqtt_codec: topic filters (mqtt.reply-topics); gateway_http_core: the Host/origin syntax
# (request_checks.hpp) for http.host-names and allowed-origins; gateway_messages: object
# indexes as the API writes them (parse_index_text) for sparkplug-metrics.
target_link_libraries(gateway_config PUBLIC gateway_lib canopen_lss Boost::json PRIVATE gateway_ascii_codec gateway_mqtt_codec gateway_messages yaml-cpp gateway_http_core canopen_options)
