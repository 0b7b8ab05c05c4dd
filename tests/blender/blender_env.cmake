# Included by run_blender.cmake and blender_test.cmake: the environment of one Blender run.
#   dqj_blender_venv_present()      with -DPYTHON (a bpy wheel's venv): FALSE, after skipping or
#                                   failing by tests/missing_tool.cmake's rule, if the venv is missing
#   dqj_blender_user_folders(DIR)   fresh BLENDER_USER_RESOURCES (4.2+: every user folder), CONFIG,
#                                   SCRIPTS, DATAFILES and EXTENSIONS (4.2+) under DIR, never the
#                                   real user's folders
include(${CMAKE_CURRENT_LIST_DIR}/../missing_tool.cmake)

function(dqj_blender_venv_present result)
  set(${result} TRUE PARENT_SCOPE)
  if(PYTHON AND NOT EXISTS "${PYTHON}")
    dqj_skip_or_fail("the bpy ${BPY_VERSION} venv is missing (${PYTHON}): run scripts/bpy-env.sh ${BPY_VERSION}")
    set(${result} FALSE PARENT_SCOPE)
  endif()
endfunction()

function(dqj_blender_user_folders dir)
  file(REMOVE_RECURSE "${dir}")
  foreach(kind RESOURCES CONFIG SCRIPTS DATAFILES EXTENSIONS)
    string(TOLOWER "${kind}" folder)
    file(MAKE_DIRECTORY "${dir}/${folder}")
    set(ENV{BLENDER_USER_${kind}} "${dir}/${folder}")
  endforeach()
endfunction()
