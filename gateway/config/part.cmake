find_package(yaml-cpp REQUIRED)
add_library(gateway_config STATIC ${CMAKE_CURRENT_LIST_DIR}/config.cpp ${CMAKE_CURRENT_LIST_DIR}/state_dirs.cpp)
target_include_directories(gateway_config PUBLIC ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(gateway_config PUBLIC gateway_lib PRIVATE gateway_mqtt_codec yaml-cpp canopen_options)
