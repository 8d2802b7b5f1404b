# The simulated devices' objects (gateway/sim/device_objects), sans-I/O.
canopen_unit_test(sim_object_tests SOURCES ${U}/sim/*_test.cpp LIBS gateway_sim canopen_device)
if(TARGET sim_object_tests)
  target_compile_definitions(sim_object_tests PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
endif()
