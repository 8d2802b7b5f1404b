# Sparkplug B edge node without a broker: payloads checked with the
# generated protobuf parser (an implementation independent of the writer),
# the datatype mapping, the bdSeq store on a temp dir, the session state
# machine on a fake clock.
canopen_unit_test(sparkplug_tests SOURCES ${U}/sparkplug/*_test.cpp LIBS gateway_sparkplug sparkplug_proto)
