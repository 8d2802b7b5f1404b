canopen_unit_test(pipeline_tests SOURCES ${U}/gateway/pipeline/*_test.cpp LIBS gateway_pipeline)
