# Included by CTest after the discovered firmware tests (TEST_INCLUDE_FILES keeps the order).
# --timing runs in real time: under `ctest -j2` a neighbour test can starve its control task long
# enough for the sensor-staleness watchdog to latch (CI at 4f0a775: a fault after 1045 of 1750
# ticks), so it runs alone. Its figures are timing figures, not the machine's load.
set_tests_properties(KuavoFw.TimingRunsTheWholeMotionThroughTheTaskBodies PROPERTIES RUN_SERIAL TRUE)
