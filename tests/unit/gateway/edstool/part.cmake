# canopen-eds's report lines and dictionary JSON (gateway/edstool).
canopen_unit_test(edstool_tests SOURCES ${U}/gateway/edstool/*_test.cpp LIBS gateway_edstool Boost::json)
if(TARGET edstool_tests)
  target_compile_definitions(edstool_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}"
                                                   CANOPEN_EDS_BIN="$<TARGET_FILE:canopen-eds>")
  add_dependencies(edstool_tests canopen-eds)
endif()
