#!/usr/bin/env bash
# Builds the static third-party libraries if they are not cached yet, then configures and
# builds dqjulia (Release) into build/.
#
#   scripts/build.sh [BUILD_DIR [CMAKE_OPTION...]]     another build folder and configure options
#                                                      (scripts/release.sh: build-release/linux)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build}
shift $(($# > 0 ? 1 : 0))
deps=$(scripts/build-deps.sh)  # static OpenVDB, TBB, OpenEXR, ... (cached; about 8 minutes once)
source scripts/ccache.sh    # compiler cache, if installed: a second build of the same sources is quick
cmake -S . -B "$dir" -DDQJ_DEPS_PREFIX="$deps" -DCMAKE_BUILD_TYPE=Release "${DQJ_LAUNCHER[@]}" "$@" >/dev/null
cmake --build "$dir" -j"$(nproc)"
