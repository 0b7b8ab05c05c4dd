# What the CMake test scripts (cmake -P) share:
#
# dqj_skip_or_fail(REASON): the one rule for a tool a test needs but this machine lacks
#   (POV-Ray, Blender, a bpy wheel's venv, xvfb-run, glslangValidator): the test is skipped,
#   saying why (it prints DQJ_TEST_SKIPPED, which every such test has as its
#   SKIP_REGULAR_EXPRESSION), except in CI (CI=true), where scripts/install-deps.sh and
#   scripts/bpy-env.sh have installed every tool and a missing one fails the test.
#     cmake -DREASON="reason" -P script_support.cmake   (a test standing in for one not built)
#
# dqj_run(COMMAND...): runs a command; fails the test with its output if it exits non-zero,
#   else sets `out` (its standard output) in the caller.
function(dqj_skip_or_fail reason)
  if("$ENV{CI}" STREQUAL "true")
    message(FATAL_ERROR "${reason} (CI=true: every test must run)")
  endif()
  message("DQJ_TEST_SKIPPED: ${reason}")
endfunction()

function(dqj_run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "FAIL (exit ${status}): ${ARGN}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

if(CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE AND DEFINED REASON)
  dqj_skip_or_fail("${REASON}")
endif()
