# The simulated devices' objects (gateway/sim/device_objects), sans-I/O.
canopen_unit_test(sim_object_tests SOURCES ${U}/gateway/sim/*_test.cpp EXCLUDE ${U}/gateway/sim/simulator_test.cpp
                  LIBS gateway_sim canopen_device)
# The simulator (gateway/sim) on an AsioMemoryBus against a Network.
canopen_unit_test(sim_tests SOURCES ${U}/gateway/sim/simulator_test.cpp LIBS gateway_sim canopen_network)
foreach(t sim_object_tests sim_tests)
  if(TARGET ${t})
    target_compile_definitions(${t} PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
  endif()
endforeach()
