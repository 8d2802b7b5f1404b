canopen_unit_test(app_tests SOURCES ${U}/app/*_test.cpp LIBS gateway_app)
