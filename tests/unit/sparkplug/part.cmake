# Sparkplug B edge node without a broker: payloads checked with the
# generated protobuf parser (an implementation independent of the writer),
# the datatype mapping, the bdSeq store on a temp dir, the session state
# machine on a fake clock, a node as a device (device_model: its commands
# checked with the REST/core RPDO body reader; the public EDS corpus).
canopen_unit_test(sparkplug_tests SOURCES ${U}/sparkplug/*_test.cpp LIBS gateway_sparkplug sparkplug_proto gateway_rest_parse)
if(TARGET sparkplug_tests)
  target_compile_definitions(sparkplug_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
