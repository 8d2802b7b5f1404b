# CiA 309-3 ASCII interface (contract "CiA 309-3 ASCII interface").
# gateway_ascii_codec: the sans-I/O language (line framing, the parser, values
# and answers as CANopenNode's gateway writes them); the fuzz build links only this.
add_library(gateway_ascii_codec STATIC ${CMAKE_CURRENT_LIST_DIR}/ascii_command.cpp ${CMAKE_CURRENT_LIST_DIR}/ascii_values.cpp
                                       ${CMAKE_CURRENT_LIST_DIR}/ascii_parse.cpp ${CMAKE_CURRENT_LIST_DIR}/ascii_answer.cpp
                                       ${CMAKE_CURRENT_LIST_DIR}/ascii_listen.cpp)
target_link_libraries(gateway_ascii_codec PUBLIC gateway_lib canopen_core canopen_lss PRIVATE canopen_options)
# The server on the io_context: TCP or unix socket, requests through the request core.
add_library(gateway_ascii STATIC ${CMAKE_CURRENT_LIST_DIR}/ascii_server.cpp ${CMAKE_CURRENT_LIST_DIR}/ascii_lss.cpp)
target_link_libraries(gateway_ascii PUBLIC gateway_ascii_codec gateway_core_types Boost::headers
                                    PRIVATE gateway_core canopen_json canopen_options)
