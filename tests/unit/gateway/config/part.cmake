canopen_unit_test(config_tests SOURCES ${U}/gateway/config/*_test.cpp LIBS gateway_config)
if(TARGET config_tests)
  target_compile_definitions(config_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
