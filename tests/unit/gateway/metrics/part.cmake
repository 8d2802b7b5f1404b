canopen_unit_test(metrics_tests SOURCES ${U}/gateway/metrics/*_test.cpp LIBS gateway_metrics)
