#!/usr/bin/env bash
# Builds the static third-party libraries if they are not cached yet, then configures and
# builds dqjulia (Release) into build/.
set -euo pipefail
cd "$(dirname "$0")/.."
deps=$(scripts/build-deps.sh)  # static OpenVDB, TBB, OpenEXR, ... (cached; about 8 minutes once)
cmake -S . -B build -DDQJ_DEPS_PREFIX="$deps" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
