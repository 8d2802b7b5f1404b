# The MQTT request front end: topics and bodies decoded into core requests,
# reply addresses, reply bodies, against a fake core.
canopen_unit_test(mqtt_requests_tests SOURCES ${U}/gateway/mqtt_requests/*_test.cpp LIBS gateway_mqtt_requests)
