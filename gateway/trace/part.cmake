# The bus trace (issue 18): the frame tap of each network, CiA 301 decoding
# of frames, bus load, the capture ring and its pcapng/candump writers, the
# trace WebSocket's filter and queue. No I/O: NetworkUnit feeds it frames
# and time; the HTTP routes read it.
add_library(gateway_trace STATIC
  ${CMAKE_CURRENT_LIST_DIR}/frame_decode.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bus_load.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capture.cpp
  ${CMAKE_CURRENT_LIST_DIR}/trace_stream.cpp
  ${CMAKE_CURRENT_LIST_DIR}/network_trace.cpp
  ${CMAKE_CURRENT_LIST_DIR}/tapped_channel.cpp)
target_include_directories(gateway_trace PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_trace PUBLIC canopen_core canopen_lss gateway_core_types gateway_json_wire
                                    PRIVATE Boost::json canopen_options)
