# MQTT transport: a crash-safe disk queue with a memory tier in front
# (outbound_queue), a stall detector, a sans-I/O MQTT 3.1.1/5 codec and
# session (session.hpp), a TCP/TLS connection on Boost.Asio, the MQTT
# client both the publisher and the Sparkplug edge node run on (client.hpp),
# the publisher (queue, storage, flow), which hands the requests it
# receives to the request front end (mqtt_requests/) and sends its replies
# (reply_sender.hpp). It knows nothing of the request core.
find_package(OpenSSL REQUIRED)
include(${CMAKE_CURRENT_LIST_DIR}/codec.cmake)
# The client alone (session, connection, reconnect): what the Sparkplug
# edge node needs, without the publisher's queue and storage.
add_library(gateway_mqtt_client STATIC
  ${CMAKE_CURRENT_LIST_DIR}/session.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mqtt_connection.cpp
  ${CMAKE_CURRENT_LIST_DIR}/client.cpp)
target_include_directories(gateway_mqtt_client PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_mqtt_client
  PUBLIC gateway_lib gateway_mqtt_codec OpenSSL::SSL OpenSSL::Crypto
  PRIVATE canopen_options)
add_library(gateway_mqtt STATIC
  ${CMAKE_CURRENT_LIST_DIR}/disk_queue.cpp
  ${CMAKE_CURRENT_LIST_DIR}/disk_queue_replay.cpp
  ${CMAKE_CURRENT_LIST_DIR}/outbound_queue.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stall_detector.cpp
  ${CMAKE_CURRENT_LIST_DIR}/publisher.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mqtt_metrics.cpp)
target_include_directories(gateway_mqtt PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_mqtt
  PUBLIC gateway_mqtt_client gateway_lib gateway_mqtt_codec gateway_messages gateway_metrics Boost::json OpenSSL::SSL OpenSSL::Crypto
  PRIVATE canopen_options)
