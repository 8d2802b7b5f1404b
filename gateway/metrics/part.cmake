add_library(gateway_metrics STATIC ${CMAKE_CURRENT_LIST_DIR}/metrics.cpp ${CMAKE_CURRENT_LIST_DIR}/registry.cpp)
target_include_directories(gateway_metrics PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_metrics PRIVATE canopen_options)
