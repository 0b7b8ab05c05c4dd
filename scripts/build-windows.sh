#!/usr/bin/env bash
# Cross-builds dqjulia for Windows x64 with MinGW-w64 (cmake/toolchains/mingw-w64-x86_64.cmake)
# into build-windows/: bin/dqjulia.dll, bin/dqjulia.exe, the Blender extension in dist/
# (dqjulia_blender-windows-x64.zip) and the Windows tests' programs (`ctest --test-dir build-windows`,
# under Wine, against the Linux build in build/, which scripts/build.sh makes). Builds the static
# third-party libraries for Windows first if they are not cached yet
# (scripts/build-deps.sh --target windows-x64, about 6 minutes once).
#
#   scripts/build-windows.sh [BUILD_DIR [CMAKE_OPTION...]]   another build folder and configure
#                                                            options (scripts/release.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build-windows}
shift $(($# > 0 ? 1 : 0))
deps=$(scripts/build-deps.sh --target windows-x64)
source scripts/ccache.sh  # compiler cache, if installed: a second build of the same sources is quick
cmake -S . -B "$dir" -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/mingw-w64-x86_64.cmake -DDQJ_DEPS_PREFIX="$deps" \
  -DCMAKE_BUILD_TYPE=Release -DDQJ_LINUX_BUILD="$PWD/build" "${DQJ_LAUNCHER[@]}" "$@" >/dev/null
cmake --build "$dir" -j"$(nproc)"
