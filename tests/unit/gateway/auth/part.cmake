# Tokens, roles, rate limit; the security matrix over real HTTP against the
# whole gateway on the simulated demo network.
canopen_unit_test(auth_tests SOURCES ${U}/gateway/auth/*_test.cpp LIBS gateway_process gateway_rest gateway_auth Boost::json Threads::Threads)
