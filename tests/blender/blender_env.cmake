# Included by run_blender.cmake and blender_test.cmake: the environment of one Blender run.
#   dqj_blender_require_venv()      with -DPYTHON (a bpy wheel's venv) that is missing: skips or
#                                   fails by tests/script_support.cmake's rule and ends the calling
#                                   script (a macro, so its return() is the caller's)
#   dqj_blender_user_folders(DIR)   fresh BLENDER_USER_RESOURCES (4.2+: every user folder), CONFIG,
#                                   SCRIPTS, DATAFILES and EXTENSIONS (4.2+) under DIR, never the
#                                   real user's folders
include(${CMAKE_CURRENT_LIST_DIR}/../script_support.cmake)

macro(dqj_blender_require_venv)
  if(PYTHON AND NOT EXISTS "${PYTHON}")
    dqj_skip_or_fail("the bpy ${BPY_VERSION} venv is missing (${PYTHON}): run scripts/bpy-env.sh ${BPY_VERSION}")
    return()
  endif()
endmacro()

function(dqj_blender_user_folders dir)
  file(REMOVE_RECURSE "${dir}")
  foreach(kind RESOURCES CONFIG SCRIPTS DATAFILES EXTENSIONS)
    string(TOLOWER "${kind}" folder)
    file(MAKE_DIRECTORY "${dir}/${folder}")
    set(ENV{BLENDER_USER_${kind}} "${dir}/${folder}")
  endforeach()
endfunction()
