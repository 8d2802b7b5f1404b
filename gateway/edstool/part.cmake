# canopen-eds (check / show): the gateway's EDS/DCF acceptance rules as a
# command users run before they deploy; its report and dictionary JSON are
# shared with the REST /od route.
add_library(gateway_edstool STATIC ${CMAKE_CURRENT_LIST_DIR}/eds_report.cpp)
target_include_directories(gateway_edstool PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${CMAKE_CURRENT_LIST_DIR}/..)
# gateway_lib: printable() (log.hpp) for the lines that quote the files.
target_link_libraries(gateway_edstool PUBLIC canopen_eds Boost::json PRIVATE canopen_json gateway_lib gateway_core_types canopen_options)

add_executable(canopen-eds ${CMAKE_CURRENT_LIST_DIR}/canopen_eds_main.cpp)
target_link_libraries(canopen-eds PRIVATE gateway_edstool canopen_options)
