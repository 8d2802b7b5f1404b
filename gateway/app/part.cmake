# The process minus main(): networks, own device, pipeline, outputs.
file(READ ${CMAKE_SOURCE_DIR}/deploy/eds/cia402-drive.eds DEMO_DRIVE_EDS)
file(READ ${CMAKE_SOURCE_DIR}/deploy/eds/cia401-io-module.eds DEMO_IO_EDS)
configure_file(${CMAKE_CURRENT_LIST_DIR}/demo_devices.cpp.in ${CMAKE_CURRENT_BINARY_DIR}/demo_devices.cpp @ONLY)
add_library(gateway_app STATIC ${CMAKE_CURRENT_LIST_DIR}/app.cpp ${CMAKE_CURRENT_LIST_DIR}/seq_store.cpp
                               ${CMAKE_CURRENT_LIST_DIR}/network_unit.cpp ${CMAKE_CURRENT_LIST_DIR}/composition.cpp
                               ${CMAKE_CURRENT_LIST_DIR}/mqtt_output.cpp
                               ${CMAKE_CURRENT_LIST_DIR}/node_overlay.cpp ${CMAKE_CURRENT_LIST_DIR}/node_config.cpp
                               ${CMAKE_CURRENT_LIST_DIR}/core_networks.cpp ${CMAKE_CURRENT_LIST_DIR}/app_status.cpp
                               ${CMAKE_CURRENT_LIST_DIR}/core_metrics.cpp
                               ${CMAKE_CURRENT_BINARY_DIR}/demo_devices.cpp)
target_include_directories(gateway_app PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
target_compile_definitions(gateway_app PRIVATE CANOPEN_GATEWAY_VERSION="${PROJECT_VERSION}")
target_link_libraries(gateway_app PUBLIC gateway_status gateway_config gateway_auth gateway_core gateway_pipeline gateway_messages gateway_mqtt gateway_mqtt_requests gateway_sim
                                         gateway_trace gateway_history gateway_metrics
                                         canopen_device canopen_local_node canopen_network canopen_socketcan canopen_eds
                                  PRIVATE canopen_options)

# The composition of the front ends (front_ends.*: HTTP/REST, the WebSocket
# event stream, MQTT requests, the Sparkplug B edge node, ASCII, each from the
# App's request core and status view) and
# the process minus its command line (process.*: run_gateway()).
add_library(gateway_process STATIC ${CMAKE_CURRENT_LIST_DIR}/front_ends.cpp ${CMAKE_CURRENT_LIST_DIR}/process.cpp)
target_compile_definitions(gateway_process PRIVATE CANOPEN_SOURCE_WEB_DIR="${PROJECT_SOURCE_DIR}/web")
target_link_libraries(gateway_process PUBLIC gateway_app gateway_rest gateway_http gateway_ascii gateway_sparkplug_node gateway_lib
                                      PRIVATE gateway_metrics canopen_socketcan canopen_options)
