# Runs one Blender test script with fresh user folders under USER, in a virtual X display when
# XVFB_RUN is given. Fails if Blender exits non-zero.
#   -DBLENDER= -DUSER= -DSCRIPT= "-DBLENDER_ARGS=a;b" "-DSCRIPT_ARGS=a;b" [-DXVFB_RUN=]
#   -DPYTHON= -DBPY_VERSION= -DUSER= -DSCRIPT= "-DSCRIPT_ARGS=a;b"
# The second form runs the script in a bpy wheel's venv (scripts/bpy-env.sh): `import bpy`
# is Blender. If that venv is missing the test fails saying why when CI=true, and is skipped
# otherwise (it prints DQJ_TEST_SKIPPED, the test's SKIP_REGULAR_EXPRESSION).
# BLENDER_USER_RESOURCES (4.2+: every user folder), CONFIG, SCRIPTS, DATAFILES and EXTENSIONS
# (4.2+) all point into USER, never at the real user's folders.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/blender_env.cmake)
dqj_blender_require_venv()
dqj_blender_user_folders("${USER}")
if(PYTHON)
  set(command "${PYTHON}" "${SCRIPT}" -- ${SCRIPT_ARGS})
else()
  set(command "${BLENDER}" ${BLENDER_ARGS} --python "${SCRIPT}" -- ${SCRIPT_ARGS})
endif()
if(XVFB_RUN)
  set(command "${XVFB_RUN}" -a -s "-screen 0 1280x800x24" ${command})
endif()
execute_process(COMMAND ${command} RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "Blender test ${SCRIPT} failed (exit ${result})")
endif()
