# The PDO value history (issue 18): per object three rings of min/max/mean
# buckets (1 s, 10 s, 60 s) under a byte cap, fed with the TPDO values and
# node breaks of the stack's events; GET .../nodes/{node}/history reads it.
# No I/O and no clock: App feeds it samples with their receive time.
add_library(gateway_history STATIC ${CMAKE_CURRENT_LIST_DIR}/value_history.cpp
                                   ${CMAKE_CURRENT_LIST_DIR}/history_metrics.cpp)
target_include_directories(gateway_history PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_history PUBLIC canopen_core gateway_metrics PRIVATE canopen_options)
