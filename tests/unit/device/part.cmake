# canopen::Device: the slave side of CiA 301 as one unit, and the master
# (canopen::Network) against it over the in-memory bus.
canopen_unit_test(device_tests SOURCES ${U}/device/device_test.cpp ${U}/device/master_and_device_test.cpp
                  LIBS canopen_device canopen_network)
# The simulator (gateway/sim) on an AsioMemoryBus against a Network.
canopen_unit_test(sim_tests SOURCES ${U}/device/simulator_test.cpp LIBS gateway_sim canopen_network)
foreach(t device_tests sim_tests)
  if(TARGET ${t})
    target_compile_definitions(${t} PRIVATE CANOPEN_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
  endif()
endforeach()
