add_library(gateway_pipeline STATIC ${CMAKE_CURRENT_LIST_DIR}/pipeline.cpp ${CMAKE_CURRENT_LIST_DIR}/state_cache.cpp
                                    ${CMAKE_CURRENT_LIST_DIR}/pipeline_metrics.cpp)
target_include_directories(gateway_pipeline PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_pipeline PUBLIC gateway_lib canopen_network gateway_metrics PRIVATE canopen_options)
