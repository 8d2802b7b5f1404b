# REST routes against the whole gateway on the simulated demo network, over
# real HTTP on 127.0.0.1 (a small raw-socket client, no Beast).
canopen_unit_test(rest_tests SOURCES ${U}/gateway/rest/*_test.cpp EXCLUDE ${U}/gateway/rest/api_reference_test.cpp
                  LIBS gateway_process gateway_rest gateway_trace Boost::json Threads::Threads)
if(TARGET rest_tests)  # node_config_test.cpp uploads deploy/eds/ files; capture tests run tests/tools
  target_compile_definitions(rest_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
# The user documentation (README.md, docs/) against the OpenAPI document the
# gateway serves (gateway/rest/openapi.json), and its links.
canopen_unit_test(docs_tests SOURCES ${U}/gateway/rest/api_reference_test.cpp LIBS Boost::json)
if(TARGET docs_tests)
  target_compile_definitions(docs_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
