# Runs one Blender test script with fresh user folders (BLENDER_USER_CONFIG/SCRIPTS/DATAFILES
# under USER), in a virtual X display when XVFB_RUN is given. Fails if Blender exits non-zero.
#   -DBLENDER= -DUSER= -DSCRIPT= "-DBLENDER_ARGS=a;b" "-DSCRIPT_ARGS=a;b" [-DXVFB_RUN=]
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${USER}")
foreach(kind CONFIG SCRIPTS DATAFILES)
  string(TOLOWER "${kind}" folder)
  file(MAKE_DIRECTORY "${USER}/${folder}")
  set(ENV{BLENDER_USER_${kind}} "${USER}/${folder}")
endforeach()
set(command "${BLENDER}" ${BLENDER_ARGS} --python "${SCRIPT}" -- ${SCRIPT_ARGS})
if(XVFB_RUN)
  set(command "${XVFB_RUN}" -a -s "-screen 0 1280x800x24" ${command})
endif()
execute_process(COMMAND ${command} RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "Blender test ${SCRIPT} failed (exit ${result})")
endif()
