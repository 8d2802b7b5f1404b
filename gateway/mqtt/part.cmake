# MQTT transport: a crash-safe disk queue and the Paho-based publisher that
# also takes requests (see mqtt/publisher.hpp).
find_package(PahoMqttCpp REQUIRED)
add_library(gateway_mqtt STATIC
  ${CMAKE_CURRENT_LIST_DIR}/disk_queue.cpp
  ${CMAKE_CURRENT_LIST_DIR}/publisher.cpp)
target_include_directories(gateway_mqtt PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_mqtt
  PUBLIC gateway_lib PahoMqttCpp::paho-mqttpp3 Boost::json
  PRIVATE canopen_options)
