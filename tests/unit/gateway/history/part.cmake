# The PDO value history (gateway/history): buckets, breaks, tiers, bounds.
canopen_unit_test(history_tests SOURCES ${U}/gateway/history/*_test.cpp LIBS gateway_history)
