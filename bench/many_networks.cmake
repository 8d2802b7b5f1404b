# 16 CAN networks at full 1 Mbit/s load through the whole gateway path to
# MQTT QoS 0 (bench/README.md, "16 networks"); its own main().
add_executable(many_networks_bench ${CMAKE_CURRENT_LIST_DIR}/many_networks.cpp)
target_link_libraries(many_networks_bench PRIVATE gateway_pipeline gateway_messages gateway_mqtt canopen_network
                                                  canopen_eds canopen_options)
target_compile_definitions(many_networks_bench PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
# Smoke run (untimed) so it keeps working: 2 s against a real mosquitto.
add_test(NAME bench.many_networks COMMAND ${CMAKE_CURRENT_LIST_DIR}/many_networks.sh ${CMAKE_BINARY_DIR} 2)
set_tests_properties(bench.many_networks PROPERTIES LABELS bench TIMEOUT 120)
