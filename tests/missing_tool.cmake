# The one rule for a tool a test needs but this machine lacks (POV-Ray, Blender, a bpy wheel's
# venv, xvfb-run, glslangValidator): the test is skipped, saying why (it prints
# DQJ_TEST_SKIPPED, which every such test has as its SKIP_REGULAR_EXPRESSION), except in CI
# (CI=true), where scripts/install-deps.sh and scripts/bpy-env.sh have installed every tool
# and a missing one fails the test.
#   include(missing_tool.cmake) ... dqj_skip_or_fail("reason") ... return()
#   cmake -DREASON="reason" -P missing_tool.cmake     (a test standing in for one not built)
function(dqj_skip_or_fail reason)
  if("$ENV{CI}" STREQUAL "true")
    message(FATAL_ERROR "${reason} (CI=true: every test must run)")
  endif()
  message("DQJ_TEST_SKIPPED: ${reason}")
endfunction()

if(CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE AND DEFINED REASON)
  dqj_skip_or_fail("${REASON}")
endif()
