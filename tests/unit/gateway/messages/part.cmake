# Unit tests of gateway/messages (event encoding, request/reply bodies).
if(TARGET gateway_messages)
  canopen_unit_test(messages_tests SOURCES ${U}/gateway/messages/*_test.cpp LIBS gateway_messages)
endif()
