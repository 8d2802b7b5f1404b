# REST API under /api/v1 (../shared/api-contract.md): routes on the
# HttpServer that answer from the status view (status/view.hpp: state
# cache, EDS/DCF files, ...) or decode SDO, NMT, RPDO, SYNC, LSS,
# configuration and maintenance requests for the request core
# (core/request_core.hpp); /metrics; the OpenAPI document (openapi.json,
# built into the binary). It does not link the App (gateway_app): the
# composition (app/front_ends.*) hands it the core and the view.

# Request decoding that needs no App (path numbers, RPDO body): its own
# library so the fuzz build links it without the server and the App.
add_library(gateway_rest_parse STATIC ${CMAKE_CURRENT_LIST_DIR}/rest_parse.cpp)
target_include_directories(gateway_rest_parse PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_rest_parse PUBLIC canopen_pdo canopen_od gateway_messages gateway_core_types
                                         PRIVATE Boost::json canopen_json canopen_options)

file(READ ${CMAKE_CURRENT_LIST_DIR}/openapi.json GATEWAY_OPENAPI_JSON)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${CMAKE_CURRENT_LIST_DIR}/openapi.json)
configure_file(${CMAKE_CURRENT_LIST_DIR}/openapi_document.cpp.in ${CMAKE_CURRENT_BINARY_DIR}/openapi_document.cpp @ONLY)
# One literal of ~170 KB: over the 65,536 characters the standard asks
# compilers to support, which GCC and Clang both handle; Clang's -Wpedantic says so.
set_source_files_properties(${CMAKE_CURRENT_BINARY_DIR}/openapi_document.cpp
  PROPERTIES COMPILE_OPTIONS "$<$<CXX_COMPILER_ID:Clang>:-Wno-overlength-strings>")

add_library(gateway_rest STATIC
  ${CMAKE_CURRENT_LIST_DIR}/rest_api.cpp
  ${CMAKE_CURRENT_LIST_DIR}/status_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/command_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pdo_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/lss_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/config_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/maintenance_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/route_checks.cpp
  ${CMAKE_CURRENT_LIST_DIR}/api_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/trace_routes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/history_routes.cpp
  ${CMAKE_CURRENT_BINARY_DIR}/openapi_document.cpp)
target_include_directories(gateway_rest PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_rest PUBLIC gateway_status gateway_core gateway_http gateway_messages gateway_edstool
                                   PRIVATE gateway_rest_parse gateway_metrics gateway_trace Boost::json canopen_json canopen_options)
