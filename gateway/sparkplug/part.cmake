# Sparkplug B edge node, sans-I/O (sparkplug/edge_session.hpp): the
# payload writer and command decoder (payload.hpp, proto/sparkplug_b.proto),
# the session state machine and the bdSeq kept in state-dir; the CANopen
# side of it: a node as a device, its metrics and commands (device_model.hpp).
# The MQTT connection and the events are wired in by the application.
add_library(gateway_sparkplug STATIC
  ${CMAKE_CURRENT_LIST_DIR}/payload.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bdseq_store.cpp
  ${CMAKE_CURRENT_LIST_DIR}/edge_session.cpp
  ${CMAKE_CURRENT_LIST_DIR}/device_model.cpp)
target_include_directories(gateway_sparkplug PUBLIC ${CMAKE_CURRENT_LIST_DIR}/..)
target_link_libraries(gateway_sparkplug PUBLIC canopen_core gateway_core_types canopen_pdo canopen_eds
                                        PRIVATE gateway_lib sparkplug_proto Boost::json canopen_json canopen_options)
# The edge node on the network (edge_client.hpp): the EdgeSession run over
# its own MQTT client (mqtt/client.hpp, gateway_mqtt_client; not the
# publisher's queue and storage). A library of its own so gateway_sparkplug
# stays sans-I/O (no Asio, no sockets) and its tests need no broker.
add_library(gateway_sparkplug_client STATIC ${CMAKE_CURRENT_LIST_DIR}/edge_client.cpp)
target_link_libraries(gateway_sparkplug_client PUBLIC gateway_sparkplug gateway_mqtt_client gateway_metrics gateway_lib
                                               PRIVATE canopen_options)
# The Sparkplug B front end as the composition root makes it (edge_node.hpp):
# the EdgeClient and the CANopen side (sparkplug_output.hpp: stack events to
# births and data, NCMD/DCMD to request-core commands), given the request
# core and the status view only.
add_library(gateway_sparkplug_node STATIC ${CMAKE_CURRENT_LIST_DIR}/sparkplug_output.cpp
                                          ${CMAKE_CURRENT_LIST_DIR}/edge_node.cpp)
target_link_libraries(gateway_sparkplug_node PUBLIC gateway_sparkplug_client gateway_core gateway_status gateway_pipeline
                                             PRIVATE canopen_options)
