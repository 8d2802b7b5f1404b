# Simulated CANopen nodes (canopen::Device per EDS on a channel) and an
# in-process CAN bus on Asio, for canopen-gateway --demo and tests; the
# canopen-sim executable runs nodes on a SocketCAN interface.
add_library(gateway_sim STATIC
  ${CMAKE_CURRENT_LIST_DIR}/asio_memory_bus.cpp
  ${CMAKE_CURRENT_LIST_DIR}/device_objects.cpp
  ${CMAKE_CURRENT_LIST_DIR}/simulator.cpp)
target_include_directories(gateway_sim PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_sim PUBLIC canopen_device canopen_eds canopen_lss canopen_socketcan PRIVATE canopen_options)

add_executable(canopen-sim ${CMAKE_CURRENT_LIST_DIR}/sim_main.cpp)
target_link_libraries(canopen-sim PRIVATE gateway_sim canopen_options)
