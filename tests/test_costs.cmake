# Run by ctest in every test directory after its discovered gtest cases are defined
# (TEST_INCLUDE_FILES, tests/CMakeLists.txt). With -j, ctest starts tests in descending COST;
# without a cost it starts them in the order they were defined, and on a clean clone (no
# Testing/Temporary/CTestCostData.txt yet) the longest test, defined halfway down, then ran last:
# CI at 1aa5a19 (host H) spent 479 s in ctest for 830 test-seconds on 2 cores, 313 of them in
# mocap_cli.DynamicStageReportAndCsv started 165 s in. Costs are the seconds of that run; the
# long tests that are not gtest cases (firmware_all, fuzz.ShortCampaignFindsNothing,
# Report.HtmlReplayRendersInChromium, Campaign.SmallCampaign…) get theirs where they are added.
set(_kuavo_test_costs
  mocap_cli.DynamicStageReportAndCsv 313
  mocap_cli.ClosedLoopCheckRepairsWhereTheRobotFalls 46
  mocap_cli.AWindowTooShortForTheDanceIsReportedUnsound 33
  MpcLoop.HorizonExperimentOnCarpetWithAPush 23
  MpcLoop.StandsThirtySeconds 18)
get_cmake_property(_kuavo_vars VARIABLES)
set(_kuavo_defined "")
foreach(_var IN LISTS _kuavo_vars)
  if(_var MATCHES "_tests_TESTS$")
    list(APPEND _kuavo_defined ${${_var}})
  endif()
endforeach()
list(LENGTH _kuavo_test_costs _n)
math(EXPR _last "${_n} - 1")
foreach(_i RANGE 0 ${_last} 2)
  math(EXPR _j "${_i} + 1")
  list(GET _kuavo_test_costs ${_i} _name)
  list(GET _kuavo_test_costs ${_j} _cost)
  list(FIND _kuavo_defined ${_name} _at)  # ctest scripts run without CMP0057's if(IN_LIST)
  if(_at GREATER -1)
    set_tests_properties(${_name} PROPERTIES COST ${_cost})
  endif()
endforeach()
