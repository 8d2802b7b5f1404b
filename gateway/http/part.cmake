# HTTP/1.1 + WebSocket server (REST routes, /api/v1/events, dashboard files).
# Beast is instantiated in the server's session files only (connection.cpp,
# http_session.cpp, ws_client.cpp, websocket_session.cpp); the rest stays
# light to compile.
find_package(OpenSSL REQUIRED)
# Without Beast: request/response types, router, Host/Origin/framing checks,
# WebSocket filter, static files (the fuzz build links only this).
add_library(gateway_http_core STATIC
  ${CMAKE_CURRENT_LIST_DIR}/http_types.cpp
  ${CMAKE_CURRENT_LIST_DIR}/router.cpp
  ${CMAKE_CURRENT_LIST_DIR}/request_checks.cpp
  ${CMAKE_CURRENT_LIST_DIR}/event_stream.cpp
  ${CMAKE_CURRENT_LIST_DIR}/static_files.cpp)
target_include_directories(gateway_http_core PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_http_core PUBLIC gateway_lib Boost::headers PRIVATE gateway_core_types gateway_json_wire Boost::json canopen_options)
# The server (HttpServer, http_server.hpp); its internal headers
# (server_impl.hpp, beast_types.hpp, connection.hpp, http_session.hpp,
# ws_client.hpp, websocket_session.hpp) are for these files only.
set(GATEWAY_HTTP_BEAST_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/connection.cpp
  ${CMAKE_CURRENT_LIST_DIR}/http_session.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ws_client.cpp
  ${CMAKE_CURRENT_LIST_DIR}/websocket_session.cpp)
add_library(gateway_http STATIC
  ${CMAKE_CURRENT_LIST_DIR}/http_server.cpp
  ${CMAKE_CURRENT_LIST_DIR}/listener.cpp
  ${GATEWAY_HTTP_BEAST_SOURCES}
  ${CMAKE_CURRENT_LIST_DIR}/http_metrics.cpp)
target_link_libraries(gateway_http
  PUBLIC gateway_http_core gateway_lib gateway_metrics Boost::headers
  PRIVATE Boost::json Boost::url OpenSSL::SSL OpenSSL::Crypto Threads::Threads canopen_options)
# Beast at -O2 with full debug info peaked at ~3.2 GB of compiler memory and
# ~110 s CPU for the former single server.cpp; line tables only (-g1) cut
# that to ~2.1 GB and ~75 s, which matters on 2-core CI runners. Debug/ASan
# builds keep full -g.
set_source_files_properties(${GATEWAY_HTTP_BEAST_SOURCES}
  PROPERTIES COMPILE_OPTIONS "$<$<CONFIG:RelWithDebInfo>:-g1>")
