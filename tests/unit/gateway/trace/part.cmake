canopen_unit_test(trace_tests SOURCES ${U}/gateway/trace/*_test.cpp LIBS gateway_trace Boost::json)
if(TARGET trace_tests)
  target_compile_definitions(trace_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
