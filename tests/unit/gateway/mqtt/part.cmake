# MQTT: DiskQueue unit tests and publisher tests against a real mosquitto
# started by the fixture (skipped when /usr/sbin/mosquitto is missing), and
# the MQTT codec's unit tests. Paho is the independent reference client of
# the tests (subscribers, requesters); the gateway does not use it.
if(NOT TARGET PahoMqttCpp::paho-mqttpp3)  # found once per build (app tests use it too)
  find_package(PahoMqttCpp REQUIRED)
endif()
# publisher_test.cpp: requests through the publisher to the request front end.
canopen_unit_test(mqtt_tests SOURCES ${U}/gateway/mqtt/*_test.cpp LIBS gateway_mqtt gateway_mqtt_requests PahoMqttCpp::paho-mqttpp3)
if(TARGET mqtt_tests)
  add_executable(mqtt_publish_tool ${U}/gateway/mqtt/mqtt_publish_tool.cpp)
  target_link_libraries(mqtt_publish_tool PRIVATE gateway_mqtt canopen_options)
  target_compile_definitions(mqtt_tests PRIVATE
    MQTT_PUBLISH_TOOL="$<TARGET_FILE:mqtt_publish_tool>")
  add_dependencies(mqtt_tests mqtt_publish_tool)
endif()
