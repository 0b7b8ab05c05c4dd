# Installs the build into WORK/prefix (cmake --install), then builds consumer.c against it
# twice, through find_package(dqjulia) (asking for this version: same major version) and through
# pkg-config, and runs both programs.
# -DBUILD=<build tree> -DSOURCE=<this folder> -DWORK=<scratch> -DCC=<C compiler>
# or, instead of BUILD, -DPREFIX=<an install tree made elsewhere> (tests/release: the unpacked archive)
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/../script_support.cmake)  # dqj_run
file(REMOVE_RECURSE "${WORK}")
file(STRINGS "${CMAKE_CURRENT_LIST_DIR}/../../VERSION" version LIMIT_COUNT 1)
if(DEFINED PREFIX)
  set(prefix "${PREFIX}")
else()
  set(prefix "${WORK}/prefix")
  dqj_run(${CMAKE_COMMAND} --install "${BUILD}" --prefix "${prefix}")
endif()

function(check_output what)
  if(NOT out MATCHES "^dqjulia [0-9]+\\.[0-9]+\\.[0-9]+ n=[0-9]+ de=[0-9.]+")
    message(FATAL_ERROR "FAIL: ${what} printed '${out}'")
  endif()
  message(STATUS "ok: ${what}: ${out}")
endfunction()

foreach(file include/dqjulia/dqjulia.h lib/libdqjulia.so lib/cmake/dqjulia/dqjuliaConfig.cmake
             lib/cmake/dqjulia/dqjuliaConfigVersion.cmake lib/pkgconfig/dqjulia.pc)
  if(NOT EXISTS "${prefix}/${file}")
    message(FATAL_ERROR "FAIL: the install has no ${file}")
  endif()
endforeach()

# find_package(dqjulia)
dqj_run(${CMAKE_COMMAND} -S "${SOURCE}" -B "${WORK}/cmake-build" "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_C_COMPILER=${CC}"
        "-DDQJ_WANTED_VERSION=${version}")
dqj_run(${CMAKE_COMMAND} --build "${WORK}/cmake-build")
dqj_run(${CMAKE_COMMAND} -E env "LD_LIBRARY_PATH=${prefix}/lib" "${WORK}/cmake-build/consumer")
check_output("find_package(dqjulia)")

# pkg-config
set(ENV{PKG_CONFIG_PATH} "${prefix}/lib/pkgconfig")
dqj_run(pkg-config --cflags --libs dqjulia)
string(STRIP "${out}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
dqj_run("${CC}" "${SOURCE}/consumer.c" -o "${WORK}/consumer-pc" ${flags})
dqj_run(${CMAKE_COMMAND} -E env "LD_LIBRARY_PATH=${prefix}/lib" "${WORK}/consumer-pc")
check_output("pkg-config dqjulia")
message(STATUS "2 passed, 0 failed")
