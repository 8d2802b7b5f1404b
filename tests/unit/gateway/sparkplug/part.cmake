# Sparkplug B edge node: payloads checked with the generated protobuf parser
# (an implementation independent of the writer), the datatype mapping, the
# bdSeq store on a temp dir, the session state machine on a fake clock, a
# node as a device (device_model: its commands checked with the REST/core
# RPDO body reader; the public EDS corpus) — all without a broker; and the
# EdgeClient against a real mosquitto started by the test (skipped when
# /usr/sbin/mosquitto is missing), Paho as the host.
if(NOT TARGET PahoMqttCpp::paho-mqttpp3)  # found once per build (app tests use it too)
  find_package(PahoMqttCpp REQUIRED)
endif()
canopen_unit_test(sparkplug_tests SOURCES ${U}/gateway/sparkplug/*_test.cpp
                  LIBS gateway_sparkplug gateway_sparkplug_client gateway_sparkplug_node sparkplug_proto gateway_rest_parse PahoMqttCpp::paho-mqttpp3)
if(TARGET sparkplug_tests)
  target_compile_definitions(sparkplug_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
