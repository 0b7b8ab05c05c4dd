# Cross build for Windows x64 with Debian's MinGW-w64 (g++-mingw-w64-x86-64-posix: the posix thread
# model, which std::thread, std::mutex and oneTBB need). scripts/build-deps.sh --target windows-x64
# builds the third-party libraries with it, scripts/build-windows.sh the project:
#
#   cmake -S . -B build-windows -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/mingw-w64-x86_64.cmake \
#         -DDQJ_DEPS_PREFIX=$(scripts/build-deps.sh --target windows-x64 --print)
#
# Libraries, headers and CMake packages are looked up only in the MinGW sysroot and in
# DQJ_DEPS_PREFIX, never among the build machine's own (Linux) ones; programs only on the build
# machine. Windows programs the build or the tests run go through Wine (wine-run.sh beside this
# file) when Debian's wine64 is installed.
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
set(DQJ_MINGW_TRIPLE x86_64-w64-mingw32)
set(CMAKE_C_COMPILER ${DQJ_MINGW_TRIPLE}-gcc-posix)
set(CMAKE_CXX_COMPILER ${DQJ_MINGW_TRIPLE}-g++-posix)
set(CMAKE_RC_COMPILER ${DQJ_MINGW_TRIPLE}-windres)
set(CMAKE_OBJDUMP ${DQJ_MINGW_TRIPLE}-objdump CACHE FILEPATH "objdump for the Windows binaries")

set(CMAKE_FIND_ROOT_PATH /usr/${DQJ_MINGW_TRIPLE} ${DQJ_DEPS_PREFIX})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(CMAKE_TRY_COMPILE_PLATFORM_VARIABLES DQJ_DEPS_PREFIX)

# GCC keeps the Win64 stack 16-byte aligned but spills AVX and AVX-512 registers with aligned
# moves that assume 32 or 64 bytes (GCC bug 54412), which crashes the Highway kernels' AVX2 and
# AVX-512 code paths at random. The assembler turns those moves into unaligned ones (as fast on
# every CPU with AVX).
string(APPEND CMAKE_C_FLAGS_INIT " -Wa,-muse-unaligned-vector-move")
string(APPEND CMAKE_CXX_FLAGS_INIT " -Wa,-muse-unaligned-vector-move")

# Wine runs the Windows programs of tests and build steps (CMake prefixes add_test and
# add_custom_command with it for programs of this build), in a Wine prefix of the build tree.
find_program(DQJ_WINE wine64 PATHS /usr/lib/wine NO_DEFAULT_PATH)
find_program(DQJ_WINE wine64)
if(DQJ_WINE)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${CMAKE_CURRENT_LIST_DIR}/wine-run.sh ${CMAKE_BINARY_DIR}/wine)
endif()
