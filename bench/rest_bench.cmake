# REST SDO latency through the whole gateway vs. the request core alone (App::requests);
# its own main() (bench/README.md, "REST API").
if(TARGET gateway_rest)
  add_executable(rest_bench ${CMAKE_CURRENT_LIST_DIR}/rest_bench.cpp)
  target_link_libraries(rest_bench PRIVATE gateway_process gateway_rest gateway_app gateway_http canopen_options)
  # Smoke run so it keeps working; the numbers are for people.
  add_test(NAME bench.rest_smoke COMMAND rest_bench 200)
  set_tests_properties(bench.rest_smoke PROPERTIES LABELS bench TIMEOUT 120)
endif()
