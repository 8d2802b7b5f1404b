find_package(OpenSSL REQUIRED)
canopen_unit_test(http_tests SOURCES ${U}/gateway/http/*_test.cpp
  LIBS gateway_http Boost::json Boost::url OpenSSL::SSL OpenSSL::Crypto Threads::Threads)
# The Beast clients make this TU as heavy as the server's (see gateway/http/part.cmake).
set_source_files_properties(${U}/gateway/http/server_test.cpp
  PROPERTIES COMPILE_OPTIONS "$<$<CONFIG:RelWithDebInfo>:-g1>")
