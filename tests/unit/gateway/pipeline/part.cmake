canopen_unit_test(pipeline_tests SOURCES ${U}/pipeline/*_test.cpp LIBS gateway_pipeline)
