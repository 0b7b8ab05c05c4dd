# The Linux archive as tests/cleanroom/archive_test.py takes it, made from this build until the
# release's own (scripts/release.sh: dist/<version>/dqjulia-<version>-linux-x64.tar.gz) is made by
# the test command: `cmake --install` into one top folder, tarred.
#   cmake -DBUILD=<build tree> -DNAME=dqjulia-<version>-linux-x64 -DOUT=<folder> -P install_archive.cmake
file(REMOVE_RECURSE ${OUT}/${NAME} ${OUT}/${NAME}.tar.gz)
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${OUT}/${NAME} OUTPUT_QUIET
                RESULT_VARIABLE failed)
if(failed)
  message(FATAL_ERROR "cmake --install ${BUILD} failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E tar czf ${NAME}.tar.gz ${NAME} WORKING_DIRECTORY ${OUT}
                RESULT_VARIABLE failed)
if(failed)
  message(FATAL_ERROR "tarring ${OUT}/${NAME} failed")
endif()
file(REMOVE_RECURSE ${OUT}/${NAME})
message(STATUS "${OUT}/${NAME}.tar.gz")
