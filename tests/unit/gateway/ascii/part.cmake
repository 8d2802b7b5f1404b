# The CiA 309-3 ASCII interface: the language without I/O, and the server
# over real sockets (TCP on 127.0.0.1, a unix socket) against the whole
# gateway on the simulated demo network.
canopen_unit_test(ascii_tests SOURCES ${U}/gateway/ascii/*_test.cpp LIBS gateway_ascii gateway_app Threads::Threads)
