# The user documentation (README.md, docs/) against the OpenAPI document the
# gateway serves (gateway/rest/openapi.json), and its links.
canopen_unit_test(docs_tests SOURCES ${U}/docs/*_test.cpp LIBS Boost::json)
if(TARGET docs_tests)
  target_compile_definitions(docs_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
