# The typed request core (core/request.hpp, core/request_core.hpp): every
# front end (REST, MQTT, ...) decodes into a core::Request and encodes the
# core::Result; range checks, roles, limits, audit and request metrics
# happen here once. core/format.hpp: the one way to write object addresses
# and hex.
# gateway_core_types: the vocabulary and formatting, no state; the codecs
# (messages), auth and the transports use it without the core itself.
add_library(gateway_core_types STATIC ${CMAKE_CURRENT_LIST_DIR}/request.cpp ${CMAKE_CURRENT_LIST_DIR}/format.cpp
                                       ${CMAKE_CURRENT_LIST_DIR}/rpdo_values.cpp)
target_include_directories(gateway_core_types PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
# role.hpp is header-only in gateway/ (the include root above): the core
# links the stack and auth/, nothing else of the gateway (issue 26).
target_link_libraries(gateway_core_types PUBLIC canopen_pdo canopen_od canopen_lss PRIVATE canopen_options)

add_library(gateway_core STATIC ${CMAKE_CURRENT_LIST_DIR}/request_core.cpp ${CMAKE_CURRENT_LIST_DIR}/lss_requests.cpp
                                 ${CMAKE_CURRENT_LIST_DIR}/maintenance.cpp
                                 ${CMAKE_CURRENT_LIST_DIR}/node_config.cpp)
target_link_libraries(gateway_core PUBLIC gateway_core_types gateway_auth canopen_network canopen_eds
                                   PRIVATE canopen_options)
