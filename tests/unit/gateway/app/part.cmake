# The gateway process in-process on the demo network (the App and the front
# ends the composition root makes, app/front_ends.hpp); app_mqtt_test.cpp also
# against a real mosquitto (Paho as the independent subscriber).
if(NOT TARGET PahoMqttCpp::paho-mqttpp3)  # found once per build (app tests use it too)
  find_package(PahoMqttCpp REQUIRED)
endif()
canopen_unit_test(app_tests SOURCES ${U}/gateway/app/*_test.cpp LIBS gateway_process PahoMqttCpp::paho-mqttpp3 sparkplug_proto)
if(TARGET app_tests)  # app_node_config_test.cpp uploads deploy/eds/ files
  target_compile_definitions(app_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}" CANOPEN_GATEWAY_VERSION="${PROJECT_VERSION}")
endif()
