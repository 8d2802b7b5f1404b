# The gateway process in-process on the demo network; app_mqtt_test.cpp also
# against a real mosquitto (Paho as the independent subscriber).
if(NOT TARGET PahoMqttCpp::paho-mqttpp3)  # found once per build (app tests use it too)
  find_package(PahoMqttCpp REQUIRED)
endif()
canopen_unit_test(app_tests SOURCES ${U}/app/*_test.cpp LIBS gateway_app PahoMqttCpp::paho-mqttpp3 sparkplug_proto)
