#!/usr/bin/env bash
# Builds the static third-party libraries if they are not cached yet, then configures and
# builds dqjulia (Release) into build/.
set -euo pipefail
cd "$(dirname "$0")/.."
deps=$(scripts/build-deps.sh)  # static OpenVDB, TBB, OpenEXR, ... (cached; about 8 minutes once)
source scripts/ccache.sh    # compiler cache, if installed: a second build of the same sources is quick
cmake -S . -B build -DDQJ_DEPS_PREFIX="$deps" -DCMAKE_BUILD_TYPE=Release "${DQJ_LAUNCHER[@]}" >/dev/null
cmake --build build -j"$(nproc)"
