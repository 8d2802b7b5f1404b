# CAN frame -> MQTT publish through the whole gateway path; its own main().
add_executable(mqtt_path_bench ${CMAKE_CURRENT_LIST_DIR}/mqtt_path.cpp)
target_link_libraries(mqtt_path_bench PRIVATE gateway_pipeline gateway_messages gateway_mqtt canopen_network
                                              canopen_eds canopen_options)
target_compile_definitions(mqtt_path_bench PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
# Smoke run (untimed) so it keeps working: 2,000 events against a real mosquitto.
add_test(NAME bench.mqtt_compare COMMAND ${CMAKE_CURRENT_LIST_DIR}/mqtt_compare.sh ${CMAKE_BINARY_DIR} 2000 1)
set_tests_properties(bench.mqtt_compare PROPERTIES LABELS bench TIMEOUT 120)
