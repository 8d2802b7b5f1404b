# The front ends' read-only status view of the running gateway (view.hpp),
# implemented by the App (app/app_status.*): rest/ depends on this, not on app/.
add_library(gateway_status INTERFACE)
target_include_directories(gateway_status INTERFACE ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_status INTERFACE gateway_config gateway_core gateway_pipeline gateway_history gateway_trace
                                               canopen_eds canopen_od canopen_pdo)
