# The request core against a fake core::Networks (no App, no bus): range
# checks, roles, audit, per-caller limits, metrics; the command roles and
# the number formatting.
canopen_unit_test(core_tests SOURCES ${U}/gateway/core/*_test.cpp LIBS gateway_core gateway_messages)
