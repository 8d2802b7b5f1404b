# REST API under /api/v1 (../shared/api-contract.md): routes on the
# HttpServer that answer from the App's state cache and EDS/DCF files or
# pass SDO/NMT requests to App::handle_request.
add_library(gateway_rest STATIC ${CMAKE_CURRENT_LIST_DIR}/rest_api.cpp)
target_include_directories(gateway_rest PUBLIC ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(gateway_rest PUBLIC gateway_app gateway_http gateway_messages
                                   PRIVATE Boost::json canopen_json canopen_options)
