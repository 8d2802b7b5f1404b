# Tokens, roles, rate limit and the HTTP authorizer (auth.hpp).
find_package(OpenSSL REQUIRED)
add_library(gateway_auth STATIC ${CMAKE_CURRENT_LIST_DIR}/auth.cpp)
target_include_directories(gateway_auth PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_auth PUBLIC gateway_lib gateway_http_core gateway_core_types PRIVATE OpenSSL::Crypto canopen_options)
