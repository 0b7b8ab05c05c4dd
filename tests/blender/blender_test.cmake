# One Blender test: makes a file with the real dqjulia, then checks it in the real Blender.
#   cmake -DCLI=dqjulia -DBLENDER=blender -DSCRIPTS=tests/blender -DWORK=folder -DEXAMPLES=examples
#         -DMODE=vdb|sequence|ply|obj -P blender_test.cmake
#   ... -DPYTHON=VENV/bin/python -DBPY_VERSION=4.5.15 ...: check in a bpy wheel's venv instead
#   (skipped, or failing when CI=true, if the venv is missing: tests/script_support.cmake's rule).
# The dqjulia run uses small resolutions so the whole check takes seconds.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/blender_env.cmake)
dqj_blender_require_venv()
file(REMOVE_RECURSE "${WORK}")
dqj_blender_user_folders("${WORK}/user")

if(PYTHON)
  set(blender ${PYTHON})
else()
  set(blender ${BLENDER} -b --factory-startup --python-exit-code 1 --python)
endif()
if(MODE STREQUAL "vdb")
  dqj_run(${CLI} bake -q -r 32 --grids surface,density,color,trap,iterations -o ${WORK}/fractal.vdb)
  dqj_run(${blender} ${SCRIPTS}/check_vdb.py -- ${WORK}/fractal.vdb surface,density,color,trap,iterations)
elseif(MODE STREQUAL "sequence")
  dqj_run(${CLI} bake -q -r 24 -p ${EXAMPLES}/animation.json --frames 1-3 -o ${WORK}/seq.vdb)
  dqj_run(${blender} ${SCRIPTS}/check_vdb.py -- --sequence ${WORK}/seq_0001.vdb 3 surface,density)
else()
  dqj_run(${CLI} mesh -q -r 32 --stats -o ${WORK}/fractal.${MODE})
  string(REGEX MATCH "vertices ([0-9]+)" _ "${out}")
  set(vertices ${CMAKE_MATCH_1})
  string(REGEX MATCH "faces ([0-9]+)" _ "${out}")
  set(faces ${CMAKE_MATCH_1})
  if(NOT vertices OR NOT faces)
    message(FATAL_ERROR "dqjulia mesh --stats printed no counts:\n${out}")
  endif()
  dqj_run(${blender} ${SCRIPTS}/check_mesh.py -- ${WORK}/fractal.${MODE} ${vertices} ${faces})
endif()
message(STATUS "${out}")
file(REMOVE_RECURSE "${WORK}")
